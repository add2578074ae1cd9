//! Where a labelling round's click comes from: the scripted planner (with human-like noise), a
//! clicks file, or a person at stdin.

use std::collections::BTreeMap;
use std::io::BufRead;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::config::LabelConfig;
use crate::data::atomic::save_image_atomic;
use crate::data::labels::{Label, Labels};
use crate::data::progress::Progress;
use crate::grasp::draw::draw_grasp;
use crate::grasp::{normalize_angle, PixelGrasp, BIN_DEG, IMAGE_SIZE};
use crate::policy::oracle;
use crate::policy::verify::CheckConfig;
use crate::vision::camera::Camera;
use crate::vision::render::Frame;

/// The angle step a person gets with the A/D keys: one angle bin.
pub(crate) const ANGLE_STEP_DEG: f32 = BIN_DEG;

/// Where clicks come from.
pub(super) enum Clicker {
    /// The oracle planner, with optional human-like noise.
    Scripted { noise_px: f32, noise_deg: f32 },
    /// A list from a file, per object in order.
    File {
        clicks: BTreeMap<String, Vec<Label>>,
    },
    /// A person (or a script) at stdin, looking at a preview image.
    Interactive { preview: PathBuf },
    /// A person at the labelling page, which the server shows.
    Web {
        server: Box<crate::present::web::WebServer>,
        session: Box<crate::present::web::session::LabelSession>,
    },
}

impl Clicker {
    pub(super) fn name(&self) -> &'static str {
        match self {
            Clicker::Scripted { .. } => "scripted",
            Clicker::File { .. } => "file",
            Clicker::Interactive { .. } => "interactive",
            Clicker::Web { .. } => "web",
        }
    }

    /// The click for one round, or why there is none (the round then fails). The scripted
    /// clicker plans on the round's object, mask id `id`; people may click any object.
    pub(super) fn click(
        &self,
        object: &str,
        id: u16,
        round: u32,
        round_seed: u64,
        camera: &Camera,
        frame: &Frame,
    ) -> anyhow::Result<Result<PixelGrasp, String>> {
        match self {
            Clicker::Scripted {
                noise_px,
                noise_deg,
            } => {
                // A person clicks in 22.5° steps; plan in those steps too.
                let config = CheckConfig::with_angles((180.0 / ANGLE_STEP_DEG) as u32);
                let plan = match oracle::plan(camera, frame, id, &config) {
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
            Clicker::Web { session, .. } => session
                .await_click(object, round, &frame.to_rgb_image())
                .map(Ok),
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

pub(super) fn check_enough_clicks(
    clicks: &BTreeMap<String, Vec<Label>>,
    labels: &Labels,
    progress: &Progress,
    args: &LabelConfig,
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
        draw_grasp(&mut image, &cursor);
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
