//! Colour maps for showing scalar fields (affordance maps) as images: the heat colours, the range
//! a picture's colours span, and the heat drawn over the camera's image.

use image::{Rgb, RgbImage};

/// Matplotlib's inferno colour map at `value` in [0, 1] (clamped; NaN is 0): black through red
/// to pale yellow, its lightness rising all the way, so the hottest spot is also the brightest.
pub(crate) fn inferno(value: f32) -> [u8; 3] {
    // Eleven samples of the published map, linearly interpolated: indistinguishable at 8 bits
    // for display, and no lookup-table crate needed.
    const STOPS: [[f32; 3]; 11] = [
        [0.0, 0.0, 4.0],
        [22.0, 11.0, 57.0],
        [66.0, 10.0, 104.0],
        [106.0, 23.0, 110.0],
        [147.0, 38.0, 103.0],
        [188.0, 55.0, 84.0],
        [221.0, 81.0, 58.0],
        [243.0, 120.0, 25.0],
        [252.0, 165.0, 10.0],
        [246.0, 215.0, 70.0],
        [252.0, 255.0, 164.0],
    ];
    let v = if value.is_finite() {
        value.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = v * (STOPS.len() - 1) as f32;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let t = x - i as f32;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    [0, 1, 2].map(|c| (a[c] + (b[c] - a[c]) * t).round() as u8)
}

/// The scores a picture's colours span: `lo` is drawn as no heat, `hi` as the hottest colour, on
/// a square-root scale. A trained network's maps sit near 0 with a peak on a few pixels (its
/// targets are 1 px wide), so a fixed linear 0–1 scale shows a dark square with a dot: each
/// picture is scaled to its own range, and the square root lifts the runners-up (a tenth of the
/// peak shows a third of the way up the colours) into sight. The legend states both.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct HeatRange {
    /// The lowest score shown.
    pub(crate) lo: f32,
    /// The highest score shown.
    pub(crate) hi: f32,
}

impl HeatRange {
    /// The smallest and largest finite value; 0–1 when there is none.
    pub(crate) fn of(values: impl IntoIterator<Item = f32>) -> Self {
        let (lo, hi) = values
            .into_iter()
            .filter(|v| v.is_finite())
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        if lo <= hi {
            Self { lo, hi }
        } else {
            Self { lo: 0.0, hi: 1.0 }
        }
    }

    /// `value`'s place on the colour scale, 0–1: the square root of its fraction of the range.
    /// NaN (no score there) stays NaN, and a flat range (every score equal) shows no heat.
    pub(crate) fn place(&self, value: f32) -> f32 {
        if value.is_nan() {
            return f32::NAN;
        }
        let span = self.hi - self.lo;
        if span <= f32::EPSILON {
            return 0.0;
        }
        ((value - self.lo) / span).clamp(0.0, 1.0).sqrt()
    }

    /// The score at `place` on the colour scale (the inverse of [`HeatRange::place`]).
    pub(crate) fn at(&self, place: f32) -> f32 {
        self.lo + place * place * (self.hi - self.lo)
    }
}

/// One pixel of the heat overlay: the camera's colour turned grey and dimmed (so that a yellow
/// object never reads as heat), then the inferno colour of `place` (0–1 in the picture's range)
/// laid over it, the more opaque the hotter. NaN (no score) leaves the dimmed grey alone.
pub(crate) fn heat_over(rgb: [u8; 3], place: f32) -> [u8; 3] {
    let luma = 0.299 * f32::from(rgb[0]) + 0.587 * f32::from(rgb[1]) + 0.114 * f32::from(rgb[2]);
    let grey = 0.6 * luma;
    if !place.is_finite() {
        return [grey.round() as u8; 3];
    }
    // Nearly opaque from a third of the range up, so that the runners-up show as well as the
    // peak; below that the heat fades out into the image.
    let alpha = 0.9 * (3.0 * place).min(1.0);
    let heat = inferno(place);
    heat.map(|c| (grey + (f32::from(c) - grey) * alpha).round() as u8)
}

/// The heat overlay of a `size` × `size` field (row-major, NaN where nothing was scored) on the
/// camera's image of the same size, enlarged `scale` times: the image's pixels as blocks, the
/// field sampled bilinearly so that the heat stays smooth.
pub(crate) fn heat_overlay(
    rgb: &RgbImage,
    field: &[f32],
    range: HeatRange,
    scale: u32,
) -> RgbImage {
    let size = rgb.width();
    assert_eq!(
        field.len(),
        (size * rgb.height()) as usize,
        "one score a pixel"
    );
    RgbImage::from_fn(size * scale, rgb.height() * scale, |x, y| {
        let (u, v) = (x / scale, y / scale);
        let at = [
            (x as f32 + 0.5) / scale as f32,
            (y as f32 + 0.5) / scale as f32,
        ];
        let value = sample_bilinear(field, size, at);
        Rgb(heat_over(rgb.get_pixel(u, v).0, range.place(value)))
    })
}

/// The value of a row-major `size`-wide square field at continuous point `p` (pixel (u, v)
/// covers [u, u+1) × [v, v+1)): bilinear between pixel centres, clamped at the edges; NaN
/// outside the field or where a neighbour is NaN.
pub(crate) fn sample_bilinear(field: &[f32], size: u32, p: [f32; 2]) -> f32 {
    let side = size as f32;
    if !(0.0..side).contains(&p[0]) || !(0.0..side).contains(&p[1]) {
        return f32::NAN;
    }
    let last = size as i64 - 1;
    let x = p[0] - 0.5;
    let y = p[1] - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (tx, ty) = (x - x0, y - y0);
    let at = |u: f32, v: f32| {
        let u = (u as i64).clamp(0, last) as usize;
        let v = (v as i64).clamp(0, last) as usize;
        field[v * size as usize + u]
    };
    let top = at(x0, y0) * (1.0 - tx) + at(x0 + 1.0, y0) * tx;
    let bottom = at(x0, y0 + 1.0) * (1.0 - tx) + at(x0 + 1.0, y0 + 1.0) * tx;
    top * (1.0 - ty) + bottom * ty
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inferno_runs_from_black_to_pale_yellow() {
        assert_eq!(inferno(0.0), [0, 0, 4]);
        assert_eq!(inferno(1.0), [252, 255, 164]);
        assert_eq!(inferno(-3.0), inferno(0.0));
        assert_eq!(inferno(f32::NAN), inferno(0.0));
        assert_eq!(inferno(0.5), [188, 55, 84]);
        // Lightness rises all the way: the hottest is the brightest.
        let luma = |c: [u8; 3]| u32::from(c[0]) * 3 + u32::from(c[1]) * 6 + u32::from(c[2]);
        for k in 0..10 {
            let (a, b) = (k as f32 / 10.0, (k + 1) as f32 / 10.0);
            assert!(luma(inferno(a)) < luma(inferno(b)), "{a} → {b}");
        }
    }

    #[test]
    fn a_range_spans_its_values_and_places_them() {
        let range = HeatRange::of([0.02, f32::NAN, 0.1, 0.06]);
        assert_eq!(range, HeatRange { lo: 0.02, hi: 0.1 });
        // Halfway through the range is 1/√2 of the way up the colours.
        assert!((range.place(0.06) - 0.5f32.sqrt()).abs() < 1e-6);
        assert!((range.at(range.place(0.04)) - 0.04).abs() < 1e-6);
        assert_eq!(range.place(1.0), 1.0);
        assert!(range.place(f32::NAN).is_nan());
        assert_eq!(HeatRange::of([0.3, 0.3]).place(0.3), 0.0, "flat: no heat");
        assert_eq!(HeatRange::of([f32::NAN]), HeatRange { lo: 0.0, hi: 1.0 });
    }

    #[test]
    fn the_overlay_dims_the_image_and_paints_the_peak_hot() {
        let rgb = RgbImage::from_pixel(4, 4, Rgb([250, 250, 0]));
        let mut field = vec![0.0; 16];
        field[5] = 1.0;
        let out = heat_overlay(&rgb, &field, HeatRange::of(field.iter().copied()), 2);
        assert_eq!(out.dimensions(), (8, 8));
        // Away from the peak: the yellow image as a dim grey, no heat.
        let far = out.get_pixel(7, 7).0;
        assert!(
            far[0] == far[1] && far[1] == far[2] && far[0] < 160,
            "{far:?}"
        );
        // Beside the peak's centre (pixel (1, 1), enlarged to 2..4): hot, and red in colour.
        let hot = out.get_pixel(3, 3).0;
        assert!(
            hot[0] > 180 && hot[0] > far[0] + 80 && hot[2] < 100,
            "{hot:?}"
        );
        assert!(sample_bilinear(&field, 4, [5.0, 1.0]).is_nan(), "outside");
    }
}
