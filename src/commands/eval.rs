//! `graspmap eval`: a policy (model, random or oracle) picks objects in simulation; per-object tables, Wilson intervals, visualisations and videos (SPEC §8).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context as _;
use clap::ValueEnum as _;
use image::RgbImage;

use super::grasp::{random_grasp, record_camera};
use super::Context;
use crate::affordance::{
    draw_grasp, rotated_observations, visualisation, Choice, Suppression, SuppressionConfig,
};
use crate::camera::Camera;
use crate::cli::{EvalArgs, PolicyChoice, Task};
use crate::grasp::{world_grasp, PixelGrasp};
use crate::inference::AffordanceModel;
use crate::metrics::{median, Rate, Spread};
use crate::objects::ObjectModel;
use crate::oracle::{self, DepthCheck, OracleConfig};
use crate::output::{save_gif_atomic, save_image_atomic, write_report};
use crate::render::Frame;
use crate::sim::pick::{PickOutcome, PickReason};
use crate::sim::{
    ObjectLocation, Workcell, WorkcellConfig, BIN1_CENTER, BIN_FLOOR_TOP, BIN_INNER_HALF,
    BIN_WALL_TOP,
};
use crate::workspace::{
    allowed_actions, CollisionCheck, GraspSite, GripperVolume, HeightMap, Tote,
};

/// Attempts per object in the train and test tasks (ref).
pub const ATTEMPTS_PER_OBJECT: u32 = 3;
/// Offset of the train/test drop seeds (ref): seed + 100·i + a + 10000.
pub const SINGLE_OBJECT_SEED_OFFSET: u64 = 10_000;
/// Physics steps between episode video frames: 10 fps, so that a 25-attempt episode stays
/// near 15 MB (`grasp --record` films one attempt at 24 fps).
pub const EPISODE_EVERY_STEPS: u64 = 24;
/// GIF frame delay matching [`EPISODE_EVERY_STEPS`] at 240 Hz, in hundredths of a second.
pub const EPISODE_DELAY_CS: u32 = 10;
/// The default empty_bin scene (ref).
pub const DEFAULT_EMPTY_BIN_SEED: u64 = 2;

/// Wall seconds of one attempt, by what they were spent on.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct AttemptTiming {
    /// Everything, from the drop (train/test) or the previous attempt (empty_bin) to the report.
    pub wall: f64,
    /// Physics: the drop (train/test) and the pick.
    pub sim: f64,
    /// The top-down camera image.
    pub render: f64,
    /// Rotations, network, suppression and argmax (model policy).
    pub network: f64,
}

/// One pick attempt.
#[derive(Debug, Clone, serde::Serialize)]
pub struct AttemptRecord {
    /// The scene's drop seed.
    pub drop_seed: u64,
    /// 0-based attempt number (per object in train/test, per scene in empty_bin).
    pub attempt: u32,
    /// train/test: the object alone in the bin.
    pub object: Option<String>,
    /// The grasp executed; absent when the policy found none.
    pub grasp: Option<PixelGrasp>,
    /// Model policy: the map the grasp came from and its score there.
    pub choice: Option<Choice>,
    /// Whether an object was lifted, carried and placed.
    pub success: bool,
    /// Why the attempt ended so.
    pub reason: PickReason,
    /// Human-readable detail.
    pub detail: String,
    /// The object whose surface the camera saw at the grasp centre (ground truth, for the
    /// report only; no policy sees it).
    pub aimed_at: Option<String>,
    /// The object that was held, if any.
    pub held: Option<String>,
    /// empty_bin: objects in bin 2 after this attempt.
    pub moved: Option<usize>,
    /// Where the visualisation went.
    pub vis: Option<PathBuf>,
    /// Where the time went.
    pub timing: AttemptTiming,
}

/// empty_bin: where each object ended up.
#[derive(Debug, Clone, serde::Serialize)]
pub struct BinOutcome {
    /// Objects resting in bin 2.
    pub moved: usize,
    /// Objects resting in bin 1.
    pub left: usize,
    /// Objects anywhere else.
    pub lost: usize,
    /// Each object's final place.
    pub locations: BTreeMap<String, ObjectLocation>,
}

/// One scene seed's run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SceneRun {
    /// The base seed.
    pub seed: u64,
    /// Every attempt, in order.
    pub attempts: Vec<AttemptRecord>,
    /// empty_bin only.
    pub bin: Option<BinOutcome>,
}

/// Per-object line of the train/test table.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ObjectSummary {
    /// Object name.
    pub object: String,
    /// Its attempts over all seeds.
    pub attempts: usize,
    /// Its successes.
    pub successes: usize,
    /// Failure reasons and how often each happened.
    pub failures: BTreeMap<String, usize>,
}

/// Mean per-attempt time.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct TimingSummary {
    /// Attempts timed.
    pub attempts: usize,
    /// Mean of each part.
    pub mean: AttemptTiming,
    /// Median wall seconds.
    pub median_wall: f64,
    /// Wall seconds of the whole evaluation.
    pub total_wall: f64,
}

/// Everything `eval --json` reports.
#[derive(Debug, Clone, serde::Serialize)]
pub struct EvalResults {
    /// train, test or empty_bin.
    pub task: Task,
    /// model, random or oracle.
    pub policy: PolicyChoice,
    /// The base seeds run.
    pub seeds: Vec<u64>,
    /// Pick success over all attempts, with its 95 % Wilson interval.
    pub success: Rate,
    /// train/test: by object.
    pub per_object: Vec<ObjectSummary>,
    /// empty_bin: objects moved per scene (mean ± std over seeds).
    pub moved: Option<Spread>,
    /// empty_bin: objects left in bin 1 per scene.
    pub left: Option<Spread>,
    /// empty_bin: objects lost per scene.
    pub lost: Option<Spread>,
    /// Every scene and attempt.
    pub runs: Vec<SceneRun>,
    /// Where the time went.
    pub timing: TimingSummary,
}

/// Who chooses grasps, with what it needs.
enum Policy {
    /// The network, and how its candidate grasps are checked.
    Model(Box<ModelPolicy>),
    Random,
    Oracle,
}

/// The network and the checks between its maps and the executed grasp.
struct ModelPolicy {
    model: AffordanceModel,
    /// Which grasps are zeroed before the argmax.
    check: CollisionCheck,
    /// How many of the best actions the depth test may look at (0 = the argmax as it is).
    verify_top: usize,
    /// Move the chosen grasp to the middle of its surface.
    centring: bool,
}

/// A policy's choice for one image.
struct Decision {
    grasp: Result<PixelGrasp, String>,
    choice: Option<Choice>,
    vis: Option<RgbImage>,
    network_seconds: f64,
}

/// Settings shared by every scene of one evaluation.
struct Evaluation<'a> {
    context: &'a Context,
    policy: Policy,
    suppression: SuppressionConfig,
    workcell: WorkcellConfig,
    camera: Camera,
    vis_dir: PathBuf,
    /// Put each seed's visualisations in a seed<S>/ subfolder (several seeds).
    per_seed_vis: bool,
    max_attempts: u32,
    recording: Option<Vec<RgbImage>>,
    bar: indicatif::ProgressBar,
}

/// Runs the command.
pub fn run(context: &Context, args: EvalArgs) -> anyhow::Result<()> {
    let start = Instant::now();
    let seeds = match (&args.seeds, args.seed) {
        (Some(list), _) => list.0.clone(),
        (None, Some(seed)) => vec![seed],
        (None, None) if args.task == Task::EmptyBin => vec![DEFAULT_EMPTY_BIN_SEED],
        (None, None) => vec![0],
    };
    let checkpoint = checkpoint_path(context, args.checkpoint.as_deref());
    tch::set_num_threads(i32::from(context.threads));
    let precision = args.precision.resolve();
    let policy = match args.policy {
        PolicyChoice::Model => Policy::Model(Box::new(ModelPolicy {
            model: AffordanceModel::load(&checkpoint, precision)?,
            check: args.collision_check,
            verify_top: args.verify_top,
            centring: args.centring,
        })),
        PolicyChoice::Random => Policy::Random,
        PolicyChoice::Oracle => Policy::Oracle,
    };
    let split = context.split()?;
    let names: Vec<String> = match args.task {
        Task::Train => split.train.clone(),
        Task::Test => split.test.clone(),
        Task::EmptyBin => split.train.iter().chain(&split.test).cloned().collect(),
    };
    let library = context.library();
    let models = names
        .iter()
        .map(|n| library.load(n))
        .collect::<Result<Vec<ObjectModel>, _>>()?;
    let suppression = SuppressionConfig {
        remember: args.n_past_action,
        sigma_px: args.suppression_sigma,
        rotation_reach: usize::from(args.suppress_rotation_reach),
        remember_successes: args.suppress_successes,
    };
    let vis_dir = context.data.join("affordance").join(match args.task {
        Task::Train => "eval_pick_training_vis",
        Task::Test => "eval_pick_testing_vis",
        Task::EmptyBin => "eval_empty_bin_vis",
    });
    let per_scene = match args.task {
        Task::EmptyBin => u64::from(args.max_attempts),
        _ => models.len() as u64 * u64::from(ATTEMPTS_PER_OBJECT),
    };
    let mut evaluation = Evaluation {
        context,
        policy,
        suppression,
        workcell: WorkcellConfig::default(),
        camera: Camera::top_down(),
        vis_dir,
        per_seed_vis: seeds.len() > 1,
        max_attempts: args.max_attempts,
        recording: args.record.as_ref().map(|_| Vec::new()),
        bar: context.progress_bar("attempts", per_scene * seeds.len() as u64, 0),
    };

    let mut runs = Vec::new();
    for &seed in &seeds {
        let run = match args.task {
            Task::EmptyBin => evaluation.empty_bin(&models, seed)?,
            Task::Train | Task::Test => evaluation.single_objects(&models, seed)?,
        };
        runs.push(run);
    }
    evaluation.bar.finish_and_clear();
    if let (Some(path), Some(frames)) = (&args.record, &evaluation.recording) {
        save_gif_atomic(frames, EPISODE_DELAY_CS, path)
            .with_context(|| format!("writing --record {}", path.display()))?;
        context.say(&format!("wrote the episode video to {}", path.display()));
    }

    let results = summarise(
        args.task,
        args.policy,
        seeds.clone(),
        &names,
        runs,
        start.elapsed().as_secs_f64(),
    );
    for line in report_lines(&results, &args) {
        context.say(&line);
    }
    if let Some(json) = &context.json {
        let resolved = serde_json::json!({
            "global": context,
            "task": args.task,
            "policy": args.policy,
            "checkpoint": (args.policy == PolicyChoice::Model).then_some(&checkpoint),
            "precision": (args.policy == PolicyChoice::Model).then_some(precision),
            "seeds": seeds,
            "suppression": suppression,
            "collision_check": (args.policy == PolicyChoice::Model).then_some(args.collision_check),
            "verify_top": (args.policy == PolicyChoice::Model).then_some(args.verify_top),
            "centring": args.policy == PolicyChoice::Model
                && args.collision_check == CollisionCheck::Full
                && args.centring,
            "max_attempts": args.max_attempts,
            "attempts_per_object": ATTEMPTS_PER_OBJECT,
            "objects": names,
            "workcell": WorkcellConfig::default(),
            "record": args.record,
        });
        write_report(json, "eval", seeds[0], &resolved, &results)?;
    }
    Ok(())
}

impl Evaluation<'_> {
    /// train/test: each object alone, [`ATTEMPTS_PER_OBJECT`] fresh drops each.
    fn single_objects(&mut self, models: &[ObjectModel], seed: u64) -> anyhow::Result<SceneRun> {
        let mut attempts = Vec::new();
        for (i, model) in models.iter().enumerate() {
            for a in 0..ATTEMPTS_PER_OBJECT {
                let started = Instant::now();
                let drop_seed = seed + 100 * i as u64 + u64::from(a) + SINGLE_OBJECT_SEED_OFFSET;
                let mut cell = Workcell::new(self.context.assets(), &self.workcell)?;
                cell.drop_objects(std::slice::from_ref(model), drop_seed)?;
                let drop_seconds = started.elapsed().as_secs_f64();
                // Suppression remembers actions within a scene; each attempt here is a new one.
                let memory = Suppression::new(self.suppression);
                let vis = self.vis_path(seed, &format!("{}_{a}.png", model.name));
                let mut record = self.attempt(&mut cell, &memory, drop_seed, a, vis)?;
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
                        record.reason.as_str()
                    }
                ));
                attempts.push(record);
            }
        }
        Ok(SceneRun {
            seed,
            attempts,
            bin: None,
        })
    }

    /// empty_bin: every object in bin 1 at once, picked until the bin is empty or attempts run out.
    fn empty_bin(&mut self, models: &[ObjectModel], seed: u64) -> anyhow::Result<SceneRun> {
        let started = Instant::now();
        let mut cell = Workcell::new(self.context.assets(), &self.workcell)?;
        cell.drop_objects(models, seed)?;
        let mut setup_seconds = started.elapsed().as_secs_f64();
        let total = models.len();
        let mut memory = Suppression::new(self.suppression);
        let mut attempts = Vec::new();
        for a in 0..self.max_attempts {
            if count(&cell, ObjectLocation::Bin1) == 0 {
                self.bar.inc(u64::from(self.max_attempts - a));
                break;
            }
            let attempt_start = Instant::now();
            let vis = self.vis_path(seed, &format!("seed{seed}_attempt{a:02}.png"));
            let mut record = self.attempt(&mut cell, &memory, seed, a, vis)?;
            if let Some(choice) = record.choice {
                memory.record(choice, record.success);
            }
            let moved = count(&cell, ObjectLocation::Bin2);
            record.moved = Some(moved);
            record.timing.wall = attempt_start.elapsed().as_secs_f64() + setup_seconds;
            record.timing.sim += setup_seconds;
            setup_seconds = 0.0;
            let line = format!("{moved}/{total} objects moved");
            self.bar.suspend(|| self.context.say(&line));
            self.bar.inc(1);
            attempts.push(record);
        }
        let left = count(&cell, ObjectLocation::Bin1);
        let line = format!("{left} objects left in the bin.");
        self.bar.suspend(|| self.context.say(&line));
        let locations: BTreeMap<String, ObjectLocation> = cell
            .objects()
            .iter()
            .enumerate()
            .map(|(i, o)| (o.model.name.clone(), cell.locate(i)))
            .collect();
        Ok(SceneRun {
            seed,
            attempts,
            bin: Some(BinOutcome {
                moved: count(&cell, ObjectLocation::Bin2),
                left,
                lost: count(&cell, ObjectLocation::Lost),
                locations,
            }),
        })
    }

    fn vis_path(&self, seed: u64, file: &str) -> Option<PathBuf> {
        if !matches!(self.policy, Policy::Model(..)) {
            return None;
        }
        Some(if self.per_seed_vis {
            self.vis_dir.join(format!("seed{seed}")).join(file)
        } else {
            self.vis_dir.join(file)
        })
    }

    /// Looks, decides, writes the visualisation and picks.
    fn attempt(
        &mut self,
        cell: &mut Workcell,
        memory: &Suppression,
        drop_seed: u64,
        attempt: u32,
        vis: Option<PathBuf>,
    ) -> anyhow::Result<AttemptRecord> {
        let render_start = Instant::now();
        let frame = cell.capture();
        let rgb = frame.to_rgb_image();
        let render = render_start.elapsed().as_secs_f64();
        let in_bin: Vec<u16> = cell
            .objects()
            .iter()
            .enumerate()
            .filter(|(i, _)| cell.locate(*i) == ObjectLocation::Bin1)
            .map(|(_, o)| o.id)
            .collect();
        // The random policy's own stream: one per attempt, independent of the drop.
        let random_seed = drop_seed
            .wrapping_mul(1_000)
            .wrapping_add(u64::from(attempt));
        let decision = decide(
            &self.policy,
            &self.camera,
            &frame,
            &rgb,
            &in_bin,
            memory,
            random_seed,
        );
        let vis_written = match (&vis, &decision.vis) {
            (Some(path), Some(image)) => {
                if let Some(dir) = path.parent() {
                    std::fs::create_dir_all(dir)
                        .with_context(|| format!("creating {}", dir.display()))?;
                }
                save_image_atomic(image, path)?;
                Some(path.clone())
            }
            _ => None,
        };
        let aimed_at = decision.grasp.as_ref().ok().and_then(|g| {
            let id = frame.id_at(g.u, g.v);
            cell.objects()
                .iter()
                .find(|o| o.id == id)
                .map(|o| o.model.name.clone())
        });
        if self.recording.is_some() {
            cell.start_recording(record_camera(), EPISODE_EVERY_STEPS);
        }
        let sim_start = Instant::now();
        let outcome = match &decision.grasp {
            Ok(g) => cell.pick(&world_grasp(&self.camera, &frame, *g)),
            Err(why) => PickOutcome::failure(PickReason::Ungraspable, why.clone()),
        };
        let sim = sim_start.elapsed().as_secs_f64();
        if let Some(frames) = &mut self.recording {
            let mut view = rgb.clone();
            if let Ok(g) = &decision.grasp {
                draw_grasp(&mut view, g);
            }
            let oblique = cell.take_recording();
            frames.extend(oblique.iter().map(|o| side_by_side(o, &view)));
        }
        Ok(AttemptRecord {
            drop_seed,
            attempt,
            object: None,
            grasp: decision.grasp.as_ref().ok().copied(),
            choice: decision.choice,
            success: outcome.success,
            reason: outcome.reason,
            detail: outcome.detail,
            aimed_at,
            held: outcome.object,
            moved: None,
            vis: vis_written,
            timing: AttemptTiming {
                wall: 0.0,
                sim,
                render,
                network: decision.network_seconds,
            },
        })
    }
}

/// The policy's grasp for this frame. The oracle takes the topmost object of bin 1 it can
/// grasp, the model the suppressed maps' argmax.
fn decide(
    policy: &Policy,
    camera: &Camera,
    frame: &Frame,
    rgb: &RgbImage,
    in_bin: &[u16],
    memory: &Suppression,
    random_seed: u64,
) -> Decision {
    match policy {
        Policy::Model(policy) => {
            let ModelPolicy {
                model,
                check,
                verify_top,
                centring,
            } = policy.as_ref();
            let start = Instant::now();
            let rotated = rotated_observations(rgb);
            let mut maps = model.predict(&rotated);
            if *check != CollisionCheck::Off {
                let gripper = GripperVolume::from(&OracleConfig::default());
                maps.restrict(&allowed_actions(
                    camera,
                    frame,
                    &pick_tote(),
                    &gripper,
                    *check,
                ));
            }
            memory.apply(&mut maps);
            let mut choice = maps.choose();
            if *verify_top > 0 {
                // The network ranks, the planner's depth test vetoes: in clutter its peak often
                // sits on a box's edge or corner, where the pads squeeze the box out, or across a
                // side wider than the jaw leaves room for. When none of the best passes, the
                // argmax is still tried (BENCHMARKS.md, "Depth test").
                let test = DepthCheck::new(camera, frame, OracleConfig::default());
                if let Some(passed) = maps
                    .ranked(*verify_top)
                    .into_iter()
                    .find(|c| test.assess(c.grasp).is_ok())
                {
                    choice = passed;
                }
            }
            if *check == CollisionCheck::Full && *centring {
                let gripper = GripperVolume::from(&OracleConfig::default());
                let heights = HeightMap::new(camera, frame);
                // A grasp that fits only at a corner is still executed: refusing it and taking
                // the next best did worse (BENCHMARKS.md, "Centring").
                let site = GraspSite {
                    camera,
                    frame,
                    heights: &heights,
                    tote: &pick_tote(),
                    gripper: &gripper,
                };
                let refined = site.refine(choice.grasp, |g| maps.score_at(g));
                if let Some(grasp) = refined.filter(|&g| g != choice.grasp) {
                    choice = maps.choice_of(grasp);
                }
            }
            let network_seconds = start.elapsed().as_secs_f64();
            Decision {
                grasp: Ok(choice.grasp),
                choice: Some(choice),
                vis: Some(visualisation(&rotated, &maps, &choice)),
                network_seconds,
            }
        }
        Policy::Random => Decision {
            grasp: Ok(random_grasp(camera, random_seed)),
            choice: None,
            vis: None,
            network_seconds: 0.0,
        },
        Policy::Oracle => {
            let mut why = "no object is visible in bin 1".to_owned();
            let mut grasp = Err(why.clone());
            for id in topmost_first(frame, in_bin) {
                match oracle::plan(camera, frame, id, &OracleConfig::default()) {
                    Ok(plan) => {
                        grasp = Ok(plan.grasp);
                        break;
                    }
                    Err(e) => why = e.to_string(),
                }
                grasp = Err(why.clone());
            }
            Decision {
                grasp,
                choice: None,
                vis: None,
                network_seconds: 0.0,
            }
        }
    }
}

/// Visible object ids, nearest to the camera first (ties by id).
fn topmost_first(frame: &Frame, ids: &[u16]) -> Vec<u16> {
    let mut nearest: BTreeMap<u16, f32> = BTreeMap::new();
    for v in 0..frame.height {
        for u in 0..frame.width {
            let id = frame.id_at(u, v);
            if ids.contains(&id) {
                let depth = frame.depth_at(u, v);
                let entry = nearest.entry(id).or_insert(f32::INFINITY);
                *entry = entry.min(depth);
            }
        }
    }
    let mut order: Vec<(u16, f32)> = nearest.into_iter().collect();
    order.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
    order.into_iter().map(|(id, _)| id).collect()
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

fn summarise(
    task: Task,
    policy: PolicyChoice,
    seeds: Vec<u64>,
    names: &[String],
    runs: Vec<SceneRun>,
    total_wall: f64,
) -> EvalResults {
    let all: Vec<&AttemptRecord> = runs.iter().flat_map(|r| &r.attempts).collect();
    let successes = all.iter().filter(|a| a.success).count();
    let per_object = if task == Task::EmptyBin {
        Vec::new()
    } else {
        names
            .iter()
            .map(|name| {
                let mine: Vec<&&AttemptRecord> = all
                    .iter()
                    .filter(|a| a.object.as_deref() == Some(name))
                    .collect();
                let mut failures = BTreeMap::new();
                for a in mine.iter().filter(|a| !a.success) {
                    *failures.entry(a.reason.as_str().to_owned()).or_insert(0) += 1;
                }
                ObjectSummary {
                    object: name.clone(),
                    attempts: mine.len(),
                    successes: mine.iter().filter(|a| a.success).count(),
                    failures,
                }
            })
            .collect()
    };
    let spread_of = |f: fn(&BinOutcome) -> usize| {
        (task == Task::EmptyBin).then(|| {
            let values: Vec<f64> = runs
                .iter()
                .filter_map(|r| r.bin.as_ref())
                .map(|b| f(b) as f64)
                .collect();
            Spread::of(&values)
        })
    };
    let n = all.len().max(1) as f64;
    let mean_of = |f: fn(&AttemptTiming) -> f64| all.iter().map(|a| f(&a.timing)).sum::<f64>() / n;
    let walls: Vec<f64> = all.iter().map(|a| a.timing.wall).collect();
    EvalResults {
        task,
        policy,
        seeds,
        success: Rate::new(successes, all.len()),
        per_object,
        moved: spread_of(|b| b.moved),
        left: spread_of(|b| b.left),
        lost: spread_of(|b| b.lost),
        timing: TimingSummary {
            attempts: all.len(),
            mean: AttemptTiming {
                wall: mean_of(|t| t.wall),
                sim: mean_of(|t| t.sim),
                render: mean_of(|t| t.render),
                network: mean_of(|t| t.network),
            },
            median_wall: median(&walls),
            total_wall,
        },
        runs,
    }
}

fn failure_list(failures: &BTreeMap<String, usize>) -> String {
    if failures.is_empty() {
        return "-".to_owned();
    }
    failures
        .iter()
        .map(|(reason, n)| format!("{reason} {n}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The human-readable report: a table, the overall rate, and where the time went.
fn report_lines(results: &EvalResults, args: &EvalArgs) -> Vec<String> {
    let mut lines = Vec::new();
    let seeds = results
        .seeds
        .iter()
        .map(u64::to_string)
        .collect::<Vec<_>>()
        .join(",");
    let suppression = if args.n_past_action == 0 {
        String::new()
    } else {
        format!(", n_past_action {}", args.n_past_action)
    };
    let name = |value: Option<clap::builder::PossibleValue>| {
        value.map_or_else(String::new, |v| v.get_name().to_owned())
    };
    let policy = name(results.policy.to_possible_value());
    let task = name(results.task.to_possible_value());
    lines.push(format!(
        "eval --task {task}, policy {policy}, seed {seeds}{suppression}"
    ));
    if results.task == Task::EmptyBin {
        lines.push(format!(
            "{:>6} {:>8} {:>9} {:>6} {:>5} {:>5}  failures",
            "seed", "attempts", "successes", "moved", "left", "lost"
        ));
        for run in &results.runs {
            let bin = run.bin.as_ref().expect("empty_bin runs have an outcome");
            let mut failures = BTreeMap::new();
            for a in run.attempts.iter().filter(|a| !a.success) {
                *failures.entry(a.reason.as_str().to_owned()).or_insert(0) += 1;
            }
            lines.push(format!(
                "{:>6} {:>8} {:>9} {:>6} {:>5} {:>5}  {}",
                run.seed,
                run.attempts.len(),
                run.attempts.iter().filter(|a| a.success).count(),
                bin.moved,
                bin.left,
                bin.lost,
                failure_list(&failures)
            ));
        }
        if let (Some(moved), Some(lost)) = (&results.moved, &results.lost) {
            let total = results.runs[0]
                .bin
                .as_ref()
                .map_or(0, |b| b.locations.len());
            lines.push(format!(
                "objects moved: {:.1} ± {:.1} of {total} (min {}, max {}, over {} scene{}); lost {:.1}",
                moved.mean,
                moved.std,
                moved.min,
                moved.max,
                moved.count,
                if moved.count == 1 { "" } else { "s" },
                lost.mean
            ));
        }
        lines.push(format!("pick success: {}", results.success.describe()));
    } else {
        let width = results
            .per_object
            .iter()
            .map(|o| o.object.len())
            .max()
            .unwrap_or(6)
            .max(6);
        lines.push(format!(
            "{:<width$} {:>8} {:>9}  failures",
            "object", "attempts", "successes"
        ));
        for o in &results.per_object {
            lines.push(format!(
                "{:<width$} {:>8} {:>9}  {}",
                o.object,
                o.attempts,
                o.successes,
                failure_list(&o.failures)
            ));
        }
        lines.push(format!("success rate: {}", results.success.describe()));
    }
    let t = &results.timing;
    lines.push(format!(
        "per attempt: {:.2} s wall (median {:.2}) = sim {:.2} + render {:.3} + network {:.3} + other {:.3}; total {:.1} s",
        t.mean.wall,
        t.median_wall,
        t.mean.sim,
        t.mean.render,
        t.mean.network,
        (t.mean.wall - t.mean.sim - t.mean.render - t.mean.network).max(0.0),
        t.total_wall
    ));
    lines
}

/// The pick tote's inside, from the workcell's layout.
pub fn pick_tote() -> Tote {
    Tote {
        center: [BIN1_CENTER.x, BIN1_CENTER.y],
        inner_half: BIN_INNER_HALF,
        wall_top: BIN_WALL_TOP,
        floor_top: BIN_FLOOR_TOP,
    }
}

/// The `--checkpoint` given, or where `predict` and `eval` find the model by default.
pub fn checkpoint_path(context: &Context, given: Option<&Path>) -> PathBuf {
    given.map_or_else(
        || context.data.join("affordance").join("best.safetensors"),
        Path::to_path_buf,
    )
}
