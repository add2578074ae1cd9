//! The picture of one decision that `eval` writes per attempt and `predict` writes: what the
//! network scores, as heat over the camera's image, in the image's own frame (docs/evaluation.md,
//! "Visualisation").
//!
//! Left, twice the camera's size: the best of the 8 angles at each pixel, with the chosen grasp
//! drawn as the open gripper (pads and opening to scale). Right, at the camera's size: each
//! angle's map carried back from its rotated frame, captioned with its angle, the chosen one
//! framed in white with the gripper. Below: the colour bar with the range every panel shares (the
//! picture's own lowest and highest score) and the choice. Pure: maps in, an image out.

use image::{Rgb, RgbImage};

use super::maps::{AffordanceMaps, Choice};
use crate::grasp::draw::{draw_gripper, JawPx};
use crate::grasp::rotate::unrotate_plane;
use crate::grasp::{bin_angle, BINS};
use crate::vision::annotate::{caption, with_heat_legend};
use crate::vision::colormap::{heat_overlay, HeatRange};

/// The best-of-angles panel is this many times the camera's size.
pub(crate) const SUMMARY_SCALE: u32 = 2;
/// Angle panels per row, beside the summary.
const PER_ROW: u32 = 4;

/// The picture of `maps` (scored on `observation`, the camera's image) and the executed
/// `choice`; `jaw` is the gripper in the observation's pixels.
pub(crate) fn affordance_picture(
    observation: &RgbImage,
    maps: &AffordanceMaps,
    choice: &Choice,
    jaw: JawPx,
) -> RgbImage {
    let size = maps.size();
    assert_eq!(observation.dimensions(), (size, size), "maps of this image");
    let frames: Vec<Vec<f32>> = (0..BINS)
        .map(|bin| unrotate_plane(maps.map(bin), size, bin_angle(bin)))
        .collect();
    // The chosen score too: an image pixel reads the map pixel under its centre, and a map's
    // peak pixel may fall between the image's pixels.
    let scores = frames.iter().flatten().copied();
    let range = HeatRange::of(scores.chain(std::iter::once(choice.score)));
    let best: Vec<f32> = (0..(size * size) as usize)
        .map(|i| {
            frames
                .iter()
                .map(|f| f[i])
                .filter(|x| x.is_finite())
                .fold(f32::NAN, f32::max)
        })
        .collect();
    let big = size * SUMMARY_SCALE;
    let rows = (BINS as u32).div_ceil(PER_ROW);
    let mut picture = RgbImage::new(big + PER_ROW * size, big.max(rows * size));
    let g = choice.grasp;
    let centre = [g.u as f32 + 0.5, g.v as f32 + 0.5];
    let mut summary = heat_overlay(observation, &best, range, SUMMARY_SCALE);
    let scale = SUMMARY_SCALE as f32;
    draw_gripper(
        &mut summary,
        centre.map(|c| c * scale),
        g.angle_deg,
        jaw.scaled(scale),
    );
    caption(&mut summary, (2, 2), "best of 8 angles", 12);
    image::imageops::replace(&mut picture, &summary, 0, 0);
    for (bin, frame) in frames.iter().enumerate() {
        let mut panel = heat_overlay(observation, frame, range, 1);
        if bin == choice.bin {
            draw_gripper(&mut panel, centre, g.angle_deg, jaw);
            imageproc::drawing::draw_hollow_rect_mut(
                &mut panel,
                imageproc::rect::Rect::at(0, 0).of_size(size, size),
                Rgb([255, 255, 255]),
            );
        }
        caption(&mut panel, (2, 2), &format!("{}°", bin_angle(bin)), 11);
        let x = big + (bin as u32 % PER_ROW) * size;
        let y = (bin as u32 / PER_ROW) * size;
        image::imageops::replace(&mut picture, &panel, i64::from(x), i64::from(y));
    }
    let note = format!(
        "chosen: ({}, {}) at {}°, score {:.3}",
        g.u, g.v, g.angle_deg, choice.score
    );
    with_heat_legend(&picture, range, &note)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::maps::tests::{bumpy_maps, SIZE};

    fn jaw() -> JawPx {
        JawPx {
            opening: 10.0,
            pad_width: 3.0,
            pad_thickness: 1.0,
        }
    }

    #[test]
    fn the_picture_puts_each_angle_back_in_the_image_frame() {
        let image = RgbImage::from_pixel(SIZE, SIZE, Rgb([90, 90, 90]));
        // Three bumps, the highest at (40, 60) of the original image, seen by every rotation.
        let maps = bumpy_maps();
        let choice = maps.choose();
        assert_eq!((choice.bin, choice.grasp.u, choice.grasp.v), (0, 40, 60));
        let picture = affordance_picture(&image, &maps, &choice, jaw());
        let (w, h) = picture.dimensions();
        assert_eq!(w, 2 * SIZE + 4 * SIZE);
        assert!(h > 2 * SIZE, "the legend below");
        // Bin 3's panel (row 0, fourth) shows the bump where the image has it, not where its
        // rotated frame does, and no heat far from every bump.
        let panel = |bin: u32, u: u32, v: u32| {
            let x = 2 * SIZE + (bin % 4) * SIZE + u;
            picture.get_pixel(x, (bin / 4) * SIZE + v).0
        };
        let hot = panel(3, 40, 60);
        let cold = panel(3, 110, 110);
        assert!(hot[0] > 200 && hot[0] > hot[2], "{hot:?}");
        assert_eq!(cold, [54, 54, 54], "the image, grey and dimmed");
        // The chosen bin is framed; the summary shows the gripper at twice the size.
        assert_eq!(panel(0, SIZE - 1, 64), [255, 255, 255]);
        let green = (60..100)
            .flat_map(|x| (100..140).map(move |y| (x, y)))
            .filter(|&(x, y)| picture.get_pixel(x, y).0 == [40, 220, 40])
            .count();
        assert!(green > 10, "the pads at (80, 120)");
    }
}
