//! `graspmap grasp`: one simulated pick attempt on one dropped object, from a given, oracle or random grasp.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context as _;

use super::Context;
use crate::data::atomic::save_image_atomic;
use crate::data::output::check_output_file;
use crate::grasp::draw::draw_grasp;
use crate::grasp::world::world_grasp;
use crate::grasp::PixelGrasp;
use crate::named::Named;
use crate::policy::baselines::random_grasp;
use crate::policy::oracle;
use crate::policy::verify::CheckConfig;
use crate::present::envelope::write_report;
use crate::present::video::save_video_atomic;
use crate::sim::pick::{PickOutcome, PickReason};
use crate::sim::{Workcell, WorkcellConfig};

/// One `graspmap grasp` attempt, resolved by the CLI.
#[derive(Debug, Clone)]
pub(crate) struct GraspConfig {
    /// Object to drop into bin 1.
    pub(crate) object: String,
    /// Seed of the drop pose (and of the random grasp).
    pub(crate) seed: u64,
    /// Where the grasp comes from.
    pub(crate) choice: GraspChoice,
    /// The workcell (grip force).
    pub(crate) workcell: WorkcellConfig,
    /// Where to write the attempt's animated GIF.
    pub(crate) record: Option<PathBuf>,
    /// Where to save the camera image with the grasp drawn.
    pub(crate) image: Option<PathBuf>,
}

/// Who picks the grasp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum GraspChoice {
    /// The user's pixel and angle.
    Given(PixelGrasp),
    /// The planner, from mask and depth.
    Oracle,
    /// A random point of bin 1's floor.
    Random,
}

/// How the grasp was chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum GraspSource {
    /// --pixel/--angle.
    Given,
    /// --oracle.
    Oracle,
    /// --random.
    Random,
}

/// Everything `grasp --json` reports.
#[derive(Debug, serde::Serialize)]
pub(crate) struct GraspResults {
    /// Whether the object was picked and placed.
    pub(crate) success: bool,
    /// Why the attempt ended so.
    pub(crate) reason: PickReason,
    /// Human-readable detail.
    pub(crate) detail: String,
    /// The dropped object.
    pub(crate) object: String,
    /// Grasp pixel [u, v], absent when the oracle found none.
    pub(crate) pixel: Option<[u32; 2]>,
    /// Grasp angle in degrees.
    pub(crate) angle_deg: Option<f32>,
    /// How the grasp was chosen.
    pub(crate) source: GraspSource,
    /// Wall-clock seconds, drop to placed.
    pub(crate) wall_seconds: f64,
    /// Simulated seconds, drop to placed.
    pub(crate) sim_seconds: f64,
    /// Wall seconds spent rendering the camera image.
    pub(crate) render_seconds: f64,
}

/// Runs the command.
pub(crate) fn run(context: &Context, args: GraspConfig) -> anyhow::Result<()> {
    let start = Instant::now();
    for (path, what) in [(&args.record, "--record"), (&args.image, "--image")] {
        if let Some(path) = path {
            check_output_file(path, what)?;
        }
    }
    let model = context.objects.load(&args.object)?;
    let config = args.workcell.clone();
    let mut cell = Workcell::new(&config)?;
    cell.drop_objects(std::slice::from_ref(&model), args.seed)?;
    let render_start = Instant::now();
    let frame = cell.capture();
    let render_seconds = render_start.elapsed().as_secs_f64();
    let camera = *cell.camera();

    let (source, choice) = match args.choice {
        GraspChoice::Given(g) => (GraspSource::Given, Ok(g)),
        GraspChoice::Oracle => {
            let plan = oracle::plan(
                &camera,
                &frame,
                cell.objects()[0].id,
                &CheckConfig::default(),
            );
            (
                GraspSource::Oracle,
                plan.map(|p| p.grasp).map_err(|e| e.to_string()),
            )
        }
        GraspChoice::Random => (GraspSource::Random, Ok(random_grasp(&camera, args.seed))),
    };
    if let Some(path) = &args.image {
        let mut image = frame.to_rgb_image();
        if let Ok(g) = &choice {
            draw_grasp(&mut image, g);
        }
        save_image_atomic(&image, path)
            .with_context(|| format!("writing --image {}", path.display()))?;
    }
    if args.record.is_some() {
        cell.start_recording(RECORD_EVERY_STEPS);
    }
    let outcome = match &choice {
        Ok(g) => cell.pick(&world_grasp(&camera, &frame, *g)),
        Err(why) => PickOutcome::failure(PickReason::Ungraspable, why.clone()),
    };
    if let Some(path) = &args.record {
        let frames = cell.take_recording();
        save_video_atomic(&frames, RECORD_EVERY_STEPS, path)
            .with_context(|| format!("writing --record {}", path.display()))?;
    }
    let results = GraspResults {
        success: outcome.success,
        reason: outcome.reason,
        detail: outcome.detail.clone(),
        object: model.name.clone(),
        pixel: choice.as_ref().ok().map(|g| [g.u, g.v]),
        angle_deg: choice.as_ref().ok().map(|g| g.angle_deg),
        source,
        wall_seconds: start.elapsed().as_secs_f64(),
        sim_seconds: cell.time(),
        render_seconds,
    };
    context.say(&result_line(&results, args.seed));
    if let Some(json) = &context.json {
        let resolved = serde_json::json!({
            "global": context,
            "workcell": config,
            "oracle": CheckConfig::default(),
            "object": args.object,
            "source": source,
            "record": args.record,
        });
        write_report(json, "grasp", args.seed, &resolved, &results)?;
    }
    Ok(())
}

fn result_line(r: &GraspResults, seed: u64) -> String {
    let grasp = match (r.pixel, r.angle_deg) {
        (Some([u, v]), Some(a)) => format!("pixel ({u}, {v}) angle {a:.1}°"),
        _ => "no grasp".to_owned(),
    };
    format!(
        "{} seed {seed}: {} [{}] {grasp}: {} (sim {:.2} s, wall {:.2} s)",
        r.object,
        if r.success { "success" } else { "failure" },
        r.reason.name(),
        r.detail,
        r.sim_seconds,
        r.wall_seconds
    )
}

/// Physics steps between recorded frames (240 Hz / 10 = 24 fps).
pub(crate) const RECORD_EVERY_STEPS: u64 = 10;
