//! Drawing a grasp on an image, as the reference marks one: the two finger points and the line between them.

use image::{Rgb, RgbImage};

use super::{fingers, PixelGrasp};

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
