//! What each epoch of `graspmap train` writes beside the checkpoints: the loss table, the loss curve
//! and the picture of one validation image with the network's map over it.

use std::path::Path;

use anyhow::Context as _;

use crate::data::atomic::{save_image_atomic, write_atomic};
use crate::data::dataset::{training_sample, LabelledImage, TrialWeighting};
use crate::grasp::draw::{draw_gripper, JawPx};
use crate::grasp::rotate::unrotate_plane;
use crate::grasp::{bin_angle, IMAGE_SIZE};
use crate::model::checkpoint::EpochRecord;
use crate::vision::annotate::{caption, register_font, with_heat_legend, FONT};
use crate::vision::camera::Camera;
use crate::vision::colormap::{heat_overlay, HeatRange};

pub(super) fn write_losses_csv(path: &Path, history: &[EpochRecord]) -> anyhow::Result<()> {
    let mut text = String::from("epoch,train_loss,val_loss,lr,seconds\n");
    for r in history {
        text.push_str(&format!(
            "{},{:.8},{:.8},{:e},{:.3}\n",
            r.epoch, r.train_loss, r.val_loss, r.lr, r.seconds
        ));
    }
    write_atomic(path, text.as_bytes()).with_context(|| format!("writing {}", path.display()))
}

/// Train and validation loss against epoch (log scale), 800 × 500.
pub(super) fn save_loss_curve(path: &Path, history: &[EpochRecord]) -> anyhow::Result<()> {
    use plotters::prelude::*;
    // plotters draws text with ab_glyph from a font we ship: no system fonts needed.
    register_font();
    let (width, height) = (800u32, 500u32);
    let mut buffer = vec![0u8; (width * height * 3) as usize];
    {
        let area = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        area.fill(&WHITE)?;
        let losses = history
            .iter()
            .flat_map(|r| [r.train_loss, r.val_loss])
            .filter(|l| l.is_finite() && *l > 0.0);
        let (lo, hi) = losses.fold((f64::MAX, f64::MIN), |(lo, hi), l| (lo.min(l), hi.max(l)));
        let (lo, hi) = if lo <= hi {
            (lo * 0.8, hi * 1.25)
        } else {
            (1e-4, 1.0)
        };
        let epochs = history.len().max(2) as u32;
        let mut chart = ChartBuilder::on(&area)
            .caption("graspmap train: BCE loss", (FONT, 22))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(1u32..epochs, (lo..hi).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("epoch")
            .y_desc("loss")
            .label_style((FONT, 14))
            .draw()?;
        for (name, color, value) in [
            (
                "train",
                BLUE,
                (|r: &EpochRecord| r.train_loss) as fn(&EpochRecord) -> f64,
            ),
            ("validation", RED, |r: &EpochRecord| r.val_loss),
        ] {
            chart
                .draw_series(LineSeries::new(
                    history.iter().map(|r| (r.epoch, value(r))),
                    color.stroke_width(2),
                ))?
                .label(name)
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font((FONT, 14))
            .draw()?;
        area.present()?;
    }
    let image = image::RgbImage::from_raw(width, height, buffer)
        .context("the plot buffer has the image's size")?;
    save_image_atomic(&image, path)
}

/// The picture of one fixed validation image, 768 × 278: the image with its label drawn as the
/// gripper, then the network's map for the label's angle and the training target, each as heat
/// over the image in the image's own frame, all at twice the camera's size. The prediction is
/// coloured over its own range (the colour bar states it), the target over 0–1. `prediction`
/// is the network's map of the image as validation scored it, in the label's rotated frame.
pub(super) fn save_training_vis(
    prediction: &[f32],
    item: &LabelledImage,
    dir: &Path,
    epoch: u32,
) -> anyhow::Result<()> {
    const SCALE: u32 = 2;
    let sample = training_sample(item, TrialWeighting::default(), None);
    let size = IMAGE_SIZE;
    let angle = bin_angle(sample.bin);
    let prediction = unrotate_plane(prediction, size, angle);
    let target = unrotate_plane(&sample.target, size, angle);
    let range = HeatRange::of(prediction.iter().copied());
    let fixed = HeatRange { lo: 0.0, hi: 1.0 };
    let mut input = image::imageops::resize(
        &item.image,
        size * SCALE,
        size * SCALE,
        image::imageops::FilterType::Nearest,
    );
    let g = item.grasp;
    let centre = [g.u as f32 + 0.5, g.v as f32 + 0.5].map(|c| c * SCALE as f32);
    if let Some(jaw) = JawPx::at_floor(&Camera::top_down()) {
        draw_gripper(&mut input, centre, g.angle_deg, jaw.scaled(SCALE as f32));
    }
    let panels = [
        (input, format!("{} #{}: the label", item.object, item.k)),
        (
            heat_overlay(&item.image, &prediction, range, SCALE),
            format!("prediction at {angle}°"),
        ),
        (
            heat_overlay(&item.image, &target, fixed, SCALE),
            "target (0–1)".to_owned(),
        ),
    ];
    let side = size * SCALE;
    let mut image = image::RgbImage::new(3 * side, side);
    for (k, (mut panel, words)) in panels.into_iter().enumerate() {
        caption(&mut panel, (2, 2), &words, 12);
        image::imageops::replace(&mut image, &panel, i64::from(k as u32 * side), 0);
    }
    let image = with_heat_legend(
        &image,
        range,
        &format!("epoch {epoch}: the prediction's range"),
    );
    save_image_atomic(&image, &dir.join(format!("{epoch:03}.png")))
}
