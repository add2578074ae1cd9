//! `graspmap eval`: a policy (model, random or oracle) picks objects in simulation; per-object
//! tables, Wilson intervals, visualisations and videos (docs/evaluation.md).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;
use image::RgbImage;

mod config;
mod sweep;

use super::attempt::{objects_in_bin, Look};
use super::{workers, Context};
use crate::assets::objects::ObjectModel;
use crate::data::atomic::save_image_atomic;
use crate::data::output::{check_output_dir, check_output_file};
use crate::grasp::draw::draw_grasp;
use crate::grasp::world::world_grasp;
use crate::interrupt;
use crate::model::inference::AffordanceModel;
use crate::named::{counted, Named};
use crate::policy::baselines::{OraclePolicy, RandomPolicy};
use crate::policy::heights::HeightMap;
use crate::policy::model::ModelPolicy;
use crate::policy::push::plan_push;
use crate::policy::suppression::{Suppression, SuppressionConfig};
use crate::policy::Policy;
use crate::policy::PolicyKind;
use crate::present::envelope::write_versioned_report;
use crate::present::eval_report::Task;
use crate::present::eval_report::{
    report_lines, summarise, AttemptRecord, AttemptTiming, BinOutcome, SceneRun,
};
use crate::present::video::save_video_atomic;
use crate::sim::pick::{PickOutcome, PickReason};
use crate::sim::{ObjectLocation, Workcell, WorkcellConfig};
pub(crate) use config::{
    pushes_by_default, EvalConfig, ATTEMPTS_PER_OBJECT, EPISODE_EVERY_STEPS,
    SINGLE_OBJECT_SEED_OFFSET,
};
use sweep::{
    announce_plan, comparable, finished_runs, keep_interrupted, kept_path, resolved_config,
    resume_source,
};

/// Settings shared by every scene of one evaluation, and by the threads that run them.
struct Evaluation<'a> {
    context: &'a Context,
    suppression: SuppressionConfig,
    workcell: WorkcellConfig,
    vis_dir: PathBuf,
    /// Put each seed's visualisations in a seed<S>/ subfolder (several seeds).
    per_seed_vis: bool,
    max_attempts: u32,
    give_up_after: u32,
    push_unverified: bool,
    bar: indicatif::ProgressBar,
    check_invariants: bool,
    /// One scene at a time: print its lines as they happen, not when it ends.
    live_lines: bool,
}

/// What each thread owns: its policy, with its own copy of the network, and with --record
/// the episode's frames.
struct Worker {
    policy: Box<dyn Policy + Send>,
    recording: Option<Vec<RgbImage>>,
}

/// A piece of an evaluation that runs on its own: an empty_bin scene, or one attempt of
/// train/test (each drops its object afresh).
enum Job {
    Scene(u64),
    Attempt { seed: u64, object: usize, try_: u32 },
}

/// A finished [`Job`]: a scene with the lines it printed, or one attempt of a seed.
enum Finished {
    Scene(SceneRun, Vec<String>),
    Attempt(u64, AttemptRecord),
}

/// What an evaluation runs: the seeds of this run (its shard's), the objects and where their
/// visualisations go, and the attempts of a scene at most.
struct Plan {
    seeds: Vec<u64>,
    names: Vec<String>,
    models: Vec<ObjectModel>,
    vis_dir: PathBuf,
    per_scene: u64,
}

/// Runs the command.
pub(crate) fn run(context: &Context, config: EvalConfig) -> anyhow::Result<()> {
    let start = Instant::now();
    let Plan {
        seeds,
        names,
        models,
        vis_dir,
        per_scene,
    } = plan(context, &config)?;
    let mut runs = match config.resume {
        true => resumed(context, &config, &names, seeds.len())?,
        false => Vec::new(),
    };
    let jobs = jobs(&config, &seeds, &runs, models.len());
    // The episode video is one thread's frames, in order.
    let (workers, network_threads) = match config.record {
        Some(_) => (1, context.threads),
        None => workers::plan(context.threads, jobs.len()),
    };
    crate::model::use_threads(network_threads);
    let evaluation = Evaluation {
        context,
        suppression: config.suppression,
        workcell: WorkcellConfig::default(),
        vis_dir,
        // By the whole sweep, so that shards write where the unsharded run would.
        per_seed_vis: config.seeds.len() > 1,
        max_attempts: config.max_attempts,
        give_up_after: config.give_up_after,
        push_unverified: config.push_unverified,
        bar: context.progress_bar(
            "attempts",
            per_scene * seeds.len() as u64,
            per_scene * runs.len() as u64,
        ),
        check_invariants: config.check_invariants,
        live_lines: workers == 1,
    };
    let recording = evaluation.run_jobs(
        &config,
        &jobs,
        &models,
        (workers, network_threads),
        &mut runs,
    )?;
    // Resumed runs come first; a report lists its scenes in the order of --seeds.
    runs.sort_by_key(|r| seeds.iter().position(|&s| s == r.seed));
    evaluation.bar.finish_and_clear();
    let interrupted = interrupt::requested().filter(|_| runs.len() < seeds.len());
    if let Some(interrupted) = interrupted {
        let elapsed = start.elapsed().as_secs_f64();
        return Err(keep_interrupted(
            context,
            &config,
            &names,
            runs,
            elapsed,
            interrupted,
        ));
    }
    let mut video_encode_s = None;
    if let (Some(path), Some(frames)) = (&config.record, &recording) {
        let encoding = Instant::now();
        save_video_atomic(frames, EPISODE_EVERY_STEPS, path)
            .with_context(|| format!("writing --record {}", path.display()))?;
        video_encode_s = Some(encoding.elapsed().as_secs_f64());
        context.say(&format!("wrote the episode video to {}", path.display()));
    }
    let ran = Ran {
        start,
        workers,
        video_encode_s,
    };
    finish(context, &config, &names, runs, ran, &evaluation.vis_dir)
}

/// How a finished evaluation ran, beside its scenes.
struct Ran {
    start: Instant,
    workers: usize,
    /// Seconds spent encoding and writing the --record video.
    video_encode_s: Option<f64>,
}

/// The evaluation's seeds, objects and outputs, each checked before anything runs, and its
/// plan announced.
fn plan(context: &Context, config: &EvalConfig) -> anyhow::Result<Plan> {
    let seeds = config.run_seeds();
    if seeds.is_empty() {
        anyhow::bail!(
            "--shard {} holds none of the {} of --seeds; give at most {} shards",
            config.shard,
            counted(config.seeds.len(), "seed"),
            config.seeds.len()
        );
    }
    // A missing or wrong checkpoint is reported before anything starts; each thread then
    // loads its own copy.
    policy(config)?;
    let split = context.split()?;
    let names: Vec<String> = match config.task {
        Task::Train => split.train.clone(),
        Task::Test => split.test.clone(),
        Task::EmptyBin => split.all(),
    };
    let models = context.objects.load_all(&names)?;
    let vis_dir = context.data.join("affordance").join(match config.task {
        Task::Train => "eval_pick_training_vis",
        Task::Test => "eval_pick_testing_vis",
        Task::EmptyBin => "eval_empty_bin_vis",
    });
    let kept = kept_path(context, config, &names);
    check_output_dir(kept.parent().unwrap_or(&context.data), "the reports folder")?;
    check_output_dir(&vis_dir, "the visualisations folder")?;
    if let Some(record) = &config.record {
        check_output_file(record, "--record")?;
    }
    let per_scene = match config.task {
        Task::EmptyBin => u64::from(config.max_attempts),
        _ => models.len() as u64 * u64::from(ATTEMPTS_PER_OBJECT),
    };
    announce_plan(context, config.task, per_scene, seeds.len());
    Ok(Plan {
        seeds,
        names,
        models,
        vis_dir,
        per_scene,
    })
}

/// `--resume`: the scenes an earlier report of this evaluation finished.
fn resumed(
    context: &Context,
    config: &EvalConfig,
    names: &[String],
    scenes: usize,
) -> anyhow::Result<Vec<SceneRun>> {
    let kept = kept_path(context, config, names);
    let source = resume_source(context, &kept);
    let runs = finished_runs(source, config)?;
    context.say(&format!(
        "resuming: {} of {} already in {}",
        runs.len(),
        counted(scenes, "scene"),
        source.display()
    ));
    Ok(runs)
}

/// The jobs of the seeds not in `runs`: a scene each (empty_bin), or each attempt of each
/// object (train/test).
fn jobs(config: &EvalConfig, seeds: &[u64], runs: &[SceneRun], objects: usize) -> Vec<Job> {
    seeds
        .iter()
        .filter(|&&seed| !runs.iter().any(|r| r.seed == seed))
        .flat_map(|&seed| match config.task {
            Task::EmptyBin => vec![Job::Scene(seed)],
            Task::Train | Task::Test => (0..objects)
                .flat_map(|object| {
                    (0..ATTEMPTS_PER_OBJECT).map(move |try_| Job::Attempt { seed, object, try_ })
                })
                .collect(),
        })
        .collect()
}

/// Summarises a finished evaluation, prints it, and writes its report to --json and to
/// the kept report path.
fn finish(
    context: &Context,
    config: &EvalConfig,
    names: &[String],
    runs: Vec<SceneRun>,
    ran: Ran,
    vis_dir: &Path,
) -> anyhow::Result<()> {
    let drew = runs
        .iter()
        .flat_map(|r| &r.attempts)
        .any(|a| a.vis.is_some());
    let mut results = summarise(
        config.task,
        config.policy,
        config.run_seeds(),
        names,
        runs,
        ran.start.elapsed().as_secs_f64(),
        false,
    );
    results.timing.workers = ran.workers;
    results.video = config.record.clone();
    results.video_encode_s = ran.video_encode_s;
    results.vis_dir = drew.then(|| vis_dir.to_path_buf());
    for line in report_lines(&results, config.suppression.remember) {
        context.say(&line);
    }
    let resolved = resolved_config(context, config, names);
    // The latest finished run of each task and policy stays under DATA, beside the model, for
    // `graspmap report`; --json is the user's own copy, wherever it goes.
    let kept = kept_path(context, config, names);
    let targets = context.json.iter().chain(std::iter::once(&kept));
    for target in targets {
        write_versioned_report(target, "eval", 2, config.seeds[0], &resolved, &results)?;
    }
    let settings = comparable(context, config, names);
    match settings.is_default() {
        true => context.say(&format!("report kept in {}", kept.display())),
        false => context.say(&format!(
            "report kept in {} ({}; beside, never over, the reports of other settings)",
            kept.display(),
            settings.describe()
        )),
    }
    Ok(())
}

/// The policy that chooses the grasps, with its model loaded when it needs one.
fn policy(config: &EvalConfig) -> anyhow::Result<Box<dyn Policy + Send>> {
    Ok(match config.policy {
        PolicyKind::Model => Box::new(ModelPolicy::new(
            AffordanceModel::load(&config.checkpoint, config.precision)?,
            config.model,
        )?),
        PolicyKind::Random => Box::new(RandomPolicy),
        PolicyKind::Oracle => Box::new(OraclePolicy),
    })
}

impl Evaluation<'_> {
    /// Runs `jobs` on `workers` threads of `network_threads` each, adding each finished scene
    /// to `runs` (a train/test seed once all its attempts are in); the episode's frames with
    /// --record.
    fn run_jobs(
        &self,
        config: &EvalConfig,
        jobs: &[Job],
        models: &[ObjectModel],
        (workers, network_threads): (usize, u16),
        runs: &mut Vec<SceneRun>,
    ) -> anyhow::Result<Option<Vec<RgbImage>>> {
        let per_seed = models.len() * ATTEMPTS_PER_OBJECT as usize;
        let mut attempts_of: BTreeMap<u64, Vec<AttemptRecord>> = BTreeMap::new();
        let states = workers::run_in_order(
            jobs,
            workers,
            || {
                crate::model::use_threads(network_threads);
                Ok(Worker {
                    policy: policy(config)?,
                    recording: config.record.as_ref().map(|_| Vec::new()),
                })
            },
            |worker, job| self.run_job(worker, models, job),
            |finished| match finished {
                Finished::Scene(run, lines) => {
                    for line in &lines {
                        self.bar.suspend(|| self.context.say(line));
                    }
                    runs.push(run);
                }
                Finished::Attempt(seed, record) => {
                    let attempts = attempts_of.entry(seed).or_default();
                    attempts.push(record);
                    if attempts.len() == per_seed {
                        runs.push(SceneRun {
                            seed,
                            attempts: std::mem::take(attempts),
                            bin: None,
                        });
                    }
                }
            },
        )?;
        Ok(states.into_iter().next().and_then(|w| w.recording))
    }

    /// Runs one job on a worker's policy; `None` when a signal stopped it.
    fn run_job(
        &self,
        worker: &mut Worker,
        models: &[ObjectModel],
        job: &Job,
    ) -> anyhow::Result<Option<Finished>> {
        if interrupt::requested().is_some() {
            return Ok(None);
        }
        Ok(match *job {
            Job::Scene(seed) => self
                .empty_bin(worker, models, seed)?
                .map(|(run, lines)| Finished::Scene(run, lines)),
            Job::Attempt { seed, object, try_ } => Some(Finished::Attempt(
                seed,
                self.single_object(worker, &models[object], object, seed, try_)?,
            )),
        })
    }

    /// train/test: attempt `a` of object `i`, alone in a fresh drop.
    fn single_object(
        &self,
        worker: &mut Worker,
        model: &ObjectModel,
        i: usize,
        seed: u64,
        a: u32,
    ) -> anyhow::Result<AttemptRecord> {
        let started = Instant::now();
        let drop_seed = seed + 100 * i as u64 + u64::from(a) + SINGLE_OBJECT_SEED_OFFSET;
        let mut cell = self.workcell()?;
        cell.drop_objects(std::slice::from_ref(model), drop_seed)?;
        let drop_seconds = started.elapsed().as_secs_f64();
        // Suppression remembers actions within a scene; each attempt here is a new one.
        let memory = Suppression::new(self.suppression);
        let vis = self.vis_path(seed, &format!("{}_{a}.png", model.name));
        let mut record = self.attempt(worker, &mut cell, &memory, drop_seed, a, vis)?;
        record.object = Some(model.name.clone());
        record.timing.sim += drop_seconds;
        record.timing.wall = started.elapsed().as_secs_f64();
        self.bar.inc(1);
        self.bar.set_message(format!(
            "{} {}",
            model.name,
            if record.success {
                "success"
            } else {
                record.reason.name()
            }
        ));
        Ok(record)
    }

    /// empty_bin: every object in bin 1 at once, picked until the bin is empty or attempts run out.
    /// With the lines it printed, or keeps to print when the scenes before it have printed theirs.
    fn empty_bin(
        &self,
        worker: &mut Worker,
        models: &[ObjectModel],
        seed: u64,
    ) -> anyhow::Result<Option<(SceneRun, Vec<String>)>> {
        let started = Instant::now();
        let mut cell = self.workcell()?;
        cell.drop_objects(models, seed)?;
        let mut setup_seconds = started.elapsed().as_secs_f64();
        let total = models.len();
        let mut memory = Suppression::new(self.suppression);
        let mut attempts: Vec<AttemptRecord> = Vec::new();
        let mut gave_up = false;
        let mut lines = Vec::new();
        let mut say = |line: String| match self.live_lines {
            true => self.bar.suspend(|| self.context.say(&line)),
            false => lines.push(line),
        };
        for a in 0..self.max_attempts {
            if count(&cell, ObjectLocation::Bin1) == 0 {
                self.bar.inc(u64::from(self.max_attempts - a));
                break;
            }
            let attempt_start = Instant::now();
            let vis = self.vis_path(seed, &format!("seed{seed}_attempt{a:02}.png"));
            let mut record = self.attempt(worker, &mut cell, &memory, seed, a, vis)?;
            if let Some(grasp) = record.grasp {
                memory.record(grasp, record.success);
            }
            let moved = count(&cell, ObjectLocation::Bin2);
            record.moved = Some(moved);
            record.timing.wall = attempt_start.elapsed().as_secs_f64() + setup_seconds;
            record.timing.sim += setup_seconds;
            setup_seconds = 0.0;
            say(moved_line(&record, moved, total));
            self.bar.inc(1);
            attempts.push(record);
            if interrupt::requested().is_some() {
                return Ok(None);
            }
            let failing = attempts.iter().rev().take_while(|r| !r.success).count();
            if self.give_up_after > 0 && failing >= self.give_up_after as usize {
                gave_up = true;
                self.bar.inc(u64::from(self.max_attempts - a - 1));
                say(format!("gave up after {failing} failed attempts in a row."));
                break;
            }
        }
        let bin = bin_outcome(&cell, gave_up);
        say(format!("{} objects left in the bin.", bin.left));
        let run = SceneRun {
            seed,
            attempts,
            bin: Some(bin),
        };
        Ok(Some((run, lines)))
    }

    /// A fresh workcell, watching its invariants when the soak asks for it.
    fn workcell(&self) -> anyhow::Result<Workcell> {
        let mut cell = Workcell::new(&self.workcell)?;
        if self.check_invariants {
            cell.watch_invariants();
        }
        Ok(cell)
    }

    /// Where a visualisation goes, for the policies that draw one.
    fn vis_path(&self, seed: u64, file: &str) -> PathBuf {
        if self.per_seed_vis {
            self.vis_dir.join(format!("seed{seed}")).join(file)
        } else {
            self.vis_dir.join(file)
        }
    }

    /// Looks, decides, writes the visualisation and picks.
    fn attempt(
        &self,
        worker: &mut Worker,
        cell: &mut Workcell,
        memory: &Suppression,
        drop_seed: u64,
        attempt: u32,
        vis: PathBuf,
    ) -> anyhow::Result<AttemptRecord> {
        let in_bin = objects_in_bin(cell);
        let render_start = Instant::now();
        let look = Look::take(cell, in_bin, drop_seed, attempt);
        let render = render_start.elapsed().as_secs_f64();
        let (camera, frame, rgb) = (&look.camera, &look.frame, &look.rgb);
        let decision = worker.policy.decide(&look.observation(), memory);
        let vis_written = match &decision.vis {
            Some(image) => {
                save_image_atomic(image, &vis)?;
                Some(vis)
            }
            None => None,
        };
        let aimed_at = (decision.grasp.as_ref().ok()).and_then(|&g| look.aimed_at(cell, g));
        if worker.recording.is_some() {
            cell.start_recording(EPISODE_EVERY_STEPS);
        }
        let sim_start = Instant::now();
        let push = match (&decision.grasp, decision.verified) {
            (Ok(g), Some(false)) if self.push_unverified => {
                plan_push(&HeightMap::new(camera, frame), *g)
            }
            _ => None,
        };
        let outcome = match (&decision.grasp, push) {
            (_, Some(push)) => {
                let pushed = cell.push(&push);
                PickOutcome::failure(PickReason::Pushed, pushed.detail)
            }
            (Ok(g), None) => cell.pick(&world_grasp(camera, frame, *g)),
            (Err(why), None) => PickOutcome::failure(PickReason::Ungraspable, why.to_string()),
        };
        let sim = sim_start.elapsed().as_secs_f64();
        if let Some(frames) = &mut worker.recording {
            let mut view = rgb.clone();
            if let Ok(g) = &decision.grasp {
                draw_grasp(&mut view, g);
            }
            let oblique = cell.take_recording();
            frames.extend(oblique.iter().map(|o| side_by_side(o, &view)));
        }
        let record = AttemptRecord {
            drop_seed,
            attempt,
            object: None,
            grasp: decision.grasp.as_ref().ok().copied(),
            choice: decision.choice,
            verified: decision.verified,
            success: outcome.success,
            reason: outcome.reason,
            detail: outcome.detail,
            aimed_at,
            held: outcome.object,
            placed: outcome.placed,
            moved: None,
            vis: vis_written,
            violations: cell.take_violations(),
            timing: AttemptTiming {
                wall: 0.0,
                sim,
                render,
                network: decision.network_seconds,
            },
        };
        for violation in &record.violations {
            let line = format!("invariant broken: seed {drop_seed} attempt {attempt}: {violation}");
            self.bar.suspend(|| eprintln!("{line}"));
        }
        Ok(record)
    }
}

/// empty_bin's line after an attempt: the objects moved so far, and where a carried object
/// came to rest when that was not bin 2 (what a user would otherwise see as an object that
/// vanished).
fn moved_line(record: &AttemptRecord, moved: usize, total: usize) -> String {
    let mut line = format!("{moved}/{total} objects moved");
    if let (Some(held), Some(placed)) = (&record.held, record.placed) {
        let rests = match placed {
            ObjectLocation::Bin1 => Some("back in bin 1"),
            ObjectLocation::Lost => Some("outside both bins"),
            ObjectLocation::Bin2 => None,
        };
        if let Some(rests) = rests {
            line += &format!(" ({held} was carried but came to rest {rests})");
        }
    }
    line
}

/// Where each object of an empty_bin scene ended up.
fn bin_outcome(cell: &Workcell, gave_up: bool) -> BinOutcome {
    let locations: BTreeMap<String, ObjectLocation> = cell
        .objects()
        .iter()
        .enumerate()
        .map(|(i, o)| (o.model.name.clone(), cell.locate(i)))
        .collect();
    BinOutcome {
        moved: count(cell, ObjectLocation::Bin2),
        left: count(cell, ObjectLocation::Bin1),
        lost: count(cell, ObjectLocation::Lost),
        locations,
        gave_up,
    }
}

fn count(cell: &Workcell, place: ObjectLocation) -> usize {
    (0..cell.objects().len())
        .filter(|&i| cell.locate(i) == place)
        .count()
}

/// A video frame: the oblique view, and the camera view with the grasp scaled to its height.
fn side_by_side(oblique: &RgbImage, camera_view: &RgbImage) -> RgbImage {
    let height = oblique.height();
    let scaled = image::imageops::resize(
        camera_view,
        height,
        height,
        image::imageops::FilterType::Nearest,
    );
    let mut out = RgbImage::new(oblique.width() + height, height);
    image::imageops::replace(&mut out, oblique, 0, 0);
    image::imageops::replace(&mut out, &scaled, i64::from(oblique.width()), 0);
    out
}
