//! The report's folded labels and training sections: the labels (counts and a few images with
//! their grasp drawn) and the training (loss curve, last training picture).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context as _;

use super::files::Files;
use super::html::{command, esc, missing};
use crate::data::labels::LabelStore;
use crate::grasp::draw::draw_grasp;
use crate::grasp::PixelGrasp;
use crate::named::counted;

/// Label images shown: the first label of this many objects.
const LABEL_IMAGES: usize = 8;
/// Label images are 128 px; shown at twice that so the drawn grasp is visible.
const LABEL_SCALE: u32 = 2;

/// Labels per object, and the first image of a few objects with its grasp.
pub(crate) fn labels_section(data_dir: &Path, files: &mut Files) -> anyhow::Result<String> {
    let mut html = String::new();
    let store = LabelStore::new(data_dir.join("labels"));
    if !store.labels_path().is_file() {
        html.push_str(&missing("No labels yet", &command(data_dir, "label")));
        return Ok(html);
    }
    let labels = store.load()?;
    let objects = labels.iter().count();
    let _ = writeln!(
        html,
        "<p>{} of {} in <code>{}</code>.</p>",
        counted(labels.len(), "label"),
        counted(objects, "object"),
        esc(&store.labels_path().display().to_string())
    );
    html.push_str("<table><tr><th>object</th><th>labels</th></tr>\n");
    for (object, list) in labels.iter() {
        let _ = writeln!(
            html,
            "<tr><td>{}</td><td class=\"num\">{}</td></tr>",
            esc(object),
            list.len()
        );
    }
    html.push_str("</table>\n<div class=\"gallery\">\n");
    let mut shown = 0;
    for (object, list) in labels.iter().take(LABEL_IMAGES) {
        let Some(&label) = list.first() else { continue };
        let path = store.image_path(object, 1);
        let Ok(image) = image::open(&path) else {
            let _ = writeln!(
                html,
                "<p class=\"missing\">{} is missing or unreadable: <code>{}</code> says more.</p>",
                esc(&path.display().to_string()),
                esc(&command(data_dir, "label --check"))
            );
            continue;
        };
        let mut image = image.into_rgb8();
        let grasp = PixelGrasp::from(label);
        draw_grasp(&mut image, &grasp);
        let (w, h) = image.dimensions();
        let image = image::imageops::resize(
            &image,
            w * LABEL_SCALE,
            h * LABEL_SCALE,
            image::imageops::FilterType::Nearest,
        );
        let link = files.image(&image, &format!("labels/{object}_1.png"))?;
        let _ = writeln!(
            html,
            "<figure><img src=\"{}\" width=\"{}\" height=\"{}\" alt=\"{}\"><figcaption>{} #1: ({}, {}) at {}°</figcaption></figure>",
            esc(&link),
            image.width(),
            image.height(),
            esc(object),
            esc(object),
            label.x,
            label.y,
            label.angle
        );
        shown += 1;
    }
    html.push_str("</div>\n");
    if objects > shown {
        let _ = writeln!(
            html,
            "<p class=\"note\">The first label of {shown} of the {objects} objects.</p>"
        );
    }
    Ok(html)
}

/// The loss curve and the last training picture.
pub(crate) fn training_section(data_dir: &Path, files: &mut Files) -> anyhow::Result<String> {
    let mut html = String::new();
    let affordance = data_dir.join("affordance");
    let csv = affordance.join("losses.csv");
    if !csv.is_file() {
        html.push_str(&missing(
            "No model yet",
            &command(data_dir, "train --epochs 30"),
        ));
        return Ok(html);
    }
    html.push_str(&loss_summary(&csv, data_dir)?);
    let png = affordance.join("losses.png");
    if png.is_file() {
        let link = files.copy(&png, "losses.png")?;
        let _ = writeln!(
            html,
            "<figure><img src=\"{}\" width=\"800\" height=\"500\" alt=\"training and validation loss\"><figcaption>Training and validation loss per epoch (losses.png).</figcaption></figure>",
            esc(&link)
        );
    }
    if let Some((epoch, path)) = last_training_vis(&affordance.join("training_vis")) {
        let link = files.copy(&path, &format!("training_vis_{epoch:03}.png"))?;
        let _ = writeln!(
            html,
            "<figure><img class=\"training\" src=\"{}\" alt=\"training picture\"><figcaption>Epoch {epoch}, one validation image: its label drawn as the gripper | the network's map for the label's angle, as heat over the image (its own range, on the colour bar) | the training target (0–1).</figcaption></figure>",
            esc(&link)
        );
    }
    Ok(html)
}

/// Epochs, last losses and the best validation loss, from losses.csv.
fn loss_summary(csv: &Path, data_dir: &Path) -> anyhow::Result<String> {
    let text =
        std::fs::read_to_string(csv).with_context(|| format!("reading {}", csv.display()))?;
    let bad = || {
        format!(
            "{} is not a losses file of graspmap train (delete it, or train again with `graspmap train`)",
            csv.display()
        )
    };
    let mut rows = Vec::new();
    for line in text.lines().skip(1).filter(|l| !l.trim().is_empty()) {
        let fields: Vec<&str> = line.split(',').collect();
        let [epoch, train, val, ..] = fields.as_slice() else {
            anyhow::bail!("{}", bad());
        };
        let parse = |s: &str| s.trim().parse::<f64>().ok();
        let (Some(epoch), Some(train), Some(val)) = (parse(epoch), parse(train), parse(val)) else {
            anyhow::bail!("{}", bad());
        };
        rows.push((epoch, train, val));
    }
    let Some(&(last, train, val)) = rows.last() else {
        return Ok(missing(
            "losses.csv has no epoch yet",
            &command(data_dir, "train --epochs 30"),
        ));
    };
    let best = rows
        .iter()
        .copied()
        .min_by(|a, b| a.2.total_cmp(&b.2))
        .unwrap_or((last, train, val));
    Ok(format!(
        "<p>Trained {last} epoch{}. Last: training loss {train:.4}, validation loss {val:.4}. Best validation loss {:.4} at epoch {} (best.safetensors).</p>\n",
        plural(last as usize),
        best.2,
        best.0
    ))
}

/// The highest-numbered `NNN.png` in training_vis/.
fn last_training_vis(dir: &Path) -> Option<(u32, std::path::PathBuf)> {
    std::fs::read_dir(dir)
        .ok()?
        .filter_map(Result::ok)
        .filter_map(|e| {
            let path = e.path();
            let epoch = path
                .file_name()?
                .to_str()?
                .strip_suffix(".png")?
                .parse()
                .ok()?;
            Some((epoch, path))
        })
        .max_by_key(|(epoch, _)| *epoch)
}

/// "s" unless there is exactly one.
fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}
