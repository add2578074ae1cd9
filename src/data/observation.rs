//! A user's observation for `predict`: a 128 × 128 8-bit RGB image (PNG or JPEG), decoded from
//! bytes with a size limit, or a one-line error that says what is wrong and how to fix it.

use std::path::Path;

use anyhow::{bail, Context as _};
use image::RgbImage;

use crate::grasp::IMAGE_SIZE;

/// Largest image side decoded before the check for 128 × 128 (px).
const MAX_DECODED_SIDE: u32 = 4096;

/// Reads a 128 × 128 8-bit RGB image (an opaque RGBA one is accepted), or says what is wrong.
pub(crate) fn read_observation(path: &Path) -> anyhow::Result<RgbImage> {
    let bytes =
        std::fs::read(path).with_context(|| format!("cannot open --image {}", path.display()))?;
    decode_observation(&bytes, path)
}

/// Decodes an observation from its bytes (PNG or JPEG, by content); `path` names it in errors.
pub(crate) fn decode_observation(bytes: &[u8], path: &Path) -> anyhow::Result<RgbImage> {
    let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .with_context(|| format!("cannot read --image {}", path.display()))?;
    // A header may claim any size; nothing near this is a camera image.
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_DECODED_SIDE);
    limits.max_image_height = Some(MAX_DECODED_SIDE);
    reader.limits(limits);
    let decoded = reader.decode().with_context(|| {
        format!(
            "--image {} is not a readable image (give a PNG or JPEG)",
            path.display()
        )
    })?;
    let (w, h) = (decoded.width(), decoded.height());
    if (w, h) != (IMAGE_SIZE, IMAGE_SIZE) {
        bail!(
            "--image {} is {w}×{h}; the model needs {IMAGE_SIZE}×{IMAGE_SIZE} top-down camera images (resize or crop it)",
            path.display()
        );
    }
    match decoded {
        image::DynamicImage::ImageRgb8(rgb) => Ok(rgb),
        image::DynamicImage::ImageRgba8(rgba) => {
            if rgba.pixels().any(|p| p.0[3] != 255) {
                bail!(
                    "--image {} has transparent pixels; save it as 8-bit RGB without alpha",
                    path.display()
                );
            }
            Ok(image::DynamicImage::ImageRgba8(rgba).into_rgb8())
        }
        other => bail!(
            "--image {} is {}, not 8-bit RGB; save it as 8-bit RGB",
            path.display(),
            colour_words(other.color())
        ),
    }
}

/// An image's colour type as people say it: "8-bit greyscale", "16-bit RGB with alpha".
fn colour_words(colour: image::ColorType) -> String {
    use image::ColorType as C;
    let (bits, channels) = match colour {
        C::L8 => ("8-bit", "greyscale"),
        C::La8 => ("8-bit", "greyscale with alpha"),
        C::Rgb8 => ("8-bit", "RGB"),
        C::Rgba8 => ("8-bit", "RGB with alpha"),
        C::L16 => ("16-bit", "greyscale"),
        C::La16 => ("16-bit", "greyscale with alpha"),
        C::Rgb16 => ("16-bit", "RGB"),
        C::Rgba16 => ("16-bit", "RGB with alpha"),
        C::Rgb32F => ("32-bit float", "RGB"),
        C::Rgba32F => ("32-bit float", "RGB with alpha"),
        other => return format!("{other:?}"),
    };
    format!("{bits} {channels}")
}

#[cfg(test)]
mod fuzz {
    use std::path::Path;

    use proptest::prelude::*;

    use crate::data::fuzzing::{check, config, edits, mutate};

    const OBSERVATION_PNG: &[u8] =
        include_bytes!("../../tests/fixtures/reference-labels/YcbHammer_1_rgb.png");

    fn observation_jpeg() -> &'static [u8] {
        static BYTES: std::sync::LazyLock<Vec<u8>> = std::sync::LazyLock::new(|| {
            let image =
                image::RgbImage::from_fn(128, 128, |u, v| image::Rgb([u as u8, v as u8, 90]));
            let mut bytes = std::io::Cursor::new(Vec::new());
            image
                .write_to(&mut bytes, image::ImageFormat::Jpeg)
                .unwrap();
            bytes.into_inner()
        });
        &BYTES
    }

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn fuzz_png_observation(edits in edits()) {
            let input = mutate(OBSERVATION_PNG, &edits);
            check(|| crate::data::observation::decode_observation(&input, Path::new("image.png")))?;
        }

        #[test]
        fn fuzz_jpeg_observation(edits in edits()) {
            let input = mutate(observation_jpeg(), &edits);
            check(|| crate::data::observation::decode_observation(&input, Path::new("image.jpg")))?;
        }
    }
}
