//! Drawing a grasp on an image: as the reference marks one (the two finger points and the line
//! between them), and as the gripper itself, its pads and opening to the camera's scale.

use image::{Rgb, RgbImage};

use super::gripper::GRIPPER;
use super::tote::{FLOOR_TOP, PICK_TOTE};
use super::{fingers, PixelGrasp};
use crate::vision::camera::Camera;

/// Marks a grasp: the finger points (centre ± 10 px along θ) joined by a red line,
/// green finger dots and a yellow centre pixel.
pub(crate) fn draw_grasp(image: &mut RgbImage, g: &PixelGrasp) {
    let [a, b] = fingers(*g);
    let line = Rgb([255, 40, 40]);
    imageproc::drawing::draw_line_segment_mut(image, (a[0], a[1]), (b[0], b[1]), line);
    for [x, y] in [a, b] {
        imageproc::drawing::draw_filled_circle_mut(
            image,
            (x as i32, y as i32),
            1,
            Rgb([40, 220, 40]),
        );
    }
    let (w, h) = image.dimensions();
    image.put_pixel(g.u.min(w - 1), g.v.min(h - 1), Rgb([255, 255, 0]));
}

/// The open gripper as the top-down camera sees it, in image pixels at the tote floor: the
/// jaw's opening between the pads' inner faces, and each pad's width (across the closing line)
/// and thickness (along it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct JawPx {
    /// Between the pads' inner faces, fully open.
    pub(crate) opening: f32,
    /// A pad across the closing line.
    pub(crate) pad_width: f32,
    /// A pad along the closing line.
    pub(crate) pad_thickness: f32,
}

impl JawPx {
    /// The workcell's gripper seen by `camera` at the middle of the pick tote's floor; `None`
    /// for a camera that does not see it.
    pub(crate) fn at_floor(camera: &Camera) -> Option<Self> {
        let [x, y] = PICK_TOTE.center;
        let centre = rapier3d::math::Vector::new(x, y, FLOOR_TOP);
        let metre = 0.1;
        let beside = centre + rapier3d::math::Vector::new(metre, 0.0, 0.0);
        let (a, b) = (camera.project(centre)?, camera.project(beside)?);
        let px_per_m = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt() / metre;
        Some(Self {
            opening: GRIPPER.max_opening * px_per_m,
            pad_width: GRIPPER.pad_width * px_per_m,
            pad_thickness: GRIPPER.pad_thickness * px_per_m,
        })
    }

    /// The same jaw on an image enlarged `by` times.
    pub(crate) fn scaled(self, by: f32) -> Self {
        Self {
            opening: self.opening * by,
            pad_width: self.pad_width * by,
            pad_thickness: self.pad_thickness * by,
        }
    }
}

/// Draws the open gripper of a grasp at continuous point `centre` of `image` (whose pixels the
/// `jaw` is measured in), closing along `angle_deg` (clockwise, x towards y): the two pads in
/// green, outlined in black so that they stand out on any heat colour, and the closing line
/// between them in thin red, which leaves the heat under the grasp in sight. Parts thinner than
/// a pixel are drawn a pixel wide.
pub(crate) fn draw_gripper(image: &mut RgbImage, centre: [f32; 2], angle_deg: f32, jaw: JawPx) {
    let (sin, cos) = angle_deg.to_radians().sin_cos();
    let along = [cos, sin];
    let reach = jaw.opening / 2.0 + jaw.pad_thickness / 2.0;
    let pad = [
        (jaw.pad_thickness / 2.0).max(0.75),
        (jaw.pad_width / 2.0).max(1.0),
    ];
    let line = [jaw.opening / 2.0, 0.5];
    let pads = [-1.0, 1.0].map(|s| [centre[0] + s * reach * cos, centre[1] + s * reach * sin]);
    fill_box(image, centre, along, line, [255, 40, 40]);
    for p in pads {
        // The outline first, so that the pad's colour lies on top of it.
        fill_box(image, p, along, pad.map(|h| h + 1.0), [0, 0, 0]);
        fill_box(image, p, along, pad, [40, 220, 40]);
    }
}

/// Paints the pixels whose centres lie in the box around `centre` with half extents
/// `half[0]` along the unit vector `along` and `half[1]` across it.
fn fill_box(image: &mut RgbImage, centre: [f32; 2], along: [f32; 2], half: [f32; 2], rgb: [u8; 3]) {
    let r = half[0].hypot(half[1]);
    let (w, h) = image.dimensions();
    let first = |c: f32| (c - r).floor().max(0.0) as u32;
    let last = |c: f32, n: u32| ((c + r).ceil().max(0.0) as u32).min(n);
    for v in first(centre[1])..last(centre[1], h) {
        for u in first(centre[0])..last(centre[0], w) {
            let d = [u as f32 + 0.5 - centre[0], v as f32 + 0.5 - centre[1]];
            let a = d[0] * along[0] + d[1] * along[1];
            let c = -d[0] * along[1] + d[1] * along[0];
            if a.abs() <= half[0] && c.abs() <= half[1] {
                image.put_pixel(u, v, Rgb(rgb));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_jaw_is_to_the_camera_scale() {
        let jaw = JawPx::at_floor(&Camera::top_down()).unwrap();
        // 80° over 128 px from 0.687 m above the floor: about 111 px a metre.
        assert!((9.0..10.0).contains(&jaw.opening), "{jaw:?}");
        let ratio = jaw.pad_width / jaw.opening;
        assert!((ratio - GRIPPER.pad_width / GRIPPER.max_opening).abs() < 1e-5);
        assert_eq!(jaw.scaled(2.0).opening, 2.0 * jaw.opening);
    }

    #[test]
    fn the_gripper_lies_along_its_angle() {
        let jaw = JawPx {
            opening: 20.0,
            pad_width: 8.0,
            pad_thickness: 2.0,
        };
        let green = |image: &RgbImage, u: u32, v: u32| image.get_pixel(u, v).0 == [40, 220, 40];
        let red = |image: &RgbImage, u: u32, v: u32| image.get_pixel(u, v).0 == [255, 40, 40];
        let mut flat = RgbImage::new(64, 64);
        draw_gripper(&mut flat, [32.0, 32.0], 0.0, jaw);
        // Pads 11 px either side of the centre along x, the closing line between them.
        assert!(green(&flat, 21, 32) && green(&flat, 42, 32) && green(&flat, 21, 29));
        assert!(red(&flat, 25, 32) && red(&flat, 38, 32));
        assert!(!green(&flat, 32, 21), "nothing across");
        let mut turned = RgbImage::new(64, 64);
        draw_gripper(&mut turned, [32.0, 32.0], 90.0, jaw);
        assert!(green(&turned, 32, 21) && green(&turned, 32, 42));
        assert!(red(&turned, 32, 25) && !green(&turned, 21, 32));
        assert_eq!(turned.get_pixel(33, 32).0, [0, 0, 0], "the line is thin");
    }
}
