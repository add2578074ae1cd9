//! Image rotation about the image centre: one map for images and points, used by training, prediction and the collision check.
//!
//! Rotating by +b about the image centre moves a point at angle φ around the centre to φ + b,
//! clockwise on screen (x towards y), and "rotate by −b" undoes it. Points are continuous image
//! coordinates in which pixel (u, v) covers [u, u+1) × [v, v+1); the centre of a 128 × 128 image
//! is (64, 64).
//!
//! Images are resampled with imageproc's `warp`, but not with its `rotate_about_center`:
//! imageproc puts pixel (u, v)'s centre at the integer point (u, v), so its "centre" (w/2, h/2) is
//! half a pixel right of and below ours (tested in `imageproc_centre_is_half_a_pixel_off`). We
//! build the projection ourselves in imageproc's frame, i.e. shifted by −0.5 px on both axes.
//! imageproc truncates its bilinear blends to u8 instead of rounding, so each resampling darkens
//! a textured image by about one grey level on average (a +22.5°/−22.5° round trip: −1.8); flat
//! regions are unaffected. Small next to the augmentation itself, so accepted.

use image::{GrayImage, Luma, Rgb, RgbImage};
use imageproc::geometric_transformations::{warp, Border, Interpolation, Projection};

use super::{bin_angle, PixelGrasp};

/// Rotates `image` about its centre by `angle_deg` (clockwise on screen for positive angles),
/// bilinear, black where the source lies outside the image. Same size as the input.
#[cfg(test)]
pub(crate) fn rotate_image(image: &RgbImage, angle_deg: f32) -> RgbImage {
    warp_affine(image, angle_deg, [0.0, 0.0])
}

/// Where [`rotate_image`] moves the continuous point `p` of a `size` × `size` image.
pub(crate) fn rotate_point(p: [f32; 2], angle_deg: f32, size: u32) -> [f32; 2] {
    map_point(p, angle_deg, [0.0, 0.0], [size as f32 / 2.0; 2])
}

/// The original-image grasp for pixel (`u`, `v`) of map `bin`: the pixel's centre rotated by
/// +bin · 22.5°, the pixel holding it, clipped to the image; the angle is the bin's.
pub(crate) fn unrotate(bin: usize, u: u32, v: u32, size: u32) -> PixelGrasp {
    let [x, y] = rotate_point([u as f32 + 0.5, v as f32 + 0.5], bin_angle(bin), size);
    let clip = |c: f32| (c.floor().max(0.0) as u32).min(size - 1);
    PixelGrasp {
        u: clip(x),
        v: clip(y),
        angle_deg: bin_angle(bin),
    }
}

/// A `size` × `size` plane (row-major) scored in the frame of the image turned by
/// −`angle_deg`, carried back into the image's own frame: each image pixel takes the value of
/// the plane's pixel that holds its centre turned by −`angle_deg` ([`rotate_point`]): the score
/// the network's map gives a grasp there (as the model's `score_at` reads it). NaN where that point lies outside the plane
/// (the corners that the rotation brought in from outside the image): nothing was scored there.
pub(crate) fn unrotate_plane(plane: &[f32], size: u32, angle_deg: f32) -> Vec<f32> {
    let (sin, cos) = f64::from(-angle_deg).to_radians().sin_cos();
    let half = f64::from(size) / 2.0;
    let mut out = Vec::with_capacity((size * size) as usize);
    for v in 0..size {
        for u in 0..size {
            // map_point's rotation about the centre, with its sine and cosine computed once.
            let dx = f64::from(u) + 0.5 - half;
            let dy = f64::from(v) + 0.5 - half;
            let at = [
                (cos * dx - sin * dy + half) as f32,
                (sin * dx + cos * dy + half) as f32,
            ];
            let inside = |c: f32| (0.0..size as f32).contains(&c);
            out.push(if inside(at[0]) && inside(at[1]) {
                plane[at[1] as usize * size as usize + at[0] as usize]
            } else {
                f32::NAN
            });
        }
    }
    out
}

/// The centre of an image in continuous coordinates: (w/2, h/2).
pub(crate) fn image_centre(image: &RgbImage) -> [f32; 2] {
    [image.width() as f32 / 2.0, image.height() as f32 / 2.0]
}

/// The affine map shared by images and points: rotate about `centre` by `angle_deg`, then
/// translate by `translate`. Computed in f64 so that +b followed by −b returns the point to
/// well within 1e-4 px.
pub(crate) fn map_point(
    p: [f32; 2],
    angle_deg: f32,
    translate: [f32; 2],
    centre: [f32; 2],
) -> [f32; 2] {
    let (sin, cos) = f64::from(angle_deg).to_radians().sin_cos();
    let dx = f64::from(p[0]) - f64::from(centre[0]);
    let dy = f64::from(p[1]) - f64::from(centre[1]);
    // y points down, so this matrix turns +x towards +y: clockwise on screen.
    [
        (cos * dx - sin * dy + f64::from(centre[0]) + f64::from(translate[0])) as f32,
        (sin * dx + cos * dy + f64::from(centre[1]) + f64::from(translate[1])) as f32,
    ]
}

/// Resamples `image` under [`map_point`] with the image centre, bilinear with black fill.
pub(crate) fn warp_affine(image: &RgbImage, angle_deg: f32, translate: [f32; 2]) -> RgbImage {
    warp(
        image,
        projection(image, angle_deg, translate),
        Interpolation::Bilinear,
        Border::Constant(Rgb([0, 0, 0])),
    )
}

/// [`warp_affine`] for a one-channel image (the rgbd input's height plane): the same map and
/// the same bilinear resampling, so the plane stays aligned with the RGB; black (0) fill.
pub(crate) fn warp_affine_gray(
    image: &GrayImage,
    angle_deg: f32,
    translate: [f32; 2],
) -> GrayImage {
    warp(
        image,
        projection(image, angle_deg, translate),
        Interpolation::Bilinear,
        Border::Constant(Luma([0])),
    )
}

/// imageproc's projection for [`map_point`] on an image of this size.
fn projection<P: image::Pixel>(
    image: &image::ImageBuffer<P, Vec<P::Subpixel>>,
    angle_deg: f32,
    translate: [f32; 2],
) -> Projection {
    // imageproc samples pixel (u, v) at the point (u, v), ours at (u + 0.5, v + 0.5): in its frame
    // the rotation centre is ours minus half a pixel, and translations are unchanged.
    let [cx, cy] = [
        image.width() as f32 / 2.0 - 0.5,
        image.height() as f32 / 2.0 - 0.5,
    ];
    Projection::translate(cx + translate[0], cy + translate[1])
        * Projection::rotate(angle_deg.to_radians())
        * Projection::translate(-cx, -cy)
}

#[cfg(test)]
pub(crate) mod test_images {
    //! Synthetic images and measurements shared by the rotation and augmentation tests.
    use image::RgbImage;

    /// Index and value of the brightest pixel (sum of channels; first one on ties).
    pub(crate) fn brightest(image: &RgbImage) -> ((u32, u32), u32) {
        image
            .enumerate_pixels()
            .map(|(u, v, p)| ((u, v), p.0.iter().map(|&c| u32::from(c)).sum::<u32>()))
            .fold(
                ((0, 0), 0),
                |best, cur| if cur.1 > best.1 { cur } else { best },
            )
    }

    /// Brightness-weighted centroid, in continuous coordinates, of the pixels within `radius` of
    /// the brightest one.
    pub(crate) fn centroid_near(image: &RgbImage, around: (u32, u32), radius: i64) -> [f32; 2] {
        let (mut sx, mut sy, mut sw) = (0.0f64, 0.0f64, 0.0f64);
        for v in (around.1 as i64 - radius)..=(around.1 as i64 + radius) {
            for u in (around.0 as i64 - radius)..=(around.0 as i64 + radius) {
                if u < 0 || v < 0 || u >= image.width() as i64 || v >= image.height() as i64 {
                    continue;
                }
                let w: f64 = image
                    .get_pixel(u as u32, v as u32)
                    .0
                    .iter()
                    .map(|&c| f64::from(c))
                    .sum();
                sx += w * (u as f64 + 0.5);
                sy += w * (v as f64 + 0.5);
                sw += w;
            }
        }
        [(sx / sw) as f32, (sy / sw) as f32]
    }

    /// A black image with a white Gaussian blob (σ = 1.5 px, peak 255) centred on `at`.
    pub(crate) fn blob(size: u32, at: [f32; 2]) -> RgbImage {
        RgbImage::from_fn(size, size, |u, v| {
            let dx = u as f32 + 0.5 - at[0];
            let dy = v as f32 + 0.5 - at[1];
            let g = (-(dx * dx + dy * dy) / (2.0 * 1.5 * 1.5)).exp();
            let c = (255.0 * g).round() as u8;
            image::Rgb([c, c, c])
        })
    }

    /// A grasp at a uniformly random pixel with both coordinates in `range`, any angle.
    pub(crate) fn random_grasp(
        rng: &mut impl rand::Rng,
        range: std::ops::Range<u32>,
    ) -> crate::grasp::PixelGrasp {
        crate::grasp::PixelGrasp {
            u: rng.random_range(range.clone()),
            v: rng.random_range(range),
            angle_deg: rng.random_range(0.0..180.0),
        }
    }

    pub(crate) fn dist(a: [f32; 2], b: [f32; 2]) -> f32 {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::test_images::{brightest, centroid_near, dist};
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn rotate_point_turns_clockwise_about_the_centre() {
        // +90° takes the point right of the centre to below it (y down), and below to left.
        let p = rotate_point([74.0, 64.0], 90.0, 128);
        assert!(dist(p, [64.0, 74.0]) < 1e-4, "{p:?}");
        let p = rotate_point([64.0, 74.0], 90.0, 128);
        assert!(dist(p, [54.0, 64.0]) < 1e-4, "{p:?}");
        let p = rotate_point([64.0, 64.0], 37.0, 128);
        assert!(dist(p, [64.0, 64.0]) < 1e-5, "{p:?}");
    }

    #[test]
    fn rotating_by_b_then_minus_b_returns_points() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        for _ in 0..1000 {
            let p = [
                rng.random_range(-20.0..150.0),
                rng.random_range(-20.0..150.0),
            ];
            let b = rng.random_range(-360.0..360.0);
            let back = rotate_point(rotate_point(p, b, 128), -b, 128);
            assert!(dist(back, p) < 1e-4, "{p:?} by {b}: {back:?}");
        }
    }

    #[test]
    fn rotate_image_agrees_with_rotate_point() {
        for (u, v) in [(64, 64), (63, 63), (10, 20), (100, 30), (70, 115), (0, 64)] {
            for angle in [30.0, -30.0, 22.5, 67.5, 135.0, -11.0] {
                let mut image = RgbImage::new(128, 128);
                image.put_pixel(u, v, Rgb([255, 255, 255]));
                let rotated = rotate_image(&image, angle);
                let expected = rotate_point([u as f32 + 0.5, v as f32 + 0.5], angle, 128);
                if !(0.0..128.0).contains(&expected[0]) || !(0.0..128.0).contains(&expected[1]) {
                    continue;
                }
                let ((bu, bv), value) = brightest(&rotated);
                assert!(value > 0, "({u}, {v}) by {angle}° vanished");
                let (eu, ev) = (expected[0].floor(), expected[1].floor());
                assert!(
                    (bu as f32 - eu).abs() <= 1.0 && (bv as f32 - ev).abs() <= 1.0,
                    "({u}, {v}) by {angle}°: brightest ({bu}, {bv}), rotate_point {expected:?}"
                );
                // The centroid of the resampled dot is a sharper check of the same map.
                let c = centroid_near(&rotated, (bu, bv), 2);
                assert!(
                    dist(c, expected) < 0.35,
                    "({u}, {v}) by {angle}°: centroid {c:?}, rotate_point {expected:?}"
                );
            }
        }
    }

    #[test]
    fn quarter_and_half_turns_move_whole_pixels() {
        // The centre (64, 64) is a pixel corner, so 90° steps map pixels onto pixels: +90° must
        // equal imageproc's exact clockwise rotate90, and 180° must send (0, 0) to (127, 127).
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let image = RgbImage::from_fn(128, 128, |_, _| Rgb(rng.random::<[u8; 3]>()));
        let expected = imageproc::geometric_transformations::rotate90(&image);
        let rotated = rotate_image(&image, 90.0);
        for (a, b) in rotated.pixels().zip(expected.pixels()) {
            for (x, y) in a.0.iter().zip(b.0) {
                // imageproc truncates bilinear blends to u8, and sin/cos of f32 π/2 are not
                // exactly 1 and 0, so allow one level.
                assert!(x.abs_diff(y) <= 1, "{a:?} vs {b:?}");
            }
        }
        let mut corner = RgbImage::new(128, 128);
        corner.put_pixel(0, 0, Rgb([255, 255, 255]));
        assert_eq!(brightest(&rotate_image(&corner, 180.0)).0, (127, 127));
        assert_eq!(rotate_image(&image, 0.0), image);
    }

    #[test]
    fn an_unrotated_plane_puts_each_score_back_where_the_image_shows_it() {
        let size = 128;
        for bin in 0..crate::grasp::BINS {
            // A hot spot of map `bin`, peaking at (u, v), comes back peaking at the grasp pixel
            // that unrotate names (a lone pixel might fall between the image's samples).
            let (u, v) = (70, 40);
            let mut plane = vec![0.0; (size * size) as usize];
            for (du, dv) in (0..3).flat_map(|a| (0..3).map(move |b| (a, b))) {
                let near = if (du, dv) == (1, 1) { 1.0 } else { 0.5 };
                plane[((v + dv - 1) * size + u + du - 1) as usize] = near;
            }
            let back = unrotate_plane(&plane, size, bin_angle(bin));
            let g = unrotate(bin, u, v, size);
            let (best, _) = back
                .iter()
                .enumerate()
                .filter(|(_, x)| x.is_finite())
                .fold((0, f32::MIN), |b, (i, &x)| if x > b.1 { (i, x) } else { b });
            let (bu, bv) = (best as u32 % size, best as u32 / size);
            assert!(bu.abs_diff(g.u) <= 1 && bv.abs_diff(g.v) <= 1, "bin {bin}");
        }
        // A turned plane leaves its corners unscored; bin 0's is the plane itself.
        let ramp: Vec<f32> = (0..size * size).map(|i| i as f32).collect();
        assert!(unrotate_plane(&ramp, size, 45.0)[0].is_nan());
        assert_eq!(unrotate_plane(&ramp, size, 0.0), ramp);
    }

    #[test]
    fn imageproc_centre_is_half_a_pixel_off() {
        // Why rotate_image does not call rotate_about_center: that rotates about imageproc's
        // (64, 64), the centre of pixel (64, 64), which is (64.5, 64.5) in ours. A half
        // turn then sends pixel (0, 0) to (128, 128), off the image, instead of (127, 127).
        let mut corner = RgbImage::new(128, 128);
        corner.put_pixel(1, 1, Rgb([255, 255, 255]));
        let theirs = imageproc::geometric_transformations::rotate_about_center(
            &corner,
            std::f32::consts::PI,
            Interpolation::Bilinear,
            Border::Constant(Rgb([0, 0, 0])),
        );
        assert_eq!(brightest(&theirs).0, (127, 127));
        assert_eq!(brightest(&rotate_image(&corner, 180.0)).0, (126, 126));
    }
}
