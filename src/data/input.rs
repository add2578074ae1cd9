//! What the network sees: RGB, and with `--input rgbd` a fourth plane, the height above the
//! tote floor computed from the depth image (docs/learning.md, "Input").
//!
//! Training, `eval` and `predict` all build their input here and convert it with the one
//! `dataset::write_chw`, so a model sees the same numbers whichever command runs it.

use std::path::Path;

use anyhow::{bail, Context as _};
use image::{GrayImage, ImageBuffer, Luma, RgbImage};

use crate::grasp::rotate::{warp_affine, warp_affine_gray};
use crate::grasp::tote::FLOOR_TOP;
use crate::grasp::{bin_angle, BINS, IMAGE_SIZE};
use crate::named::named_enum;
use crate::vision::camera::TOP_DOWN_EYE_HEIGHT;

/// A depth image as `scene --depth` and `label` write it: 16-bit millimetres along the
/// optical axis.
pub type DepthMm = ImageBuffer<Luma<u16>, Vec<u16>>;

/// Heights from 0 (the tote floor) to this many millimetres map to the input range [0, 1];
/// anything higher reads 1. One grey level is one millimetre, and the tote's walls (190 mm above
/// its floor) and the tallest stacks still fit below it.
pub(crate) const HEIGHT_FULL_SCALE_MM: f32 = 255.0;

named_enum! {
    /// Which planes the network takes.
    #[derive(Default, serde::Deserialize, Hash)]
    pub enum InputKind {
        /// RGB only, the reference's input.
        #[default]
        Rgb = "rgb", "the camera's RGB (the reference's input)",
        /// RGB and the height above the tote floor.
        Rgbd = "rgbd", "RGB and the height above the tote floor from the depth image",
    }
}

impl InputKind {
    /// Input planes of the network's first convolution.
    pub fn channels(self) -> usize {
        match self {
            InputKind::Rgb => 3,
            InputKind::Rgbd => 4,
        }
    }

    /// True for the reference's input (checkpoints then leave the field out, as before).
    pub(crate) fn is_rgb(&self) -> bool {
        *self == InputKind::Rgb
    }
}

/// The height above the tote floor of every pixel of a top-down depth image, in millimetres,
/// clipped to 0..=[`HEIGHT_FULL_SCALE_MM`]: the camera looks straight down, so a surface at
/// depth d lies (eye height − floor height − d) above the floor. Bare floor, the ground outside
/// the tote and pixels that hit nothing all read 0, the same as the black fill of a rotation.
pub fn height_from_depth_mm(depth: &DepthMm) -> GrayImage {
    let floor_depth_mm = (TOP_DOWN_EYE_HEIGHT - FLOOR_TOP) * 1000.0;
    GrayImage::from_fn(depth.width(), depth.height(), |u, v| {
        let height = floor_depth_mm - f32::from(depth.get_pixel(u, v).0[0]);
        Luma([height.round().clamp(0.0, HEIGHT_FULL_SCALE_MM) as u8])
    })
}

/// One network input before its conversion to CHW: the RGB image and, for rgbd, its height plane.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct NetInput {
    /// The camera's colour image.
    pub(crate) rgb: RgbImage,
    /// Height above the tote floor, 1 mm per level ([`height_from_depth_mm`]); `None` for rgb.
    pub(crate) height: Option<GrayImage>,
}

impl NetInput {
    /// An rgb input.
    pub(crate) fn rgb(rgb: RgbImage) -> Self {
        Self { rgb, height: None }
    }

    /// The input of `kind` for an image and its depth; `depth` is read only for rgbd.
    pub(crate) fn new(kind: InputKind, rgb: RgbImage, depth: Option<&DepthMm>) -> Self {
        let height = match kind {
            InputKind::Rgb => None,
            InputKind::Rgbd => Some(height_from_depth_mm(
                depth.expect("an rgbd input is built with its depth image"),
            )),
        };
        Self { rgb, height }
    }

    /// Planes in the CHW conversion: 3, or 4 with the height.
    pub(crate) fn channels(&self) -> usize {
        3 + usize::from(self.height.is_some())
    }

    /// Which kind of input this is.
    pub(crate) fn kind(&self) -> InputKind {
        match self.height {
            None => InputKind::Rgb,
            Some(_) => InputKind::Rgbd,
        }
    }

    /// Rotation about the centre, then translation ([`crate::grasp::rotate::map_point`]),
    /// applied to every plane with the same map and bilinear resampling, black fill.
    pub(crate) fn warped(&self, angle_deg: f32, translate: [f32; 2]) -> Self {
        Self {
            rgb: warp_affine(&self.rgb, angle_deg, translate),
            height: self
                .height
                .as_ref()
                .map(|h| warp_affine_gray(h, angle_deg, translate)),
        }
    }
}

/// The rotated inputs the 8 maps belong to: input `b` is the original turned by −b · 22.5°.
pub(crate) fn rotated_inputs(input: &NetInput) -> Vec<NetInput> {
    (0..BINS)
        .map(|b| input.warped(-bin_angle(b), [0.0, 0.0]))
        .collect()
}

/// Reads a 128 × 128 16-bit depth PNG in millimetres, naming `path` and the fix on any problem.
pub fn read_depth_png(path: &Path) -> anyhow::Result<DepthMm> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    decode_depth_png(&bytes, path)
}

/// Decodes a depth PNG from its bytes; `path` names it in errors.
pub(crate) fn decode_depth_png(bytes: &[u8], path: &Path) -> anyhow::Result<DepthMm> {
    let decoded = image::load_from_memory_with_format(bytes, image::ImageFormat::Png)
        .with_context(|| format!("{} is not a readable PNG", path.display()))?;
    let (w, h, color) = (decoded.width(), decoded.height(), decoded.color());
    match decoded {
        image::DynamicImage::ImageLuma16(depth) if (w, h) == (IMAGE_SIZE, IMAGE_SIZE) => Ok(depth),
        _ => bail!(
            "{} is a {w}×{h} {color:?} image; a depth image is {IMAGE_SIZE}×{IMAGE_SIZE} 16-bit grey \
             in millimetres, as `graspmap scene --depth` writes it",
            path.display()
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasp::rotate::test_images::{blob, brightest};

    #[test]
    fn height_reads_millimetres_above_the_floor_and_clips() {
        let floor = ((TOP_DOWN_EYE_HEIGHT - FLOOR_TOP) * 1000.0).round() as u16;
        let depth = DepthMm::from_fn(4, 1, |u, _| {
            Luma([[floor, floor - 42, 10_000, floor - 400][u as usize]])
        });
        let height = height_from_depth_mm(&depth);
        assert_eq!(
            height.as_raw(),
            &[0, 42, 0, 255],
            "floor, 42 mm, far, clipped"
        );
    }

    #[test]
    fn rotation_keeps_the_height_plane_aligned_with_the_rgb() {
        // A bright spot in RGB and a tall spot in height at the same off-centre pixel: after
        // each of the 8 rotations and an augmentation-like warp both still peak together.
        let rgb = blob(128, [90.5, 40.5]);
        let height = GrayImage::from_fn(128, 128, |u, v| Luma([rgb.get_pixel(u, v).0[0]]));
        let input = NetInput {
            rgb,
            height: Some(height),
        };
        let mut warped = rotated_inputs(&input);
        warped.push(input.warped(7.3, [11.2, -5.7]));
        for (b, turned) in warped.iter().enumerate() {
            let (rgb_peak, _) = brightest(&turned.rgb);
            let plane = turned.height.as_ref().unwrap();
            let (hu, hv, _) = plane
                .enumerate_pixels()
                .max_by_key(|(u, v, p)| (p.0[0], std::cmp::Reverse((*v, *u))))
                .unwrap();
            assert_eq!(rgb_peak, (hu, hv), "warp {b}");
            // Same resampling, so the planes agree pixel for pixel, not only at the peak.
            for (u, v, p) in plane.enumerate_pixels() {
                assert_eq!(
                    p.0[0],
                    turned.rgb.get_pixel(u, v).0[0],
                    "warp {b} ({u}, {v})"
                );
            }
        }
    }

    #[test]
    fn depth_png_must_be_16_bit_128_square() {
        let path = Path::new("x_depth.png");
        let encode = |image: image::DynamicImage| {
            let mut bytes = std::io::Cursor::new(Vec::new());
            image.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
            bytes.into_inner()
        };
        let good = encode(DepthMm::from_pixel(128, 128, Luma([700])).into());
        assert_eq!(
            decode_depth_png(&good, path).unwrap().get_pixel(3, 3).0,
            [700]
        );
        let eight = encode(GrayImage::new(128, 128).into());
        let error = decode_depth_png(&eight, path).unwrap_err().to_string();
        assert!(
            error.contains("x_depth.png") && error.contains("16-bit"),
            "{error}"
        );
        let small = encode(DepthMm::new(64, 128).into());
        assert!(decode_depth_png(&small, path).is_err());
    }
}
