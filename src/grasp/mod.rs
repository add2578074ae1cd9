//! The action space: what a grasp is in the image, and the facts every layer shares about it.
//!
//! A grasp is an integer pixel (u, v) of the 128 × 128 top-down image and an angle θ in degrees,
//! clockwise on screen (x towards y), normalised into [0, 180). The network scores [`BINS`]
//! rotations of 22.5° each. This folder is the pure core: it may use `vision` (the camera, to
//! turn a pixel into a world point) and nothing above it; no rapier world, no tch.
//! Conventions: docs/conventions.md.

pub(crate) mod draw;
pub(crate) mod gripper;
pub(crate) mod rotate;
pub mod tote;
pub mod world;

/// Largest grasp angle magnitude accepted from users (degrees); angles are normalised mod 180, so
/// a full turn either way covers every way of writing one, and no value overflows on the way.
pub(crate) const MAX_ANGLE_DEG: f64 = 360.0;

/// Side length of the camera image and of every label image (px).
pub(crate) const IMAGE_SIZE: u32 = 128;
/// Number of angle bins over the half turn.
pub(crate) const BINS: usize = 8;
/// Width of one angle bin in degrees (180 / [`BINS`]).
pub(crate) const BIN_DEG: f32 = 22.5;
/// Distance (px) from the grasp centre to each finger point along the grasp angle: how the
/// reference marks a grasp and augments it.
pub(crate) const FINGER_OFFSET_PX: f32 = 10.0;

/// A grasp in image terms, as users click and label it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PixelGrasp {
    /// Column.
    pub u: u32,
    /// Row.
    pub v: u32,
    /// Image angle in degrees, clockwise (x towards y), in [0, 180).
    pub angle_deg: f32,
}

/// Why a pixel or an angle is not a grasp of the image.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum PixelError {
    /// A coordinate outside 0..IMAGE_SIZE, or not an integer.
    #[error("{axis} = {value} must be an integer in 0..={max}")]
    OutOfImage {
        /// "x" or "y".
        axis: &'static str,
        /// The value given.
        value: f64,
        /// The largest valid coordinate.
        max: u32,
    },
    /// An angle that is not a finite number of degrees within ±[`MAX_ANGLE_DEG`].
    #[error(
        "angle = {value:?} must be a number of degrees from -{MAX_ANGLE_DEG} to {MAX_ANGLE_DEG}"
    )]
    BadAngle {
        /// The value given.
        value: f64,
    },
}

impl PixelGrasp {
    /// The grasp for coordinates and an angle read from a file or a flag: coordinates must be
    /// integers inside the image, the angle any finite number of degrees (normalised here).
    /// Every reader of labels and clicks validates through this one function.
    pub(crate) fn checked(x: f64, y: f64, angle_deg: f64) -> Result<Self, PixelError> {
        let coordinate = |axis: &'static str, value: f64| {
            if value.fract() == 0.0 && (0.0..f64::from(IMAGE_SIZE)).contains(&value) {
                Ok(value as u32)
            } else {
                Err(PixelError::OutOfImage {
                    axis,
                    value,
                    max: IMAGE_SIZE - 1,
                })
            }
        };
        if !angle_deg.is_finite() || angle_deg.abs() > MAX_ANGLE_DEG {
            return Err(PixelError::BadAngle { value: angle_deg });
        }
        Ok(Self {
            u: coordinate("x", x)?,
            v: coordinate("y", y)?,
            angle_deg: normalize_angle(angle_deg as f32),
        })
    }
}

/// Normalises an angle in degrees into [0, 180): a parallel-jaw grasp is symmetric under a half turn.
pub(crate) fn normalize_angle(deg: f32) -> f32 {
    let a = deg.rem_euclid(180.0);
    if a >= 180.0 {
        0.0
    } else {
        a
    }
}

/// The bin of an angle in degrees: round(θ / 22.5) mod 8 on θ normalised into [0, 180), so
/// angles within half a bin of 180° wrap to bin 0 (ours; the reference put 170° in bin 7).
pub(crate) fn angle_bin(angle_deg: f32) -> usize {
    (normalize_angle(angle_deg) / BIN_DEG).round() as usize % BINS
}

/// The angle in degrees that bin `bin` stands for.
pub(crate) fn bin_angle(bin: usize) -> f32 {
    bin as f32 * BIN_DEG
}

/// The two finger points of a grasp: its pixel centre (u + 0.5, v + 0.5) ∓ [`FINGER_OFFSET_PX`]
/// along θ, first finger on the −θ side.
pub(crate) fn fingers(grasp: PixelGrasp) -> [[f32; 2]; 2] {
    let centre = [grasp.u as f32 + 0.5, grasp.v as f32 + 0.5];
    let (sin, cos) = grasp.angle_deg.to_radians().sin_cos();
    let d = [FINGER_OFFSET_PX * cos, FINGER_OFFSET_PX * sin];
    [
        [centre[0] - d[0], centre[1] - d[1]],
        [centre[0] + d[0], centre[1] + d[1]],
    ]
}

/// The grasp that two finger points describe: their midpoint (continuous image coordinates) and
/// the angle of the line through them, in degrees in [0, 180). Finger order does not matter.
pub(crate) fn grasp_from_fingers(f: [[f32; 2]; 2]) -> ([f32; 2], f32) {
    let centre = [(f[0][0] + f[1][0]) / 2.0, (f[0][1] + f[1][1]) / 2.0];
    let angle = (f[1][1] - f[0][1]).atan2(f[1][0] - f[0][0]).to_degrees();
    (centre, normalize_angle(angle))
}

#[cfg(test)]
mod tests {
    use super::rotate::test_images::dist;
    use super::*;

    #[test]
    fn angles_wrap_into_half_turn() {
        assert_eq!(normalize_angle(0.0), 0.0);
        assert_eq!(normalize_angle(180.0), 0.0);
        assert_eq!(normalize_angle(-30.0), 150.0);
        assert_eq!(normalize_angle(390.0), 30.0);
        assert!(normalize_angle(-1e-9) < 180.0);
    }

    #[test]
    fn checked_grasps_name_the_bad_value() {
        assert_eq!(
            PixelGrasp::checked(64.0, 70.0, 190.0),
            Ok(PixelGrasp {
                u: 64,
                v: 70,
                angle_deg: 10.0
            })
        );
        let out = PixelGrasp::checked(128.0, 3.0, 0.0).unwrap_err();
        assert_eq!(out.to_string(), "x = 128 must be an integer in 0..=127");
        assert!(PixelGrasp::checked(3.0, 2.5, 0.0).is_err());
        assert!(PixelGrasp::checked(3.0, -1.0, 0.0).is_err());
        assert!(PixelGrasp::checked(3.0, 2.0, f64::NAN).is_err());
    }

    #[test]
    fn fingers_and_back() {
        let g = PixelGrasp {
            u: 40,
            v: 70,
            angle_deg: 30.0,
        };
        let f = fingers(g);
        assert!((dist(f[0], f[1]) - 2.0 * FINGER_OFFSET_PX).abs() < 1e-4);
        // Clockwise: at 30° the second finger is right of and below the centre.
        assert!(f[1][0] > 40.5 && f[1][1] > 70.5, "{f:?}");
        let (centre, angle) = grasp_from_fingers(f);
        assert!(dist(centre, [40.5, 70.5]) < 1e-4, "{centre:?}");
        assert!((angle - 30.0).abs() < 1e-3, "{angle}");
        // Swapped fingers and wrap-around describe the same grasp.
        let (_, swapped) = grasp_from_fingers([f[1], f[0]]);
        assert!((swapped - 30.0).abs() < 1e-3, "{swapped}");
        let (_, wrapped) = grasp_from_fingers(fingers(PixelGrasp {
            angle_deg: 179.9,
            ..g
        }));
        assert!((wrapped - 179.9).abs() < 1e-3, "{wrapped}");
    }
}
