//! Training samples from labelled images: angle bins, rotation to the bin, Gaussian targets, split (docs/learning.md).
//!
//! Only [`load_dataset`] touches the disk; everything else is a pure function of loaded images and
//! an explicit seeded generator. Samples are plain `f32` arrays (CHW input, HW target) that the
//! model layer turns into tensors.

use anyhow::{bail, Context};
use image::{GrayImage, RgbImage};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::augment::{self, AugmentConfig};
use super::input::{height_from_depth_mm, read_depth_png, InputKind, NetInput};
use super::labels::LabelStore;
use crate::grasp::rotate::rotate_point;
use crate::grasp::{angle_bin, bin_angle, fingers, grasp_from_fingers, PixelGrasp, IMAGE_SIZE};

/// Standard deviation of the target Gaussian, in pixels (ref).
pub(crate) const TARGET_SIGMA_PX: f32 = 1.0;
/// How often [`training_sample`] redraws an augmentation that pushes the grasp centre out of the
/// image before it falls back to the unaugmented sample.
pub(crate) const MAX_AUGMENT_TRIES: usize = 10;

/// Side of a training crop's margin that keeps the supervised pixel this far from the crop's
/// edge: beyond the network's reach of 14 px (the crop test in model/train.rs), so the loss
/// there sees what the whole image would give it.
pub(crate) const CROP_MARGIN_PX: u32 = 16;
/// Crops start on multiples of this, the network's pooling stride (2 × 2), so a crop's pooling
/// grid is the whole image's.
pub(crate) const CROP_ALIGN_PX: u32 = 4;

/// What supervises an image: a hand-made label or a trial's outcome.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Supervision {
    /// A label: a dense Gaussian target at the grasp centre, every pixel weighted.
    Label,
    /// A trial: 1 (success) or 0 (failure) at the executed pixel of the executed rotation, and
    /// no weight anywhere else.
    Trial {
        /// Whether the grasp held.
        success: bool,
    },
}

/// How trial samples are weighted against labels (docs/learning.md, "Trials").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrialWeighting {
    /// A trial's total weight; a label's is 1, spread evenly over its pixels.
    pub(crate) weight: f32,
    /// 0: the executed pixel alone; otherwise a Gaussian window of this σ (out to 2σ) around
    /// it, its weights summing to `weight`.
    pub(crate) sigma_px: f32,
}

impl Default for TrialWeighting {
    fn default() -> Self {
        Self {
            weight: 0.01,
            sigma_px: 0.0,
        }
    }
}

/// One network example, already rotated into its angle bin.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// Rotated input, C × H × W (CHW): RGB in [0, 1], then for rgbd the height plane in [0, 1].
    pub(crate) input: Vec<f32>,
    /// H × W: for a label, a Gaussian (σ = 1 px, peak 1) at the pixel holding the rotated grasp
    /// centre; for a trial, its outcome where it has weight.
    pub target: Vec<f32>,
    /// H × W per-pixel loss weights of a trial; `None` for a label (every pixel alike).
    pub(crate) weight: Option<Vec<f32>>,
    /// Angle bin of the grasp; the image was rotated by −bin · 22.5°.
    pub(crate) bin: usize,
    /// Rotated grasp centre in continuous image coordinates (may lie outside the image).
    pub(crate) center: [f32; 2],
}

impl Sample {
    /// The pixel (column, row) that holds [`Sample::center`] and the target's peak, or `None`
    /// when the centre lies outside a `size` × `size` image (the target is then all zero).
    pub(crate) fn center_pixel(&self, size: u32) -> Option<(u32, u32)> {
        let [x, y] = self.center.map(f32::floor);
        let inside = |c: f32| (0.0..size as f32).contains(&c);
        (inside(x) && inside(y)).then_some((x as u32, y as u32))
    }
}

/// Builds the sample for an image and its grasp's finger points: the grasp is re-derived from the
/// fingers, binned, and the image and centre are rotated by −bin · 22.5° so that the grasp is
/// within half a bin of horizontal.
///
/// The target Gaussian is centred on the pixel holding the rotated centre, not on the continuous
/// point: after a rotation by an odd multiple of 22.5° the centre rarely falls on a pixel centre,
/// and a Gaussian there would peak anywhere between e^(−1/4) ≈ 0.78 and 1, split over up to four
/// pixels. Snapping keeps the peak at exactly 1 on one pixel, the pixel that prediction's argmax
/// reads back.
pub(crate) fn make_sample(image: &NetInput, grasp_fingers: [[f32; 2]; 2]) -> Sample {
    let (w, h) = image.rgb.dimensions();
    assert_eq!(w, h, "square images only (got {w}×{h})");
    let (centre, angle) = grasp_from_fingers(grasp_fingers);
    let bin = angle_bin(angle);
    let turn = -bin_angle(bin);
    let rotated = image.warped(turn, [0.0, 0.0]);
    let center = rotate_point(centre, turn, w);

    let plane = (w * h) as usize;
    let mut input = vec![0.0; rotated.channels() * plane];
    write_chw(&rotated, &mut input);

    let mut sample = Sample {
        input,
        target: vec![0.0; plane],
        weight: None,
        bin,
        center,
    };
    if let Some((pu, pv)) = sample.center_pixel(w) {
        let two_var = 2.0 * TARGET_SIGMA_PX * TARGET_SIGMA_PX;
        for v in 0..h {
            for u in 0..w {
                let du = u as f32 - pu as f32;
                let dv = v as f32 - pv as f32;
                sample.target[(v * w + u) as usize] = (-(du * du + dv * dv) / two_var).exp();
            }
        }
    }
    sample
}

/// The sample of a trial: the same rotation to the executed grasp's bin as a label's, then the
/// outcome as the target where the weighting puts weight, and nothing elsewhere. A centre that
/// the rotation carries out of the image gives an all-zero weight.
pub(crate) fn make_trial_sample(
    image: &NetInput,
    grasp_fingers: [[f32; 2]; 2],
    success: bool,
    weighting: TrialWeighting,
) -> Sample {
    let mut sample = make_sample(image, grasp_fingers);
    let w = image.rgb.width();
    let plane = sample.target.len();
    let outcome = if success { 1.0 } else { 0.0 };
    sample.target = vec![0.0; plane];
    let mut weight = vec![0.0; plane];
    if let Some((pu, pv)) = sample.center_pixel(w) {
        let sigma = weighting.sigma_px.max(0.0);
        let reach = (2.0 * sigma).floor() as i64;
        let mut window = Vec::new();
        for dv in -reach..=reach {
            for du in -reach..=reach {
                let (u, v) = (i64::from(pu) + du, i64::from(pv) + dv);
                let d2 = (du * du + dv * dv) as f32;
                if !(0..i64::from(w)).contains(&u)
                    || !(0..i64::from(w)).contains(&v)
                    || d2 > 4.0 * sigma * sigma
                {
                    continue;
                }
                let g = if sigma > 0.0 {
                    (-d2 / (2.0 * sigma * sigma)).exp()
                } else {
                    1.0
                };
                window.push(((v * i64::from(w) + u) as usize, g));
            }
        }
        let total: f32 = window.iter().map(|(_, g)| g).sum();
        for (i, g) in window {
            weight[i] = weighting.weight * g / total;
            sample.target[i] = outcome;
        }
    }
    sample.weight = Some(weight);
    sample
}

/// A `crop` × `crop` window of a sample that holds its supervised pixel at least
/// [`CROP_MARGIN_PX`] from the window's edge (or at the image's own edge), placed at random, on
/// the pooling grid. Training on it costs a quarter of the whole image at 64 px; the network
/// is fully convolutional, so inference still runs on the whole image.
pub(crate) fn crop_sample(sample: &Sample, crop: u32, rng: &mut impl rand::Rng) -> Sample {
    let size = (sample.target.len() as f64).sqrt() as u32;
    if crop == 0 || crop >= size {
        return sample.clone();
    }
    let (pu, pv) = sample.center_pixel(size).unwrap_or((size / 2, size / 2));
    let margin = CROP_MARGIN_PX.min(crop / 2);
    let span = (crop - 2 * margin).max(1);
    let mut origin = |p: u32| {
        let at = margin + rng.random_range(0..span);
        let start = p.saturating_sub(at) / CROP_ALIGN_PX * CROP_ALIGN_PX;
        start.min(size - crop)
    };
    let (x0, y0) = (origin(pu), origin(pv));
    let plane = (size * size) as usize;
    let channels = sample.input.len() / plane;
    let window = |values: &[f32]| -> Vec<f32> {
        let mut out = Vec::with_capacity((crop * crop) as usize);
        for y in y0..y0 + crop {
            let row = (y * size + x0) as usize;
            out.extend_from_slice(&values[row..row + crop as usize]);
        }
        out
    };
    let mut input = Vec::with_capacity(channels * (crop * crop) as usize);
    for c in 0..channels {
        input.extend(window(&sample.input[c * plane..(c + 1) * plane]));
    }
    Sample {
        input,
        target: window(&sample.target),
        weight: sample.weight.as_deref().map(window),
        bin: sample.bin,
        center: [sample.center[0] - x0 as f32, sample.center[1] - y0 as f32],
    }
}

/// Writes an input into `out` as the network sees it: C × H × W (CHW), each value in [0, 1]:
/// RGB / 255, then for rgbd the height plane / 255 (1 mm per level, so 0 is the tote floor and
/// 1 is 255 mm above it). The one conversion that training and prediction share, so both see
/// the same numbers.
pub(crate) fn write_chw(image: &NetInput, out: &mut [f32]) {
    let plane = (image.rgb.width() * image.rgb.height()) as usize;
    assert_eq!(out.len(), image.channels() * plane, "one CHW image");
    for (i, pixel) in image.rgb.pixels().enumerate() {
        for (c, &value) in pixel.0.iter().enumerate() {
            out[c * plane + i] = f32::from(value) / 255.0;
        }
    }
    if let Some(height) = &image.height {
        for (i, pixel) in height.pixels().enumerate() {
            out[3 * plane + i] = f32::from(pixel.0[0]) / 255.0;
        }
    }
}

/// One label with its image, as stored by `graspmap label`.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelledImage {
    /// Object name.
    pub(crate) object: String,
    /// 1-based index among that object's labels (the k in `<Object>_<k>_rgb.png`).
    pub(crate) k: usize,
    /// The 128 × 128 RGB observation.
    pub(crate) image: RgbImage,
    /// Its height plane ([`height_from_depth_mm`] of `<Object>_<k>_depth.png`), loaded for rgbd.
    pub(crate) height: Option<GrayImage>,
    /// The labelled (or, for a trial, executed) grasp.
    pub(crate) grasp: PixelGrasp,
    /// Whether a label or a trial supervises it.
    pub(crate) supervision: Supervision,
}

/// Reads labels.json and every image it lists, in file order. Fails, naming the file, when
/// labels.json is missing or malformed, or an image is missing, unreadable, or not 128 × 128
/// 8-bit RGB (images are never converted: a wrong image means the labels are not what the
/// labelling tool wrote). With `input` rgbd it also reads each label's depth image, and fails
/// naming the first one that is missing.
pub fn load_dataset(store: &LabelStore, input: InputKind) -> anyhow::Result<Vec<LabelledImage>> {
    let labels_path = store.labels_path();
    if !labels_path.exists() {
        bail!(
            "{}: no labels (record some with `graspmap label`)",
            labels_path.display()
        );
    }
    let labels = store.load()?;
    let mut items = Vec::with_capacity(labels.len());
    for (object, object_labels) in labels.iter() {
        for (i, &label) in object_labels.iter().enumerate() {
            let k = i + 1;
            let path = store.image_path(object, k);
            // Deleting one label would shift the k of every later image, so the only safe fixes are
            // restoring the file or labelling again.
            let fix = "restore it, or re-record the labels with `graspmap label --force`; \
                       `graspmap label --check` lists every problem";
            let decoded = image::open(&path).with_context(|| {
                format!(
                    "{}: cannot read the image of {object} label {k} ({fix})",
                    path.display()
                )
            })?;
            let (width, height, color) = (decoded.width(), decoded.height(), decoded.color());
            if color != image::ColorType::Rgb8 || (width, height) != (IMAGE_SIZE, IMAGE_SIZE) {
                bail!(
                    "{}: image is {width}×{height} {color:?}, expected {IMAGE_SIZE}×{IMAGE_SIZE} \
                     Rgb8 ({fix})",
                    path.display()
                );
            }
            // Already 8-bit RGB, so this only unwraps the buffer.
            let image = decoded.into_rgb8();
            let height = match input {
                InputKind::Rgb => None,
                InputKind::Rgbd => Some(height_from_depth_mm(&load_depth(store, object, k)?)),
            };
            items.push(LabelledImage {
                object: object.to_owned(),
                k,
                image,
                height,
                grasp: label.into(),
                supervision: Supervision::Label,
            });
        }
    }
    Ok(items)
}

/// Shuffles 0..n with ChaCha8 seeded by `seed` and splits it 90/10 into (train, validation), each
/// sorted. Validation gets n − ⌊0.9 n⌋ items, as the ref's `int(0.9 * n)` train size, which is at
/// least 1 for n ≥ 2; a single sample goes to training.
pub(crate) fn split_train_validation(n: usize, seed: u64) -> (Vec<usize>, Vec<usize>) {
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
    let n_train = if n < 2 { n } else { n * 9 / 10 };
    let mut validation = order.split_off(n_train);
    order.sort_unstable();
    validation.sort_unstable();
    (order, validation)
}

/// The sample for one label: augmented with `augmentation` for training, as labelled for
/// validation (`None`). An augmentation that moves the grasp centre out of the image (so the target would be
/// empty) is redrawn, up to [`MAX_AUGMENT_TRIES`] times, before the unaugmented sample is used.
///
/// Labels and trials go through the same augmentation and rotation; only their targets and
/// weights differ.
pub fn training_sample(
    item: &LabelledImage,
    weighting: TrialWeighting,
    augmentation: Option<(&AugmentConfig, &mut ChaCha8Rng)>,
) -> Sample {
    let fingers = fingers(item.grasp);
    let input = NetInput {
        rgb: item.image.clone(),
        height: item.height.clone(),
    };
    let build = |image: &NetInput, fingers| match item.supervision {
        Supervision::Label => make_sample(image, fingers),
        Supervision::Trial { success } => make_trial_sample(image, fingers, success, weighting),
    };
    if let Some((config, rng)) = augmentation {
        for _ in 0..MAX_AUGMENT_TRIES {
            let (image, moved) = augment::augment_input(&input, fingers, config, rng);
            let sample = build(&image, moved);
            if sample.center_pixel(image.rgb.width()).is_some() {
                return sample;
            }
        }
    }
    build(&input, fingers)
}

/// The depth image of one label, or an error naming the first missing file and the fix.
fn load_depth(store: &LabelStore, object: &str, k: usize) -> anyhow::Result<super::input::DepthMm> {
    let path = store.depth_path(object, k);
    if !path.exists() {
        bail!(
            "{}: missing, and --input rgbd needs a depth image beside every label (write them \
             with `graspmap label --backfill-depth`, or train with --input rgb)",
            path.display()
        );
    }
    read_depth_png(&path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasp::rotate::test_images::random_grasp;
    use crate::grasp::BINS;
    use std::path::Path;

    fn fixture() -> LabelStore {
        LabelStore::new(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/reference-labels"),
        )
    }

    /// (column, row) of the largest value of a row-major `size`-wide plane.
    fn argmax(plane: &[f32], size: usize) -> (usize, usize) {
        let i = plane
            .iter()
            .enumerate()
            .fold(0, |best, (i, &x)| if x > plane[best] { i } else { best });
        (i % size, i / size)
    }

    /// The input's brightness (sum of channels) as one plane.
    fn brightness(sample: &Sample) -> Vec<f32> {
        let plane = sample.target.len();
        (0..plane)
            .map(|i| (0..3).map(|c| sample.input[c * plane + i]).sum())
            .collect()
    }

    /// Brightness-weighted centroid of the plane within `radius` of `around`.
    fn centroid(plane: &[f32], size: usize, around: (usize, usize), radius: usize) -> [f32; 2] {
        let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
        for v in around.1.saturating_sub(radius)..(around.1 + radius + 1).min(size) {
            for u in around.0.saturating_sub(radius)..(around.0 + radius + 1).min(size) {
                let w = plane[v * size + u];
                sx += w * (u as f32 + 0.5);
                sy += w * (v as f32 + 0.5);
                sw += w;
            }
        }
        [sx / sw, sy / sw]
    }

    /// Black image with white Gaussian blobs (σ = 1.5 px) at the given points.
    /// A label whose image has one blob at its grasp centre.
    fn blob_item(grasp: PixelGrasp) -> LabelledImage {
        LabelledImage {
            object: "Blob".into(),
            k: 1,
            image: blobs(&[[grasp.u as f32 + 0.5, grasp.v as f32 + 0.5]]),
            height: None,
            grasp,
            supervision: Supervision::Label,
        }
    }

    fn blobs(points: &[[f32; 2]]) -> RgbImage {
        RgbImage::from_fn(128, 128, |u, v| {
            let g: f32 = points
                .iter()
                .map(|p| {
                    let dx = u as f32 + 0.5 - p[0];
                    let dy = v as f32 + 0.5 - p[1];
                    (-(dx * dx + dy * dy) / 4.5).exp()
                })
                .sum();
            let c = (255.0 * g.min(1.0)).round() as u8;
            image::Rgb([c, c, c])
        })
    }

    #[test]
    fn angle_bins_round_and_wrap() {
        for (angle, bin) in [
            (0.0, 0),
            (170.0, 0),
            (11.24, 0),
            (11.26, 1),
            (22.5, 1),
            (-10.0, 0),
            (-30.0, 7),
            (180.0, 0),
            (90.0, 4),
            (157.5, 7),
            (168.0, 7),
            (168.8, 0),
            (359.0, 0),
        ] {
            assert_eq!(angle_bin(angle), bin, "{angle}°");
        }
        for bin in 0..BINS {
            assert_eq!(angle_bin(bin_angle(bin)), bin);
        }
    }

    #[test]
    fn rotation_to_the_bin_makes_grasps_horizontal() {
        // Fingers drawn as blobs on the image must end up on one row: this checks the image's
        // rotation sense, not only rotate_point's.
        for bin in 0..BINS {
            for (u, v) in [(64, 64), (50, 75), (80, 40)] {
                let grasp = PixelGrasp {
                    u,
                    v,
                    angle_deg: bin_angle(bin),
                };
                let f = fingers(grasp);
                let sample = make_sample(&NetInput::rgb(blobs(&f)), f);
                assert_eq!(sample.bin, bin);
                let turned = f.map(|p| rotate_point(p, -bin_angle(bin), 128));
                assert!((turned[0][1] - turned[1][1]).abs() < 1e-3, "{turned:?}");

                // Locate each finger blob in the input: the brightest pixel, then the other
                // brightest pixel at least 10 px away.
                let plane = brightness(&sample);
                let a = argmax(&plane, 128);
                let mut masked = plane.clone();
                for (i, x) in masked.iter_mut().enumerate() {
                    let (du, dv) = ((i % 128) as f32 - a.0 as f32, (i / 128) as f32 - a.1 as f32);
                    if du * du + dv * dv < 100.0 {
                        *x = 0.0;
                    }
                }
                let b = argmax(&masked, 128);
                let ca = centroid(&plane, 128, a, 3);
                let cb = centroid(&plane, 128, b, 3);
                assert!(
                    (ca[1] - cb[1]).abs() < 0.5,
                    "bin {bin} at ({u}, {v}): fingers at {ca:?} and {cb:?}"
                );
                assert!((ca[0] - cb[0]).abs() > 18.0, "{ca:?} {cb:?}");
                let (centre, _) = grasp_from_fingers(turned);
                assert!(
                    ((ca[1] + cb[1]) / 2.0 - centre[1]).abs() < 0.5,
                    "bin {bin}: image row {ca:?}/{cb:?}, rotated centre {centre:?}"
                );
            }
        }
    }

    #[test]
    fn target_is_a_unit_gaussian_on_the_rotated_centre_pixel() {
        for bin in 0..BINS {
            let grasp = PixelGrasp {
                u: 57,
                v: 70,
                angle_deg: bin_angle(bin),
            };
            let f = fingers(grasp);
            let sample = make_sample(&NetInput::rgb(RgbImage::new(128, 128)), f);
            let expected = rotate_point([57.5, 70.5], -bin_angle(bin), 128);
            assert!(
                (sample.center[0] - expected[0]).abs() < 1e-3
                    && (sample.center[1] - expected[1]).abs() < 1e-3
            );
            let (pu, pv) = sample.center_pixel(128).unwrap();
            assert_eq!((pu, pv), (expected[0] as u32, expected[1] as u32));
            assert_eq!(sample.target[(pv * 128 + pu) as usize], 1.0);
            assert_eq!(argmax(&sample.target, 128), (pu as usize, pv as usize));
            let sum: f32 = sample.target.iter().sum();
            assert!((sum - 2.0 * std::f32::consts::PI).abs() < 1e-3, "sum {sum}");
            assert_eq!(sample.input.len(), 3 * 128 * 128);
            assert_eq!(sample.target.len(), 128 * 128);
        }
    }

    #[test]
    fn input_is_chw_in_unit_range() {
        let image = RgbImage::from_fn(128, 128, |u, v| image::Rgb([u as u8, v as u8, 255]));
        let f = fingers(PixelGrasp {
            u: 64,
            v: 64,
            angle_deg: 0.0,
        });
        let sample = make_sample(&NetInput::rgb(image.clone()), f);
        let plane = 128 * 128;
        // Bin 0: no rotation, so channel c of pixel (u, v) sits at c·H·W + v·W + u.
        assert_eq!(sample.input[5 * 128 + 7], 7.0 / 255.0);
        assert_eq!(sample.input[plane + 5 * 128 + 7], 5.0 / 255.0);
        assert_eq!(sample.input[2 * plane + 5 * 128 + 7], 1.0);
        assert!(sample.input.iter().all(|x| (0.0..=1.0).contains(x)));
    }

    #[test]
    fn augmented_samples_keep_the_target_on_the_grasp() {
        // Property over 250 seeded draws, through the whole training path: a blob at the grasp
        // centre ends up under the target's peak (both in the rotated frame).
        let config = AugmentConfig::always();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut checked = 0;
        for _ in 0..250 {
            let item = blob_item(random_grasp(&mut rng, 30..98));
            let sample =
                training_sample(&item, TrialWeighting::default(), Some((&config, &mut rng)));
            let Some(peak) = sample.center_pixel(128) else {
                continue;
            };
            let plane = brightness(&sample);
            let bright = argmax(&plane, 128);
            if plane[bright.1 * 128 + bright.0] < 1.5 {
                continue; // the blob was cut by the border
            }
            checked += 1;
            let d = ((bright.0 as f32 - peak.0 as f32).powi(2)
                + (bright.1 as f32 - peak.1 as f32).powi(2))
            .sqrt();
            assert!(
                d <= 1.0,
                "{:?}: brightest input pixel {bright:?}, target peak {peak:?}",
                item.grasp
            );
        }
        assert!(checked > 200, "only {checked} samples checked");
    }

    #[test]
    fn validation_samples_are_not_augmented() {
        let item = blob_item(PixelGrasp {
            u: 40,
            v: 80,
            angle_deg: 45.0,
        });
        let plain = training_sample(&item, TrialWeighting::default(), None);
        assert_eq!(
            plain,
            make_sample(&NetInput::rgb(item.image.clone()), fingers(item.grasp))
        );
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let config = AugmentConfig::always();
        assert_ne!(
            training_sample(&item, TrialWeighting::default(), Some((&config, &mut rng))),
            plain
        );
    }

    #[test]
    fn augmentations_that_lose_the_grasp_are_redrawn() {
        // A grasp 3 px from the corner: many draws translate it off the image, yet every
        // training sample keeps its target peak inside.
        let corner = blob_item(PixelGrasp {
            u: 3,
            v: 3,
            angle_deg: 0.0,
        });
        let config = AugmentConfig::always();
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..200 {
            let sample = training_sample(
                &corner,
                TrialWeighting::default(),
                Some((&config, &mut rng)),
            );
            assert!(sample.center_pixel(128).is_some(), "{:?}", sample.center);
        }
        // Unaugmented, a corner grasp at 45° leaves the image when turned by −45°: the sample
        // is kept, with an empty target, for the caller to see.
        let lost = LabelledImage {
            grasp: PixelGrasp {
                u: 0,
                v: 0,
                angle_deg: 45.0,
            },
            ..corner
        };
        let sample = training_sample(&lost, TrialWeighting::default(), None);
        assert_eq!(sample.center_pixel(128), None, "{:?}", sample.center);
        assert!(sample.target.iter().all(|&t| t == 0.0));
    }

    #[test]
    fn fixture_loads_with_discs_at_the_labels() {
        let items = load_dataset(&fixture(), InputKind::Rgb).unwrap();
        let names: Vec<(String, usize)> = items.iter().map(|i| (i.object.clone(), i.k)).collect();
        assert_eq!(
            names,
            [
                ("YcbHammer".to_owned(), 1),
                ("YcbHammer".to_owned(), 2),
                ("YcbTomatoSoupCan".to_owned(), 1),
                ("YcbTomatoSoupCan".to_owned(), 2),
            ]
        );
        assert_eq!(
            items[1].grasp,
            PixelGrasp {
                u: 61,
                v: 70,
                angle_deg: 112.5
            }
        );
        for item in &items {
            // The synthetic images are grey with a red disc on the grasp centre: the red pixels'
            // centroid is the labelled pixel's centre.
            let red = |p: &image::Rgb<u8>| p.0[0] > 150 && p.0[1] < 100 && p.0[2] < 100;
            let (mut n, mut su, mut sv) = (0.0, 0.0, 0.0);
            for (u, v, p) in item.image.enumerate_pixels() {
                if red(p) {
                    n += 1.0;
                    su += u as f32 + 0.5;
                    sv += v as f32 + 0.5;
                }
            }
            assert!(n >= 9.0, "{} {}: no red disc", item.object, item.k);
            let (gu, gv) = (item.grasp.u as f32 + 0.5, item.grasp.v as f32 + 0.5);
            assert!(
                (su / n - gu).abs() < 0.5 && (sv / n - gv).abs() < 0.5,
                "{} {}: disc at ({}, {}), label ({gu}, {gv})",
                item.object,
                item.k,
                su / n,
                sv / n
            );
            assert!(red(item.image.get_pixel(item.grasp.u, item.grasp.v)));
        }
    }

    /// A copy of the reference fixture in a temporary directory.
    fn fixture_copy() -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        for entry in std::fs::read_dir(fixture().dir()).unwrap() {
            let entry = entry.unwrap();
            std::fs::copy(entry.path(), dir.path().join(entry.file_name())).unwrap();
        }
        dir
    }

    #[test]
    fn missing_and_wrong_images_are_named() {
        let dir = fixture_copy();
        let store = LabelStore::new(dir.path());
        let hammer_2 = store.image_path("YcbHammer", 2);
        std::fs::remove_file(&hammer_2).unwrap();
        let err = format!("{:#}", load_dataset(&store, InputKind::Rgb).unwrap_err());
        assert!(err.contains("YcbHammer_2_rgb.png"), "{err}");
        assert!(err.contains("graspmap label"), "{err}");

        RgbImage::new(64, 64).save(&hammer_2).unwrap();
        let err = format!("{:#}", load_dataset(&store, InputKind::Rgb).unwrap_err());
        assert!(err.contains("YcbHammer_2_rgb.png"), "{err}");
        assert!(err.contains("64×64"), "{err}");
        assert!(err.contains("expected 128×128"), "{err}");

        image::RgbaImage::new(128, 128).save(&hammer_2).unwrap();
        let err = format!("{:#}", load_dataset(&store, InputKind::Rgb).unwrap_err());
        assert!(
            err.contains("YcbHammer_2_rgb.png") && err.contains("Rgba8"),
            "{err}"
        );

        std::fs::write(&hammer_2, b"not a png").unwrap();
        let err = format!("{:#}", load_dataset(&store, InputKind::Rgb).unwrap_err());
        assert!(err.contains("YcbHammer_2_rgb.png"), "{err}");

        std::fs::remove_file(store.labels_path()).unwrap();
        let err = format!("{:#}", load_dataset(&store, InputKind::Rgb).unwrap_err());
        assert!(err.contains("labels.json"), "{err}");
    }

    #[test]
    fn split_is_a_seeded_ninety_ten_partition() {
        for n in [0, 1, 2, 5, 10, 11, 60, 61, 100] {
            let (train, validation) = split_train_validation(n, 0);
            let mut all: Vec<usize> = train.iter().chain(&validation).copied().collect();
            all.sort_unstable();
            assert_eq!(all, (0..n).collect::<Vec<_>>(), "n = {n}: not a partition");
            assert_eq!(
                validation.len(),
                n - n * 9 / 10 - usize::from(n == 1),
                "n = {n}"
            );
            if n >= 2 {
                assert!(!validation.is_empty());
            }
        }
        let (train, validation) = split_train_validation(60, 0);
        assert_eq!((train.len(), validation.len()), (54, 6));
        assert_eq!(split_train_validation(60, 0), (train, validation.clone()));
        let others: Vec<_> = (1..6).map(|s| split_train_validation(60, s).1).collect();
        assert!(
            others.iter().any(|v| *v != validation),
            "seed has no effect"
        );
    }

    #[test]
    fn crops_keep_the_supervised_pixel_inside_their_margin_on_the_pooling_grid() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for _ in 0..300 {
            let grasp = random_grasp(&mut rng, 0..128);
            let sample = make_sample(
                &NetInput::rgb(blobs(&[[grasp.u as f32, grasp.v as f32]])),
                fingers(grasp),
            );
            let Some((pu, pv)) = sample.center_pixel(128) else {
                continue;
            };
            let crop = crop_sample(&sample, 64, &mut rng);
            assert_eq!(crop.target.len(), 64 * 64);
            assert_eq!(crop.input.len(), 3 * 64 * 64);
            let (cu, cv) = crop.center_pixel(64).expect("the pixel is in the crop");
            // The crop's origin is on the 4-px grid, and the target moved with the image.
            assert_eq!((pu - cu) % CROP_ALIGN_PX, 0);
            assert_eq!((pv - cv) % CROP_ALIGN_PX, 0);
            assert_eq!(crop.target[(cv * 64 + cu) as usize], 1.0);
            for (c, p, origin) in [(cu, pu, pu - cu), (cv, pv, pv - cv)] {
                let at_image_edge = origin == 0 || origin == 64;
                assert!(
                    at_image_edge
                        || (CROP_MARGIN_PX..64 - CROP_MARGIN_PX + CROP_ALIGN_PX).contains(&c),
                    "pixel {p} lands at {c} of a crop from {origin}"
                );
            }
        }
    }
}
