//! `graspmap eval`: a policy (model, random or oracle) picks objects in simulation; per-object
//! tables, Wilson intervals, visualisations and videos (docs/evaluation.md).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;

mod config;
mod scene;
mod sweep;

use super::arranged::ArrangedScene;
use super::{workers, Context};
use crate::assets::objects::ObjectModel;
use crate::data::output::{check_output_dir, check_output_file};
use crate::interrupt;
use crate::model::inference::AffordanceModel;
use crate::named::counted;
use crate::policy::baselines::{OraclePolicy, RandomPolicy};
use crate::policy::model::ModelPolicy;
use crate::policy::suppression::SuppressionConfig;
use crate::policy::Policy;
use crate::policy::PolicyKind;
use crate::present::envelope::write_versioned_report;
use crate::present::eval_lines::report_lines;
use crate::present::eval_report::Task;
use crate::present::eval_report::{summarise, AttemptRecord, SceneRun};
use crate::present::video::episode::EpisodeVideo;
use crate::sim::WorkcellConfig;
pub(crate) use config::{
    give_up_by_default, pushes_by_default, single_object_seed, EvalConfig, ATTEMPTS_PER_OBJECT,
    EPISODE_EVERY_STEPS,
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
/// the episode's video, made on a thread of its own while the episode runs.
struct Worker {
    policy: Box<dyn Policy + Send>,
    recording: Option<EpisodeVideo>,
}

/// A piece of an evaluation that runs on its own: an empty_bin scene, or one attempt of
/// train/test (each drops its object afresh).
enum Job {
    Scene(u64),
    /// scenes: scene file `scene` (an index into the plan's) with a seed.
    Arranged {
        scene: usize,
        seed: u64,
    },
    Attempt {
        seed: u64,
        object: usize,
        try_: u32,
    },
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
    /// scenes: the scene files, read and checked.
    scenes: Vec<ArrangedScene>,
    vis_dir: PathBuf,
    per_scene: u64,
}

/// How an empty_bin or scenes run sets its bin up.
#[derive(Clone, Copy)]
enum Setup<'a> {
    /// empty_bin: these objects dropped with the seed.
    Drop(&'a [ObjectModel]),
    /// scenes: a scene file placed for the seed.
    Arrange(&'a ArrangedScene),
}

/// Runs the command.
pub(crate) fn run(context: &Context, config: EvalConfig) -> anyhow::Result<()> {
    let start = Instant::now();
    let Plan {
        seeds,
        names,
        models,
        scenes,
        vis_dir,
        per_scene,
    } = plan(context, &config)?;
    let mut runs = match config.resume {
        true => resumed(context, &config, &names, seeds.len())?,
        false => Vec::new(),
    };
    let jobs = jobs(&config, &seeds, &runs, models.len(), scenes.len());
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
            per_scene * (seeds.len() * scenes.len().max(1)) as u64,
            per_scene * runs.len() as u64,
        ),
        check_invariants: config.check_invariants,
        live_lines: workers == 1,
    };
    let recording = evaluation.run_jobs(
        &config,
        &jobs,
        (&models, &scenes),
        (workers, network_threads),
        &mut runs,
    )?;
    in_report_order(&mut runs, &seeds, &scenes);
    evaluation.bar.finish_and_clear();
    let interrupted =
        interrupt::requested().filter(|_| runs.len() < seeds.len() * scenes.len().max(1));
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
    if let (Some(path), Some(video)) = (&config.record, recording) {
        let encoding = Instant::now();
        video
            .finish(path, EPISODE_EVERY_STEPS)
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

/// Resumed runs come first; a report lists its scenes in the order of --seeds (scenes: those of
/// each scene file together, in the order of --scenes).
fn in_report_order(runs: &mut [SceneRun], seeds: &[u64], scenes: &[ArrangedScene]) {
    runs.sort_by_key(|r| {
        let scene = scenes
            .iter()
            .position(|s| Some(&s.scene.name) == r.scene.as_ref());
        (scene, seeds.iter().position(|&s| s == r.seed))
    });
}

/// How a finished evaluation ran, beside its scenes.
struct Ran {
    start: Instant,
    workers: usize,
    /// Seconds from the episode's end to the --record video written: the frames the video's
    /// thread had still to make, and the file.
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
    let scenes = ArrangedScene::load_all(context, &config.scenes)?;
    let names: Vec<String> = match config.task {
        Task::Train => context.split()?.train,
        Task::Test => context.split()?.test,
        Task::EmptyBin => context.split()?.all(),
        Task::Scenes => scenes.iter().map(|s| s.scene.name.clone()).collect(),
    };
    let models = match config.task {
        Task::Scenes => Vec::new(),
        _ => context.objects.load_all(&names)?,
    };
    if matches!(config.task, Task::Train | Task::Test) {
        // The last attempt of the last object has the largest seed: when it fits, all do.
        let last = models.len().saturating_sub(1);
        for &seed in &config.seeds {
            single_object_seed(seed, last, ATTEMPTS_PER_OBJECT - 1)?;
        }
    }
    let vis_dir = context.data.join("affordance").join(match config.task {
        Task::Train => "eval_pick_training_vis",
        Task::Test => "eval_pick_testing_vis",
        Task::EmptyBin => "eval_empty_bin_vis",
        Task::Scenes => "eval_scenes_vis",
    });
    let kept = kept_path(context, config, &names);
    check_output_dir(kept.parent().unwrap_or(&context.data), "the reports folder")?;
    check_output_dir(&vis_dir, "the visualisations folder")?;
    if let Some(record) = &config.record {
        check_output_file(record, "--record")?;
    }
    let per_scene = match config.task {
        Task::EmptyBin | Task::Scenes => u64::from(config.max_attempts),
        Task::Train | Task::Test => models.len() as u64 * u64::from(ATTEMPTS_PER_OBJECT),
    };
    announce_plan(
        context,
        config.task,
        per_scene,
        seeds.len() * scenes.len().max(1),
    );
    Ok(Plan {
        seeds,
        names,
        models,
        scenes,
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
    context.note(&format!(
        "resuming: {} of {} already in {}",
        runs.len(),
        counted(scenes, "scene"),
        source.display()
    ));
    Ok(runs)
}

/// The jobs of the seeds not in `runs`: a scene each (empty_bin), or each attempt of each
/// object (train/test).
fn jobs(
    config: &EvalConfig,
    seeds: &[u64],
    runs: &[SceneRun],
    objects: usize,
    scenes: usize,
) -> Vec<Job> {
    seeds
        .iter()
        .filter(|&&seed| !runs.iter().any(|r| r.seed == seed))
        .flat_map(|&seed| match config.task {
            Task::EmptyBin => vec![Job::Scene(seed)],
            Task::Scenes => (0..scenes)
                .map(|scene| Job::Arranged { scene, seed })
                .collect(),
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
    let lines = report_lines(&results, config.suppression.remember);
    // VPG's three metrics close a scenes run's output, after where its report went.
    let closing = match config.task {
        Task::Scenes => 3.min(lines.len()),
        _ => 0,
    };
    for line in &lines[..lines.len() - closing] {
        context.say(line);
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
    for line in &lines[lines.len() - closing..] {
        context.say(line);
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
        (models, scenes): (&[ObjectModel], &[ArrangedScene]),
        (workers, network_threads): (usize, u16),
        runs: &mut Vec<SceneRun>,
    ) -> anyhow::Result<Option<EpisodeVideo>> {
        let per_seed = models.len() * ATTEMPTS_PER_OBJECT as usize;
        let mut attempts_of: BTreeMap<u64, Vec<AttemptRecord>> = BTreeMap::new();
        let states = workers::run_in_order(
            jobs,
            workers,
            || {
                crate::model::use_threads(network_threads);
                Ok(Worker {
                    policy: policy(config)?,
                    recording: (config.record.as_ref())
                        .map(|path| EpisodeVideo::start(path, EPISODE_EVERY_STEPS))
                        .transpose()?,
                })
            },
            |worker, job| self.run_job(worker, (models, scenes), job),
            |finished| match finished {
                Finished::Scene(run, lines) => {
                    for line in &lines {
                        self.bar.suspend(|| self.context.note(line));
                    }
                    runs.push(run);
                }
                Finished::Attempt(seed, record) => {
                    let attempts = attempts_of.entry(seed).or_default();
                    attempts.push(record);
                    if attempts.len() == per_seed {
                        runs.push(SceneRun {
                            scene: None,
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
        (models, scenes): (&[ObjectModel], &[ArrangedScene]),
        job: &Job,
    ) -> anyhow::Result<Option<Finished>> {
        if interrupt::requested().is_some() {
            return Ok(None);
        }
        Ok(match *job {
            Job::Scene(seed) => self
                .empty_bin(worker, Setup::Drop(models), seed)?
                .map(|(run, lines)| Finished::Scene(run, lines)),
            Job::Arranged { scene, seed } => self
                .empty_bin(worker, Setup::Arrange(&scenes[scene]), seed)?
                .map(|(run, lines)| Finished::Scene(run, lines)),
            Job::Attempt { seed, object, try_ } => Some(Finished::Attempt(
                seed,
                self.single_object(worker, &models[object], object, seed, try_)?,
            )),
        })
    }
}
