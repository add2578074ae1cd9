//! What each epoch of `graspmap train` writes beside the checkpoints: the loss table, the loss curve and the visualisation of one validation image.

use std::path::Path;

use anyhow::Context as _;

use crate::data::atomic::{save_image_atomic, write_atomic};
use crate::data::dataset::{training_sample, LabelledImage, TrialWeighting};
use crate::grasp::IMAGE_SIZE;
use crate::model::checkpoint::EpochRecord;
use crate::model::train::predict_map;
use crate::model::unet::{MiniUNet, Precision};
use crate::vision::colormap::viridis;

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
    static FONT: std::sync::Once = std::sync::Once::new();
    // plotters draws text with ab_glyph from a font we ship: no system fonts needed.
    FONT.call_once(|| {
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
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
            .caption("graspmap train: BCE loss", ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(1u32..epochs, (lo..hi).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("epoch")
            .y_desc("loss")
            .label_style(("sans-serif", 14))
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
            .label_font(("sans-serif", 14))
            .draw()?;
        area.present()?;
    }
    let image = image::RgbImage::from_raw(width, height, buffer)
        .context("the plot buffer has the image's size")?;
    save_image_atomic(&image, path)
}

/// input | prediction | target, 384 × 128, for one fixed validation image.
pub(super) fn save_training_vis(
    net: &MiniUNet,
    item: &LabelledImage,
    dir: &Path,
    epoch: u32,
    precision: Precision,
) -> anyhow::Result<()> {
    let sample = training_sample(item, TrialWeighting::default(), None);
    let prediction = predict_map(net, &sample, precision);
    let size = IMAGE_SIZE;
    let mut image = image::RgbImage::new(size * 3, size);
    for y in 0..size {
        for x in 0..size {
            let i = (y * size + x) as usize;
            let plane = (size * size) as usize;
            let rgb = [0, 1, 2].map(|c| (sample.input[c * plane + i] * 255.0).round() as u8);
            image.put_pixel(x, y, image::Rgb(rgb));
            image.put_pixel(size + x, y, image::Rgb(viridis(prediction[i])));
            image.put_pixel(2 * size + x, y, image::Rgb(viridis(sample.target[i])));
        }
    }
    save_image_atomic(&image, &dir.join(format!("{epoch:03}.png")))
}
