//! `graspmap predict`: the trained model's best grasp on a user's 128 × 128 image, with the 8-rotation visualisation.

use std::path::Path;

use anyhow::{bail, Context as _};
use image::RgbImage;

use super::eval::checkpoint_path;
use super::Context;
use crate::affordance::{rotated_observations, visualisation, Choice};
use crate::cli::PredictArgs;
use crate::inference::AffordanceModel;
use crate::labels::IMAGE_SIZE;
use crate::output::{save_image_atomic, write_report};

/// Everything `predict --json` reports.
#[derive(Debug, serde::Serialize)]
pub struct PredictResults {
    /// The input image.
    pub image: std::path::PathBuf,
    /// Grasp centre column in the input image.
    pub x: u32,
    /// Grasp centre row.
    pub y: u32,
    /// Grasp angle in degrees (clockwise, a multiple of 22.5).
    pub angle: f32,
    /// Affordance at the chosen pixel, in [0, 1].
    pub score: f32,
    /// The full choice (bin and rotated pixel).
    pub choice: Choice,
    /// Where the visualisation went.
    pub vis: std::path::PathBuf,
    /// Wall seconds of the network (8 rotations, one batch).
    pub network_seconds: f64,
}

/// Runs the command.
pub fn run(context: &Context, args: PredictArgs) -> anyhow::Result<()> {
    let image = read_observation(&args.image)?;
    let checkpoint = checkpoint_path(context, args.checkpoint.as_deref());
    tch::set_num_threads(i32::from(context.threads));
    let precision = args.precision.resolve();
    let model = AffordanceModel::load(&checkpoint, precision)?;
    let start = std::time::Instant::now();
    let rotated = rotated_observations(&image);
    let maps = model.predict(&rotated);
    let choice = maps.choose();
    let network_seconds = start.elapsed().as_secs_f64();
    let out = args.out.clone().unwrap_or_else(|| {
        let stem = args
            .image
            .file_stem()
            .map_or_else(|| "image".into(), |s| s.to_string_lossy().into_owned());
        context
            .data
            .join("affordance")
            .join("predict_vis")
            .join(format!("{stem}.png"))
    });
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    save_image_atomic(&visualisation(&rotated, &maps, &choice), &out)?;
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
            "out": out,
        });
        write_report(json, "predict", 0, &resolved, &results)?;
    }
    Ok(())
}

/// Reads a 128 × 128 8-bit RGB image (an opaque RGBA one is accepted), or says what is wrong.
pub fn read_observation(path: &Path) -> anyhow::Result<RgbImage> {
    let decoded = image::ImageReader::open(path)
        .with_context(|| format!("cannot open --image {}", path.display()))?
        .with_guessed_format()
        .with_context(|| format!("cannot read --image {}", path.display()))?
        .decode()
        .with_context(|| {
            format!(
                "--image {} is not a readable image (give a PNG or JPEG)",
                path.display()
            )
        })?;
    let (w, h) = (decoded.width(), decoded.height());
    if (w, h) != (IMAGE_SIZE, IMAGE_SIZE) {
        bail!(
            "--image {} is {w}×{h}; the model needs {IMAGE_SIZE}×{IMAGE_SIZE} top-down camera images (resize or crop it)",
            path.display()
        );
    }
    match decoded {
        image::DynamicImage::ImageRgb8(rgb) => Ok(rgb),
        image::DynamicImage::ImageRgba8(rgba) => {
            if rgba.pixels().any(|p| p.0[3] != 255) {
                bail!(
                    "--image {} has transparent pixels; save it as 8-bit RGB without alpha",
                    path.display()
                );
            }
            Ok(image::DynamicImage::ImageRgba8(rgba).into_rgb8())
        }
        other => bail!(
            "--image {} is {:?}, not 8-bit RGB; save it as 8-bit RGB",
            path.display(),
            other.color()
        ),
    }
}
