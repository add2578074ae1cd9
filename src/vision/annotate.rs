//! Words on pictures: captions and the colour bar that states a heat picture's range, so that a
//! picture opened on its own still says what its colours mean.
//!
//! Text is drawn with plotters' ab_glyph renderer and the DejaVu Sans font the binary ships, so
//! no system font is needed and every machine draws the same pixels.

use image::{Rgb, RgbImage};
use plotters::prelude::*;

use super::colormap::{inferno, HeatRange};

/// The font family the pictures and the loss curve draw with.
pub(crate) const FONT: &str = "sans-serif";

/// Makes DejaVu Sans plotters' [`FONT`] (once per process).
pub(crate) fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
    });
}

/// The style of a picture's words: `px` pixels high, white.
fn style(px: u32) -> TextStyle<'static> {
    register_font();
    TextStyle::from((FONT, f64::from(px)).into_font()).color(&WHITE)
}

/// The width and height `text` takes in `style`.
fn text_size(text: &str, style: &TextStyle) -> (u32, u32) {
    style.font.box_size(text).unwrap_or((0, 0))
}

/// Writes `text` with its top-left corner at `at`, `px` pixels high, on a dark box that keeps it
/// legible over any image.
pub(crate) fn caption(image: &mut RgbImage, at: (i32, i32), text: &str, px: u32) {
    let style = style(px);
    let (tw, th) = text_size(text, &style);
    let pad = 2;
    let (w, h) = image.dimensions();
    let area = BitMapBackend::with_buffer(image, (w, h)).into_drawing_area();
    let corner = (
        at.0 + tw as i32 + 2 * pad,
        at.1 + th.max(px) as i32 + 2 * pad,
    );
    let _ = area.draw(&Rectangle::new([at, corner], BOX.filled()));
    let _ = area.draw_text(text, &style, (at.0 + pad, at.1 + pad));
    let _ = area.present();
}

/// The colour of the boxes and strips words are written on.
const BOX: RGBColor = RGBColor(20, 20, 20);

/// The strip under a heat picture: the colour bar from `range.lo` to `range.hi` with both ends
/// written beside it and the score its middle stands for (the scale is a square root's), then
/// `note`. Returns `image` with the strip added below.
pub(crate) fn with_heat_legend(image: &RgbImage, range: HeatRange, note: &str) -> RgbImage {
    const HEIGHT: u32 = 22;
    const BAR: i32 = 120;
    let (w, h) = image.dimensions();
    let mut out = RgbImage::from_pixel(w, h + HEIGHT, Rgb([BOX.0, BOX.1, BOX.2]));
    image::imageops::replace(&mut out, image, 0, 0);
    let style = style(13);
    let low = format!("{:.3}", range.lo);
    let x0 = 8 + text_size(&low, &style).0 as i32;
    let top = h as i32;
    let area = BitMapBackend::with_buffer(&mut out, (w, h + HEIGHT)).into_drawing_area();
    let _ = area.draw_text(&low, &style, (4, top + 4));
    for x in 0..BAR {
        let [r, g, b] = inferno(x as f32 / (BAR - 1) as f32);
        let column = [(x0 + x, top + 5), (x0 + x + 1, top + HEIGHT as i32 - 5)];
        let _ = area.draw(&Rectangle::new(column, RGBColor(r, g, b).filled()));
    }
    let rest = format!(
        "{:.3}  (√ scale: mid-bar {:.3})   {note}",
        range.hi,
        range.at(0.5)
    );
    let _ = area.draw_text(&rest, &style, (x0 + BAR + 4, top + 4));
    let _ = area.present();
    drop(area);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_caption_writes_light_pixels_on_a_dark_box_where_it_is_put() {
        let mut image = RgbImage::from_pixel(64, 32, Rgb([128, 128, 128]));
        caption(&mut image, (2, 2), "45°", 12);
        let light = image.pixels().filter(|p| p.0[0] > 200).count();
        assert!(light > 5, "the text is drawn");
        assert_eq!(image.get_pixel(2, 2).0, [20, 20, 20], "on its box");
        assert_eq!(image.get_pixel(60, 30).0, [128, 128, 128], "nothing else");
    }

    #[test]
    fn the_legend_adds_a_strip_with_the_colour_bar() {
        let image = RgbImage::from_pixel(300, 10, Rgb([0, 0, 0]));
        let out = with_heat_legend(&image, HeatRange { lo: 0.0, hi: 0.5 }, "note");
        assert_eq!(out.dimensions(), (300, 32));
        let hottest = out.pixels().filter(|p| p.0 == inferno(1.0)).count();
        assert!(hottest >= 10, "the bar's hot end is drawn");
    }
}
