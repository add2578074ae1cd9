//! `graspmap grasp`: one simulated pick attempt on one dropped object, from a given, oracle or random grasp.

use std::time::Instant;

use anyhow::Context as _;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rapier3d::math::Vector;

use super::Context;
use crate::affordance::draw_grasp;
use crate::camera::Camera;
use crate::cli::{parse_pixel, GraspArgs};
use crate::grasp::{normalize_angle, world_grasp, PixelGrasp};
use crate::oracle::{self, OracleConfig};
use crate::output::{save_gif_atomic, save_image_atomic, write_report};
use crate::sim::pick::{PickOutcome, PickReason};
use crate::sim::{Workcell, WorkcellConfig, BIN1_CENTER, BIN_FLOOR_TOP, BIN_INNER_HALF};

/// How the grasp was chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GraspSource {
    /// --pixel/--angle.
    Given,
    /// --oracle.
    Oracle,
    /// --random.
    Random,
}

/// Everything `grasp --json` reports.
#[derive(Debug, serde::Serialize)]
pub struct GraspResults {
    /// Whether the object was picked and placed.
    pub success: bool,
    /// Why the attempt ended so.
    pub reason: PickReason,
    /// Human-readable detail.
    pub detail: String,
    /// The dropped object.
    pub object: String,
    /// Grasp pixel [u, v], absent when the oracle found none.
    pub pixel: Option<[u32; 2]>,
    /// Grasp angle in degrees.
    pub angle_deg: Option<f32>,
    /// How the grasp was chosen.
    pub source: GraspSource,
    /// Wall-clock seconds, drop to placed.
    pub wall_seconds: f64,
    /// Simulated seconds, drop to placed.
    pub sim_seconds: f64,
    /// Wall seconds spent rendering the camera image.
    pub render_seconds: f64,
}

/// Runs the command.
pub fn run(context: &Context, args: GraspArgs) -> anyhow::Result<()> {
    let given = match (&args.pixel, args.angle) {
        (Some(pixel), Some(angle)) => {
            if !angle.is_finite() {
                anyhow::bail!("--angle {angle} must be a finite number of degrees");
            }
            let (u, v) = parse_pixel(pixel)?;
            Some(PixelGrasp {
                u,
                v,
                angle_deg: normalize_angle(angle),
            })
        }
        _ => None,
    };
    if !(args.grip_force > 0.0 && args.grip_force.is_finite()) {
        anyhow::bail!(
            "--grip-force {} must be a positive number of newtons",
            args.grip_force
        );
    }
    let start = Instant::now();
    let model = context.library().load(&args.object)?;
    let config = WorkcellConfig {
        grip_force: args.grip_force,
        ..WorkcellConfig::default()
    };
    let mut cell = Workcell::new(context.assets(), &config)?;
    cell.drop_objects(std::slice::from_ref(&model), args.seed)?;
    let render_start = Instant::now();
    let frame = cell.capture();
    let render_seconds = render_start.elapsed().as_secs_f64();
    let camera = Camera::top_down();

    let (source, choice) = if let Some(g) = given {
        (GraspSource::Given, Ok(g))
    } else if args.oracle {
        let plan = oracle::plan(
            &camera,
            &frame,
            cell.objects()[0].id,
            &OracleConfig::default(),
        );
        (
            GraspSource::Oracle,
            plan.map(|p| p.grasp).map_err(|e| e.to_string()),
        )
    } else {
        (GraspSource::Random, Ok(random_grasp(&camera, args.seed)))
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
        cell.start_recording(record_camera(), RECORD_EVERY_STEPS);
    }
    let outcome = match &choice {
        Ok(g) => cell.pick(&world_grasp(&camera, &frame, *g)),
        Err(why) => PickOutcome::failure(PickReason::Ungraspable, why.clone()),
    };
    if let Some(path) = &args.record {
        let frames = cell.take_recording();
        save_gif_atomic(&frames, RECORD_DELAY_CS, path)
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
            "oracle": OracleConfig::default(),
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
        r.reason.as_str(),
        r.detail,
        r.sim_seconds,
        r.wall_seconds
    )
}

/// A uniformly random point of bin 1's floor, seen through the camera, and a uniform angle.
pub fn random_grasp(camera: &Camera, seed: u64) -> PixelGrasp {
    // A separate stream from the drop, so the same seed does not correlate the two.
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(1);
    loop {
        let point = Vector::new(
            BIN1_CENTER.x + rng.random_range(-BIN_INNER_HALF[0]..=BIN_INNER_HALF[0]),
            BIN1_CENTER.y + rng.random_range(-BIN_INNER_HALF[1]..=BIN_INNER_HALF[1]),
            BIN_FLOOR_TOP,
        );
        let angle_deg = normalize_angle(rng.random_range(0.0..180.0));
        if let Some([u, v, _]) = camera.project(point) {
            if (0.0..128.0).contains(&u) && (0.0..128.0).contains(&v) {
                return PixelGrasp {
                    u: u as u32,
                    v: v as u32,
                    angle_deg,
                };
            }
        }
    }
}

/// The oblique view of the whole workcell used by `--record`.
pub fn record_camera() -> Camera {
    Camera::look_at(
        Vector::new(1.35, -1.25, 1.25),
        Vector::new(0.0, 0.0, 0.25),
        Vector::Z,
        45.0,
        320,
        240,
    )
}

/// Physics steps between recorded frames (240 Hz / 10 = 24 fps).
pub const RECORD_EVERY_STEPS: u64 = 10;
/// GIF frame delay in hundredths of a second, matching `RECORD_EVERY_STEPS`.
pub const RECORD_DELAY_CS: u32 = 4;
