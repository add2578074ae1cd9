//! `graspmap predict`: the trained model's best grasp on a user's 128 × 128 image, with the picture of
//! its 8 maps over the image (model::picture).

use std::path::{Path, PathBuf};

use anyhow::bail;
use image::RgbImage;

use super::Context;
use crate::data::atomic::save_image_atomic;
use crate::data::input::{read_depth_png, InputKind, NetInput};
use crate::data::observation::read_observation;
use crate::data::output::check_output_file;
use crate::grasp::draw::JawPx;
use crate::model::inference::AffordanceModel;
use crate::model::maps::Choice;
use crate::model::picture::affordance_picture;
use crate::model::unet::Precision;
use crate::present::envelope::write_report;
use crate::vision::camera::Camera;

/// What `graspmap predict` reads and writes, resolved by the CLI.
#[derive(Debug, Clone)]
pub(crate) struct PredictConfig {
    /// A 128 × 128 RGB image (PNG or JPEG).
    pub(crate) image: PathBuf,
    /// Its depth image (16-bit millimetres), which an rgbd model needs.
    pub(crate) depth: Option<PathBuf>,
    /// The model's weights.
    pub(crate) checkpoint: PathBuf,
    /// Where the picture of the maps goes.
    pub(crate) out: PathBuf,
    /// Arithmetic of the network.
    pub(crate) precision: Precision,
}

/// Everything `predict --json` reports.
#[derive(Debug, serde::Serialize)]
pub(crate) struct PredictResults {
    /// The input image.
    pub(crate) image: std::path::PathBuf,
    /// Grasp centre column in the input image.
    pub(crate) x: u32,
    /// Grasp centre row.
    pub(crate) y: u32,
    /// Grasp angle in degrees (clockwise, a multiple of 22.5).
    pub(crate) angle: f32,
    /// Affordance at the chosen pixel, in [0, 1].
    pub(crate) score: f32,
    /// The full choice (bin and rotated pixel).
    pub(crate) choice: Choice,
    /// Where the visualisation went.
    pub(crate) vis: std::path::PathBuf,
    /// Wall seconds of the network (8 rotations, one batch).
    pub(crate) network_seconds: f64,
}

/// Runs the command.
pub(crate) fn run(context: &Context, args: PredictConfig) -> anyhow::Result<()> {
    check_output_file(&args.out, "--out")?;
    let image = read_observation(&args.image)?;
    let checkpoint = &args.checkpoint;
    crate::model::use_threads(context.threads);
    let precision = args.precision;
    let model = AffordanceModel::load(checkpoint, precision)?;
    let input = observation_input(&model, checkpoint, image, args.depth.as_deref())?;
    let start = std::time::Instant::now();
    let maps = model.score(&input)?;
    let choice = maps.choose();
    let network_seconds = start.elapsed().as_secs_f64();
    let out = args.out.clone();
    // The image is taken to come from the workcell's camera: the gripper is drawn to its scale.
    let jaw = JawPx::at_floor(&Camera::top_down()).expect("the top-down camera sees the floor");
    save_image_atomic(&affordance_picture(&input.rgb, &maps, &choice, jaw), &out)?;
    let g = choice.grasp;
    context.say(&format!(
        "grasp x {} y {} angle {:.1}° score {:.3} (wrote {})",
        g.u,
        g.v,
        g.angle_deg,
        choice.score,
        out.display()
    ));
    if let Some(json) = &context.json {
        let results = PredictResults {
            image: args.image.clone(),
            x: g.u,
            y: g.v,
            angle: g.angle_deg,
            score: choice.score,
            choice,
            vis: out.clone(),
            network_seconds,
        };
        let resolved = serde_json::json!({
            "global": context,
            "checkpoint": checkpoint,
            "precision": precision,
            "image": args.image,
            "depth": args.depth,
            "out": out,
        });
        write_report(json, "predict", 0, &resolved, &results)?;
    }
    Ok(())
}

/// The model's input for the image: with an rgbd model, the height plane from `--depth`,
/// which must then be given.
fn observation_input(
    model: &AffordanceModel,
    checkpoint: &Path,
    image: RgbImage,
    depth: Option<&Path>,
) -> anyhow::Result<NetInput> {
    match (model.input(), depth) {
        (InputKind::Rgb, None) => Ok(NetInput::rgb(image)),
        (InputKind::Rgb, Some(path)) => bail!(
            "--depth {}: {} is an rgb model, which reads no depth; leave --depth out",
            path.display(),
            checkpoint.display()
        ),
        (InputKind::Rgbd, None) => bail!(
            "{} is an rgbd model: give the image's depth with --depth PNG (16-bit millimetres, \
             as `graspmap scene --depth` writes it)",
            checkpoint.display()
        ),
        (InputKind::Rgbd, Some(path)) => {
            let depth = read_depth_png(path)?;
            Ok(NetInput::new(InputKind::Rgbd, image, Some(&depth)))
        }
    }
}
