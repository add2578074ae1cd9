//! Training augmentation (the reference's imgaug settings), applied jointly to an image and a grasp's finger points (docs/learning.md).
//!
//! The image and the points go through the same affine map as every rotation in the project
//! ([`crate::grasp::rotate`]). Everything here is pure: randomness comes from the caller's `Rng`.

#[cfg(test)]
use image::RgbImage;
use rand::Rng;

use super::input::NetInput;
use crate::grasp::rotate::{image_centre, map_point};

/// Random affine augmentation of a training sample (the reference's imgaug settings).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct AugmentConfig {
    /// Chance that a sample is augmented at all; otherwise it passes through unchanged. Default 0.7.
    pub probability: f64,
    /// Largest translation on each axis, as a fraction of the image's width (x) or height (y);
    /// drawn uniformly from ±this. Default 0.2 (±25.6 px on a 128 px image).
    pub max_translate_frac: f32,
    /// Largest rotation about the image centre in degrees, drawn uniformly from ±this.
    /// Default 11.25 (half an angle bin).
    pub max_rotate_deg: f32,
}

impl AugmentConfig {
    /// Every sample augmented, with the default ranges: what the property tests exercise.
    #[cfg(test)]
    pub(crate) fn always() -> Self {
        Self {
            probability: 1.0,
            ..Self::default()
        }
    }
}

impl Default for AugmentConfig {
    fn default() -> Self {
        Self {
            probability: 0.7,
            max_translate_frac: 0.2,
            max_rotate_deg: 11.25,
        }
    }
}

/// With probability `config.probability`, rotates the image about its centre by a uniform angle
/// in ±`max_rotate_deg` and then translates it by a uniform offset in ±`max_translate_frac` of
/// its size on each axis; the finger points undergo the same map. Otherwise returns both
/// unchanged. Finger points may end up outside the image: the caller decides what that means.
///
/// Draws from `rng` in a fixed order (apply?, angle, dx, dy), and nothing more when the sample
/// is not augmented, so a seeded generator reproduces the same augmentations.
#[cfg(test)]
pub(crate) fn augment(
    image: &RgbImage,
    fingers: [[f32; 2]; 2],
    config: &AugmentConfig,
    rng: &mut impl Rng,
) -> (RgbImage, [[f32; 2]; 2]) {
    let (input, moved) = augment_input(&NetInput::rgb(image.clone()), fingers, config, rng);
    (input.rgb, moved)
}

/// [`augment`] for a whole network input: the same draws, and one map for the RGB, the height
/// plane (rgbd) and the finger points, so the planes stay aligned.
pub(crate) fn augment_input(
    input: &NetInput,
    fingers: [[f32; 2]; 2],
    config: &AugmentConfig,
    rng: &mut impl Rng,
) -> (NetInput, [[f32; 2]; 2]) {
    if !rng.random_bool(config.probability.clamp(0.0, 1.0)) {
        return (input.clone(), fingers);
    }
    let image = &input.rgb;
    // Uniform in [−max, max); written out rather than with random_range so that a zero range
    // (augmentation switched off on one axis) is allowed.
    let mut symmetric = |max: f32| (rng.random::<f32>() * 2.0 - 1.0) * max;
    let angle = symmetric(config.max_rotate_deg);
    let translate = [
        symmetric(config.max_translate_frac * image.width() as f32),
        symmetric(config.max_translate_frac * image.height() as f32),
    ];
    let centre = image_centre(image);
    let moved = fingers.map(|p| map_point(p, angle, translate, centre));
    (input.warped(angle, translate), moved)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasp::rotate::test_images::{blob, brightest, dist, random_grasp};
    use crate::grasp::{
        fingers, grasp_from_fingers, normalize_angle, PixelGrasp, FINGER_OFFSET_PX,
    };
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn augmentation_moves_fingers_with_the_image() {
        // Property, over 300 seeded draws: a blob at the grasp centre is still under the centre
        // of the transformed fingers after augmentation.
        let config = AugmentConfig::always();
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut checked = 0;
        for _ in 0..300 {
            let grasp = random_grasp(&mut rng, 20..108);
            let f = fingers(grasp);
            let image = blob(128, grasp_from_fingers(f).0);
            let (augmented, moved) = augment(&image, f, &config, &mut rng);
            let (centre, angle) = grasp_from_fingers(moved);
            // Rigid map: the fingers stay 20 px apart and turn by at most the maximum rotation.
            assert!((dist(moved[0], moved[1]) - 2.0 * FINGER_OFFSET_PX).abs() < 1e-3);
            let turn = normalize_angle(angle - grasp.angle_deg + 90.0) - 90.0;
            assert!(turn.abs() <= config.max_rotate_deg + 1e-3, "{turn}");
            if !(3.0..125.0).contains(&centre[0]) || !(3.0..125.0).contains(&centre[1]) {
                continue; // the blob left the image; nothing to compare
            }
            checked += 1;
            let ((bu, bv), _) = brightest(&augmented);
            let peak = [bu as f32 + 0.5, bv as f32 + 0.5];
            assert!(
                dist(peak, centre) < 1.0,
                "{grasp:?}: brightest pixel {peak:?}, transformed centre {centre:?}"
            );
        }
        assert!(checked > 200, "only {checked} draws stayed inside");
    }

    #[test]
    fn augmentation_is_seeded_and_respects_probability() {
        let image = blob(128, [64.0, 64.0]);
        let f = fingers(PixelGrasp {
            u: 64,
            v: 64,
            angle_deg: 0.0,
        });
        let config = AugmentConfig::default();
        let run = |seed| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            (0..200)
                .map(|_| augment(&image, f, &config, &mut rng))
                .collect::<Vec<_>>()
        };
        let a = run(3);
        assert_eq!(a, run(3), "same seed, same augmentations");
        let unchanged = a.iter().filter(|(img, g)| *g == f && *img == image).count();
        // p = 0.7: about 60 of 200 pass through; 3 σ ≈ 19.
        assert!(
            (40..=80).contains(&unchanged),
            "{unchanged} of 200 unchanged"
        );
        let off = AugmentConfig {
            probability: 0.0,
            ..config
        };
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        assert_eq!(augment(&image, f, &off, &mut rng), (image.clone(), f));
    }
}
