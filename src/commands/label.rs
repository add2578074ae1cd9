//! `graspmap label`: collect grasp labels round by round, each verified by a simulated pick, resumable after any interruption.

use std::collections::BTreeMap;
use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use anyhow::{bail, Context as _};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::Context;
use crate::camera::Camera;
use crate::cli::LabelArgs;
use crate::grasp::{normalize_angle, world_grasp, PixelGrasp};
use crate::labels::{Label, LabelStore, Labels, Progress, IMAGE_SIZE};
use crate::oracle::{self, OracleConfig};
use crate::output::{save_image_atomic, write_report};
use crate::render::Frame;
use crate::sim::pick::PickReason;
use crate::sim::{Workcell, WorkcellConfig};

/// The angle step a person gets with the A/D keys.
pub const ANGLE_STEP_DEG: f32 = 22.5;

/// Where clicks come from.
enum Clicker {
    /// The oracle planner, with optional human-like noise.
    Scripted { noise_px: f32, noise_deg: f32 },
    /// A list from a file, per object in order.
    File {
        clicks: BTreeMap<String, Vec<Label>>,
    },
    /// A person (or a script) at stdin, looking at a preview image.
    Interactive { preview: PathBuf },
}

impl Clicker {
    fn name(&self) -> &'static str {
        match self {
            Clicker::Scripted { .. } => "scripted",
            Clicker::File { .. } => "file",
            Clicker::Interactive { .. } => "interactive",
        }
    }

    /// The click for one round, or why there is none (the round then fails).
    fn click(
        &self,
        object: &str,
        round: u32,
        round_seed: u64,
        frame: &Frame,
    ) -> anyhow::Result<Result<PixelGrasp, String>> {
        match self {
            Clicker::Scripted {
                noise_px,
                noise_deg,
            } => {
                // A person clicks in 22.5° steps; plan in those steps too.
                let config = OracleConfig {
                    angles: (180.0 / ANGLE_STEP_DEG) as u32,
                    ..OracleConfig::default()
                };
                let plan = match oracle::plan(&Camera::top_down(), frame, 1, &config) {
                    Ok(plan) => plan,
                    Err(e) => return Ok(Err(e.to_string())),
                };
                Ok(Ok(human_noise(
                    plan.grasp, *noise_px, *noise_deg, round_seed,
                )))
            }
            Clicker::File { clicks } => {
                let label = clicks
                    .get(object)
                    .and_then(|list| list.get(round as usize))
                    .with_context(|| {
                        format!("--clicks has no click for {object} round {round} (one click per round, failed rounds included)")
                    })?;
                Ok(Ok(PixelGrasp::from(*label)))
            }
            Clicker::Interactive { preview } => {
                interactive_click(preview, object, round, frame).map(Ok)
            }
        }
    }
}

/// Jitters a planned click like a person would, then snaps the angle to the A/D key steps.
fn human_noise(grasp: PixelGrasp, noise_px: f32, noise_deg: f32, round_seed: u64) -> PixelGrasp {
    let mut rng = ChaCha8Rng::seed_from_u64(round_seed);
    // Stream 2: independent of the drop (stream 0) and of random policies (stream 1).
    rng.set_stream(2);
    let mut jitter = |sigma: f32| {
        if sigma > 0.0 {
            Normal::new(0.0, sigma)
                .expect("sigma is positive and finite")
                .sample(&mut rng)
        } else {
            0.0
        }
    };
    let max = (IMAGE_SIZE - 1) as f32;
    let u = (grasp.u as f32 + jitter(noise_px)).round().clamp(0.0, max) as u32;
    let v = (grasp.v as f32 + jitter(noise_px)).round().clamp(0.0, max) as u32;
    let angle = grasp.angle_deg + jitter(noise_deg);
    PixelGrasp {
        u,
        v,
        angle_deg: normalize_angle((angle / ANGLE_STEP_DEG).round() * ANGLE_STEP_DEG),
    }
}

/// One object's tally.
#[derive(Debug, Default, Clone, serde::Serialize)]
struct ObjectSummary {
    object: String,
    /// Rounds run for this object, earlier sessions included.
    rounds: u32,
    /// Labels stored for it.
    labels: usize,
    /// Labels added by this run.
    new_labels: usize,
    /// Failed rounds of this run by reason.
    failures: BTreeMap<String, u32>,
}

#[derive(Debug, serde::Serialize)]
struct LabelResults {
    labels_dir: String,
    source: &'static str,
    objects: Vec<ObjectSummary>,
    total_labels: usize,
    total_rounds: u32,
    wall_seconds: f64,
}

/// Runs the command.
pub fn run(context: &Context, args: LabelArgs) -> anyhow::Result<()> {
    let store = LabelStore::new(context.data.join("labels"));
    let library = context.library();
    if args.check {
        return check(context, &store, &library.names());
    }
    let split = context.split()?;
    let models = library.load_all(&split.train)?;
    let clicker = if let Some(path) = &args.clicks {
        Clicker::File {
            clicks: read_clicks(path, &split.train)?,
        }
    } else if args.interactive {
        Clicker::Interactive {
            preview: args
                .preview
                .clone()
                .unwrap_or_else(|| store.dir().join("preview.png")),
        }
    } else {
        Clicker::Scripted {
            noise_px: args.click_noise_px,
            noise_deg: args.angle_noise_deg,
        }
    };

    if args.force {
        store.clear()?;
    }
    store.remove_stale_temporaries()?;
    let mut labels = store.load()?;
    let progress = resume_point(&store, &labels, &args, clicker.name(), &split.train)?;
    if let Clicker::File { clicks } = &clicker {
        check_enough_clicks(clicks, &labels, &progress, &args, &split.train)?;
    }

    let start = Instant::now();
    let wanted = args.per_object as u64 * split.train.len() as u64;
    // A person at the prompt needs a quiet terminal.
    let bar = if args.interactive {
        indicatif::ProgressBar::hidden()
    } else {
        context.progress_bar(
            "labels",
            wanted,
            labels_in(&labels, &split.train, args.per_object),
        )
    };
    let verbose_rounds = !matches!(clicker, Clicker::Scripted { .. });
    // Objects are independent (each has its own rounds and seeds), so they run on parallel
    // workers; the dataset files are written under one lock, in split order, so the result does
    // not depend on which worker finishes first. A person answers one prompt at a time.
    let workers = if args.interactive {
        1
    } else {
        (context.threads as usize).min(split.train.len()).max(1)
    };
    let mut progress = progress;
    labels.arrange(&split.train);
    for object in &split.train {
        let (rounds, recorded) = progress.entry(object);
        progress.set_rounds(object, rounds, recorded);
    }
    let shared = Mutex::new(Shared { labels, progress });
    let next = AtomicUsize::new(0);
    let failed = AtomicBool::new(false);
    let outcomes: Mutex<Vec<Option<anyhow::Result<ObjectSummary>>>> =
        Mutex::new((0..split.train.len()).map(|_| None).collect());
    let job = ObjectJob {
        context,
        args: &args,
        store: &store,
        clicker: &clicker,
        bar: &bar,
        verbose_rounds,
        stop: &failed,
    };
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| loop {
                let j = next.fetch_add(1, Ordering::SeqCst);
                if j >= split.train.len() || failed.load(Ordering::SeqCst) {
                    break;
                }
                let outcome = job.label_object(j, &split.train[j], &models[j], &shared);
                if outcome.is_err() {
                    failed.store(true, Ordering::SeqCst);
                }
                lock(&outcomes)[j] = Some(outcome);
            });
        }
    });
    bar.finish_and_clear();
    let mut summaries = Vec::new();
    for outcome in lock(&outcomes).drain(..).flatten() {
        summaries.push(outcome?);
    }

    let results = LabelResults {
        labels_dir: store.dir().display().to_string(),
        source: clicker.name(),
        total_labels: summaries.iter().map(|s| s.labels).sum(),
        total_rounds: summaries.iter().map(|s| s.rounds).sum(),
        objects: summaries,
        wall_seconds: start.elapsed().as_secs_f64(),
    };
    print_summary(context, &results);
    if let Some(json) = &context.json {
        let resolved = serde_json::json!({
            "global": context,
            "per_object": args.per_object,
            "max_rounds": args.max_rounds,
            "source": clicker.name(),
            "clicks": args.clicks,
            "click_noise_px": args.click_noise_px,
            "angle_noise_deg": args.angle_noise_deg,
            "train": split.train,
        });
        write_report(json, "label", args.seed, &resolved, &results)?;
    }
    Ok(())
}

/// Dataset state shared by the workers.
struct Shared {
    labels: Labels,
    progress: Progress,
}

fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    // A worker that panicked mid-write has already lost its round; the files on disk are
    // whole (atomic renames), so the state is still usable.
    mutex
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// What every worker needs to label one object.
struct ObjectJob<'a> {
    context: &'a Context,
    args: &'a LabelArgs,
    store: &'a LabelStore,
    clicker: &'a Clicker,
    bar: &'a indicatif::ProgressBar,
    verbose_rounds: bool,
    stop: &'a AtomicBool,
}

impl ObjectJob<'_> {
    /// Runs rounds for training object `j` until it has its labels.
    fn label_object(
        &self,
        j: usize,
        object: &str,
        model: &crate::objects::ObjectModel,
        shared: &Mutex<Shared>,
    ) -> anyhow::Result<ObjectSummary> {
        let args = self.args;
        let camera = Camera::top_down();
        let config = WorkcellConfig::default();
        let mut summary = ObjectSummary {
            object: object.to_owned(),
            ..Default::default()
        };
        let (mut round, mut have) = {
            let state = lock(shared);
            (
                state.progress.rounds_of(object),
                state.labels.of(object).len(),
            )
        };
        while have < args.per_object as usize {
            if self.stop.load(Ordering::SeqCst) {
                // Another object failed; this one resumes on the next run.
                break;
            }
            if round >= args.max_rounds {
                bail!(
                    "{object}: only {have} of {} labels after {round} rounds (--max-rounds {}); raise --max-rounds or check the clicks",
                    args.per_object,
                    args.max_rounds
                );
            }
            let round_seed = args.seed + 100 * j as u64 + round as u64;
            self.bar
                .set_message(format!("{object} {have}/{} round {round}", args.per_object));
            let mut cell = Workcell::new(self.context.assets(), &config)?;
            cell.drop_objects(std::slice::from_ref(model), round_seed)?;
            let frame = cell.capture();
            let click = self.clicker.click(object, round, round_seed, &frame)?;
            let (reason, detail) = match &click {
                Ok(grasp) => {
                    let outcome = cell.pick(&world_grasp(&camera, &frame, *grasp));
                    (outcome.reason, outcome.detail)
                }
                Err(why) => (PickReason::Ungraspable, why.clone()),
            };
            let line = match &click {
                Ok(g) => format!(
                    "{object} round {round} click ({}, {}, {:.1}°): {} {detail}",
                    g.u,
                    g.v,
                    g.angle_deg,
                    reason.as_str()
                ),
                Err(_) => format!("{object} round {round}: no click: {detail}"),
            };
            round += 1;
            {
                let mut state = lock(shared);
                let Shared { labels, progress } = &mut *state;
                if let (PickReason::Success, Ok(grasp)) = (reason, &click) {
                    self.store.append(
                        labels,
                        object,
                        Label::from(*grasp),
                        &frame.to_rgb_image(),
                    )?;
                    summary.new_labels += 1;
                    self.bar.inc(1);
                } else {
                    *summary
                        .failures
                        .entry(reason.as_str().to_owned())
                        .or_default() += 1;
                }
                have = labels.of(object).len();
                progress.set_rounds(object, round, have as u32);
                self.store.save_progress(progress)?;
            }
            if self.verbose_rounds || reason != PickReason::Success {
                self.bar.suspend(|| self.context.say(&line));
            }
        }
        summary.rounds = round;
        summary.labels = have;
        Ok(summary)
    }
}

fn labels_in(labels: &Labels, objects: &[String], cap: u32) -> u64 {
    objects
        .iter()
        .map(|o| labels.of(o).len().min(cap as usize) as u64)
        .sum()
}

fn print_summary(context: &Context, results: &LabelResults) {
    context.say(&format!(
        "{:<18} {:>6} {:>6} {:>4}  failures this run",
        "object", "labels", "rounds", "new"
    ));
    for s in &results.objects {
        let failures = s
            .failures
            .iter()
            .map(|(reason, n)| format!("{reason} {n}"))
            .collect::<Vec<_>>()
            .join(", ");
        context.say(&format!(
            "{:<18} {:>6} {:>6} {:>4}  {}",
            s.object,
            s.labels,
            s.rounds,
            s.new_labels,
            if failures.is_empty() { "-" } else { &failures }
        ));
    }
    context.say(&format!(
        "{} labels in {} rounds in {} ({:.1} s)",
        results.total_labels, results.total_rounds, results.labels_dir, results.wall_seconds
    ));
}

/// Where to continue: the rounds already run per object, from progress.json.
fn resume_point(
    store: &LabelStore,
    labels: &Labels,
    args: &LabelArgs,
    source: &str,
    train: &[String],
) -> anyhow::Result<Progress> {
    let fresh = Progress {
        schema: Progress::SCHEMA.to_owned(),
        seed: args.seed,
        source: source.to_owned(),
        rounds: Vec::new(),
    };
    let Some(mut progress) = store.load_progress()? else {
        if !labels.is_empty() {
            // A dataset from elsewhere (e.g. the reference tool): its rounds are unknown, so
            // continue as if every earlier round had succeeded.
            tracing::warn!(
                "{} has labels but no progress file; continuing as if each label took one round",
                store.dir().display()
            );
            let mut progress = fresh;
            for object in train {
                let n = labels.of(object).len() as u32;
                progress.set_rounds(object, n, n);
            }
            return Ok(progress);
        }
        return Ok(fresh);
    };
    if progress.schema != Progress::SCHEMA {
        bail!(
            "{} has schema '{}', expected '{}' (rerun with --force to start over)",
            store.dir().join(crate::labels::PROGRESS_FILE).display(),
            progress.schema,
            Progress::SCHEMA
        );
    }
    if progress.seed != args.seed || progress.source != source {
        bail!(
            "the labels in {} were made with --seed {} ({} clicks); rerun with those settings to resume, or with --force to start over",
            store.dir().display(),
            progress.seed,
            progress.source
        );
    }
    // A run killed between writing labels.json and progress.json: the label is there, its
    // round is not counted yet.
    for object in train {
        let (rounds, recorded) = progress.entry(object);
        let stored = labels.of(object).len() as u32;
        if stored == recorded + 1 {
            progress.set_rounds(object, rounds + 1, stored);
        } else if stored != recorded {
            bail!(
                "{}: {object} has {stored} labels but progress.json records {recorded}; rerun with --force to start over",
                store.dir().display()
            );
        }
    }
    Ok(progress)
}

/// Parses a clicks file: a JSON list of {"object", "x", "y", "angle"}, grouped per object in order.
fn read_clicks(path: &Path, train: &[String]) -> anyhow::Result<BTreeMap<String, Vec<Label>>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading --clicks {}", path.display()))?;
    let value: serde_json::Value = serde_json::from_str(&text)
        .with_context(|| format!("--clicks {} is not valid JSON", path.display()))?;
    let list = value.as_array().with_context(|| {
        format!(
            "--clicks {}: expected a list of {{\"object\", \"x\", \"y\", \"angle\"}}",
            path.display()
        )
    })?;
    let mut clicks: BTreeMap<String, Vec<Label>> = BTreeMap::new();
    for (i, entry) in list.iter().enumerate() {
        let at = || format!("--clicks {} entry {}", path.display(), i + 1);
        let object = entry
            .get("object")
            .and_then(|o| o.as_str())
            .with_context(|| format!("{}: missing \"object\" name", at()))?;
        if !train.iter().any(|t| t == object) {
            bail!(
                "{}: unknown object '{object}' (training objects: {})",
                at(),
                train.join(", ")
            );
        }
        let number = |key: &str| {
            entry
                .get(key)
                .and_then(|v| v.as_f64())
                .filter(|v| v.is_finite())
                .with_context(|| {
                    format!(
                        "{}: \"{key}\" = {} is not a number",
                        at(),
                        entry.get(key).map_or("missing".into(), |v| v.to_string())
                    )
                })
        };
        let coordinate = |key: &str| -> anyhow::Result<u32> {
            let v = number(key)?;
            if v.fract() != 0.0 || !(0.0..IMAGE_SIZE as f64).contains(&v) {
                bail!("{}: \"{key}\" = {v} must be an integer in 0..=127", at());
            }
            Ok(v as u32)
        };
        let label = Label {
            x: coordinate("x")?,
            y: coordinate("y")?,
            angle: normalize_angle(number("angle")? as f32),
        };
        clicks.entry(object.to_owned()).or_default().push(label);
    }
    Ok(clicks)
}

fn check_enough_clicks(
    clicks: &BTreeMap<String, Vec<Label>>,
    labels: &Labels,
    progress: &Progress,
    args: &LabelArgs,
    train: &[String],
) -> anyhow::Result<()> {
    for object in train {
        let needed = (args.per_object as usize).saturating_sub(labels.of(object).len());
        let left = clicks
            .get(object)
            .map_or(0, |c| c.len())
            .saturating_sub(progress.rounds_of(object) as usize);
        if left < needed {
            bail!(
                "--clicks has {left} unused clicks for {object} but {needed} more labels are needed (one click per round)",
            );
        }
    }
    Ok(())
}

/// Asks stdin for one click, showing the cursor's grasp in the preview image.
fn interactive_click(
    preview: &Path,
    object: &str,
    round: u32,
    frame: &Frame,
) -> anyhow::Result<PixelGrasp> {
    let mut cursor = PixelGrasp {
        u: IMAGE_SIZE / 2,
        v: IMAGE_SIZE / 2,
        angle_deg: 0.0,
    };
    let stdin = std::io::stdin();
    let mut lines = stdin.lock().lines();
    loop {
        let mut image = frame.to_rgb_image();
        crate::affordance::draw_grasp(&mut image, &cursor);
        let big = image::imageops::resize(&image, 512, 512, image::imageops::FilterType::Nearest);
        save_image_atomic(&big, preview)?;
        eprint!(
            "{object} round {round}: cursor ({}, {}) angle {:.1}° in {}. 'x y' moves, 'a'/'d' rotate 22.5°, 'q' or Enter grasps: ",
            cursor.u,
            cursor.v,
            cursor.angle_deg,
            preview.display()
        );
        let Some(line) = lines.next() else {
            bail!("stdin closed: labelling stopped; the labels so far are saved");
        };
        let line = line.context("reading stdin")?;
        match line.trim() {
            "" | "q" => return Ok(cursor),
            "a" => cursor.angle_deg = normalize_angle(cursor.angle_deg - ANGLE_STEP_DEG),
            "d" => cursor.angle_deg = normalize_angle(cursor.angle_deg + ANGLE_STEP_DEG),
            other => {
                let parts: Vec<&str> = other.split_whitespace().collect();
                match parts.as_slice() {
                    [x, y] => match (x.parse::<u32>(), y.parse::<u32>()) {
                        (Ok(x), Ok(y)) if x < IMAGE_SIZE && y < IMAGE_SIZE => {
                            cursor.u = x;
                            cursor.v = y;
                        }
                        _ => eprintln!("'{other}': x and y must be integers in 0..=127"),
                    },
                    _ => eprintln!("'{other}': expected 'x y', 'a', 'd', 'q' or an empty line"),
                }
            }
        }
    }
}

/// `label --check`: every problem on stdout, then exit 2 if there was any.
fn check(context: &Context, store: &LabelStore, known: &[String]) -> anyhow::Result<()> {
    let problems = store.check(known);
    for problem in &problems {
        context.say(problem);
    }
    if let Some(json) = &context.json {
        let resolved = serde_json::json!({ "global": context, "check": true });
        let results = serde_json::json!({ "labels_dir": store.dir(), "problems": problems });
        write_report(json, "label", 0, &resolved, &results)?;
    }
    if !problems.is_empty() {
        bail!(
            "{} problem(s) in {}; fix or remove the listed files, or relabel with --force",
            problems.len(),
            store.dir().display()
        );
    }
    let labels = store.load()?;
    context.say(&format!(
        "{}: {} labels for {} objects, no problems",
        store.dir().display(),
        labels.len(),
        labels.iter().count()
    ));
    Ok(())
}
