//! `graspmap label`: collect grasp labels round by round, each verified by a simulated pick, resumable after any interruption.

mod backfill;
mod clicks;
mod config;
mod rounds;
mod store;
mod waves;
mod web;

use std::sync::Mutex;
use std::time::Instant;

use anyhow::{bail, Context as _};

use super::Context;
use crate::data::clicks::read_clicks;
use crate::data::labels::{Label, LabelStore, Labels};
use crate::data::lock::StoreLock;
use crate::data::output::check_output_dir;
use crate::data::progress::Progress;
use crate::grasp::world::world_grasp;
use crate::grasp::PixelGrasp;
use crate::interrupt;
use crate::metrics::FailureTally;
use crate::named::{counted, Named};
use crate::present::envelope::write_report;
use crate::present::web::session::{pad_width_px, AttemptView, LabelSession, FILM_EVERY_STEPS};
use crate::present::web::WebServer;
use crate::sim::pick::PickReason;
use crate::vision::render::Frame;
use clicks::Clicker;
pub(crate) use config::{ClickNoise, ClickSource, LabelConfig};
use store::{check, delete, prepare, writes_depth};

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
    failures: FailureTally,
    /// Labels of this run whose pick carried another object than the round's (clutter only):
    /// stored under the round's object all the same (docs/data.md, "Clutter rounds").
    lifted_other: usize,
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
pub(crate) fn run(context: &Context, args: LabelConfig) -> anyhow::Result<()> {
    let store = LabelStore::new(context.data.join("labels"));
    if args.check {
        return check(context, &store, &context.objects.names());
    }
    if args.backfill_depth {
        return backfill::backfill_depth(context, &store).map(|_| ());
    }
    check_output_dir(store.dir(), "the labels folder")?;
    let _writer = StoreLock::acquire(store.dir(), "label")?;
    if let Some((object, k)) = &args.delete {
        return delete(context, &store, object, *k);
    }
    label(context, &args, &store)
}

/// Labels the training objects until each has its labels, with the store's lock held.
fn label(context: &Context, args: &LabelConfig, store: &LabelStore) -> anyhow::Result<()> {
    let split = context.split()?;
    check_clutter(args.clutter, &split.train)?;
    // The last round's seed is the largest: when it fits, every round's does.
    let last = split.train.len().saturating_sub(1);
    rounds::round_seed(args.seed, last, args.max_rounds - 1).context("--seed")?;
    let models = context.objects.load_all(&split.train)?;
    let clicker = clicker(args, &split.train, &split.test)?;
    if let Clicker::Web { server, .. } = &clicker {
        context.say(&format!(
            "labelling page at {} (open it in a browser; Ctrl-C stops the server)",
            server.url()
        ));
    }

    let (labels, progress) = prepare(store, args, &clicker, &split.train)?;

    let start = Instant::now();
    // A person at the prompt, or at the page, needs a quiet terminal and one round at a time.
    let by_hand = matches!(clicker, Clicker::Interactive { .. } | Clicker::Web { .. });
    let bar = if by_hand {
        indicatif::ProgressBar::hidden()
    } else {
        context.progress_bar(
            "labels",
            args.per_object as u64 * split.train.len() as u64,
            labels_in(&labels, &split.train, args.per_object),
        )
    };
    let job = ObjectJob {
        context,
        args,
        store,
        write_depth: writes_depth(store, &labels),
        clicker: &clicker,
        bar: &bar,
        verbose_rounds: !matches!(clicker, Clicker::Scripted { .. }),
    };
    let workers = if by_hand {
        1
    } else {
        usize::from(context.threads)
    };
    let shared = Mutex::new(Shared { labels, progress });
    let finished = |summaries: &[ObjectSummary]| {
        finish(
            context,
            args,
            &clicker,
            store,
            &split.train,
            summaries,
            start,
        )
    };
    let outcome = match &clicker {
        Clicker::Web { server, session } => {
            job.label_with_page(&split.train, &models, &shared, (server, session), &finished)
        }
        _ => job.label_all(&split.train, &models, &shared, workers),
    };
    bar.finish_and_clear();
    if let Some(interrupted) = interrupt::requested() {
        let state = lock(&shared);
        return stopped(
            context,
            args,
            &clicker,
            store,
            &split.train,
            &state.labels,
            interrupted,
        );
    }
    finished(&outcome?)
}

/// What a signal leaves: a complete dataset when the labels page had finished it (its server
/// stopped), else the labels so far and how to continue.
fn stopped(
    context: &Context,
    args: &LabelConfig,
    clicker: &Clicker,
    store: &LabelStore,
    train: &[String],
    labels: &Labels,
    interrupted: interrupt::Interrupted,
) -> anyhow::Result<()> {
    let kept = labels.len();
    let wanted = args.per_object as u64 * train.len() as u64;
    if matches!(clicker, Clicker::Web { .. }) && labels_in(labels, train, args.per_object) == wanted
    {
        context.say(&format!(
            "server stopped; {} in {}, complete",
            counted(kept, "label"),
            store.dir().display()
        ));
        return Ok(());
    }
    context.stopped(&format!(
        "{interrupted}: {} kept in {}, each verified and saved; rerun the same command to continue",
        counted(kept, "label"),
        store.dir().display()
    ));
    Err(interrupted.into())
}

/// Prints the summary of a complete dataset and writes the JSON report.
fn finish(
    context: &Context,
    args: &LabelConfig,
    clicker: &Clicker,
    store: &LabelStore,
    train: &[String],
    summaries: &[ObjectSummary],
    start: Instant,
) -> anyhow::Result<()> {
    let results = LabelResults {
        labels_dir: store.dir().display().to_string(),
        source: clicker.name(),
        total_labels: summaries.iter().map(|s| s.labels).sum(),
        total_rounds: summaries.iter().map(|s| s.rounds).sum(),
        objects: summaries.to_vec(),
        wall_seconds: start.elapsed().as_secs_f64(),
    };
    print_summary(context, &results);
    if let Some(json) = &context.json {
        let resolved = resolved_config(context, args, clicker.name(), train);
        write_report(json, "label", args.seed, &resolved, &results)?;
    }
    Ok(())
}

/// The run's settings as the JSON report lists them.
fn resolved_config(
    context: &Context,
    args: &LabelConfig,
    source: &str,
    train: &[String],
) -> serde_json::Value {
    serde_json::json!({
        "global": context,
        "per_object": args.per_object,
        "max_rounds": args.max_rounds,
        "source": source,
        "clicks": match &args.source {
            ClickSource::File(path) => Some(path),
            _ => None,
        },
        "click_noise_px": args.noise.px,
        "angle_noise_deg": args.noise.deg,
        "clutter": args.clutter,
        "train": train,
    })
}

/// A round drops at most every training object once.
fn check_clutter(clutter: u32, train: &[String]) -> anyhow::Result<()> {
    if clutter as usize > train.len() {
        bail!(
            "--clutter {clutter}: the split has only {} training objects to drop (use 1 to {})",
            train.len(),
            train.len()
        );
    }
    Ok(())
}

/// Where this run's clicks come from, with a clicks file read and checked up front.
fn clicker(args: &LabelConfig, train: &[String], test: &[String]) -> anyhow::Result<Clicker> {
    Ok(match &args.source {
        ClickSource::File(path) => Clicker::File {
            clicks: read_clicks(path, train, test)?,
        },
        ClickSource::Interactive { preview } => Clicker::Interactive {
            preview: preview.clone(),
        },
        ClickSource::Scripted => Clicker::Scripted {
            noise_px: args.noise.px,
            noise_deg: args.noise.deg,
        },
        ClickSource::Web { host, port } => {
            let server = WebServer::bind(*host, *port)?;
            let session =
                LabelSession::new(pad_width_px(&crate::vision::camera::Camera::top_down()));
            Clicker::Web {
                server: Box::new(server),
                session: Box::new(session),
            }
        }
    })
}

/// What a clicked grasp did in the simulator: its reason, detail, the object it carried, and
/// (for the page) the oblique view's frames.
type Tried = (PickReason, String, Option<String>, Vec<image::RgbImage>);

/// A round of one object, done: what [`ObjectJob::record_round`] stores.
struct RoundDone<'a> {
    object: &'a str,
    /// The object's rounds, this one included.
    rounds: u32,
    frame: &'a Frame,
    click: &'a Result<PixelGrasp, String>,
    tried: Tried,
}

/// Dataset state shared by the workers (and the labels page, under `--web`).
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
    args: &'a LabelConfig,
    store: &'a LabelStore,
    /// Store each label's depth image beside it (every dataset but an older one without them).
    write_depth: bool,
    clicker: &'a Clicker,
    bar: &'a indicatif::ProgressBar,
    verbose_rounds: bool,
}

impl ObjectJob<'_> {
    /// Stores a round's outcome under the dataset's lock: the label when the click succeeded,
    /// the rounds and sources in the progress file, and the attempt for the labels page.
    fn record_round(
        &self,
        shared: &Mutex<Shared>,
        done: RoundDone,
        summary: &mut ObjectSummary,
    ) -> anyhow::Result<()> {
        let RoundDone {
            object,
            rounds,
            frame,
            click,
            tried: (reason, detail, lifted, film),
        } = done;
        let mut state = lock(shared);
        let Shared { labels, progress } = &mut *state;
        let stored = matches!((reason, click), (PickReason::Success, Ok(_)));
        if let (true, Ok(grasp)) = (stored, click) {
            // The round's object, whichever object the pick carried: the label is a grasp that
            // worked in this round's image (docs/data.md, "Clutter rounds").
            let depth = self.write_depth.then(|| frame.to_depth_image_mm());
            self.store.append(
                labels,
                object,
                Label::from(*grasp),
                &frame.to_rgb_image(),
                depth.as_ref(),
            )?;
            summary.new_labels += 1;
            summary.lifted_other += usize::from(lifted.as_deref() != Some(object));
            self.bar.inc(1);
        } else {
            summary.failures.add(reason.name());
        }
        let have = labels.of(object).len();
        progress.set_rounds(object, rounds, have as u32);
        progress.record_sources(object, self.clicker.name());
        self.store.save_progress(progress)?;
        if let Clicker::Web { session, .. } = self.clicker {
            session.finish_attempt(AttemptView {
                object: object.to_owned(),
                round: rounds - 1,
                grasp: click.as_ref().ok().copied(),
                reason: reason.name().to_owned(),
                detail,
                stored,
                frames: film,
            })?;
        }
        Ok(())
    }

    /// Runs the clicked grasp in the simulator: its reason, detail, the object it carried, and
    /// (for the page) the oblique view's frames.
    fn try_click(
        &self,
        cell: &mut crate::sim::Workcell,
        frame: &Frame,
        click: &Result<PixelGrasp, String>,
    ) -> Tried {
        let Ok(grasp) = click else {
            let why = click.as_ref().err().cloned().unwrap_or_default();
            return (PickReason::Ungraspable, why, None, Vec::new());
        };
        let filmed = matches!(self.clicker, Clicker::Web { .. });
        if filmed {
            cell.start_recording(FILM_EVERY_STEPS);
        }
        let camera = *cell.camera();
        let outcome = cell.pick(&world_grasp(&camera, frame, *grasp));
        let film = if filmed {
            cell.take_recording()
        } else {
            Vec::new()
        };
        (outcome.reason, outcome.detail, outcome.object, film)
    }
}

/// The line a round prints.
fn round_line(
    object: &str,
    round: u32,
    click: &Result<crate::grasp::PixelGrasp, String>,
    reason: PickReason,
    detail: &str,
) -> String {
    match click {
        Ok(g) => format!(
            "{object} round {round} click ({}, {}, {:.1}°): {} {detail}",
            g.u,
            g.v,
            g.angle_deg,
            reason.name()
        ),
        Err(_) => format!("{object} round {round}: no click: {detail}"),
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
        context.say(&format!(
            "{:<18} {:>6} {:>6} {:>4}  {}",
            s.object,
            s.labels,
            s.rounds,
            s.new_labels,
            s.failures.describe()
        ));
    }
    context.say(&format!(
        "{} in {} in {} ({:.1} s)",
        counted(results.total_labels, "label"),
        counted(results.total_rounds as usize, "round"),
        results.labels_dir,
        results.wall_seconds
    ));
}
