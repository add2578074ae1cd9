//! Result files: atomic writes (temp file, then rename) and the versioned JSON envelope every command emits.

use std::io::Write;
use std::path::Path;

use anyhow::Context;
use serde::Serialize;

/// Writes `bytes` to `path` atomically: a killed process leaves either the old file or the new one.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let file_name = path
        .file_name()
        .with_context(|| format!("{} is not a file path", path.display()))?;
    let tmp = dir.join(format!(
        ".{}.tmp-{}",
        file_name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| {
        let mut file =
            std::fs::File::create(&tmp).with_context(|| format!("creating {}", tmp.display()))?;
        file.write_all(bytes)
            .and_then(|_| file.sync_all())
            .with_context(|| format!("writing {}", tmp.display()))?;
        std::fs::rename(&tmp, path).with_context(|| format!("replacing {}", path.display()))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Saves an image atomically; the format follows the extension.
pub fn save_image_atomic<P, C>(image: &image::ImageBuffer<P, C>, path: &Path) -> anyhow::Result<()>
where
    P: image::PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
    C: std::ops::Deref<Target = [P::Subpixel]>,
{
    let format = image::ImageFormat::from_path(path)
        .with_context(|| format!("{}: unknown image extension (use .png)", path.display()))?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write_to(&mut bytes, format)
        .with_context(|| format!("encoding {}", path.display()))?;
    write_atomic(path, bytes.get_ref())
}

/// Writes an animated GIF atomically, `delay_cs` hundredths of a second per frame.
///
/// All frames share one palette, learnt (NeuQuant) from a few frames spread over the video, and
/// each pixel finds its palette entry through a 32 × 32 × 32 lookup table. The workcell's colours
/// barely change from frame to frame, and quantising every frame on its own took most of an
/// episode video's time (25 s of 2,500 frames against about 3 s this way).
pub fn save_gif_atomic(
    frames: &[image::RgbImage],
    delay_cs: u32,
    path: &Path,
) -> anyhow::Result<()> {
    let Some(first) = frames.first() else {
        anyhow::bail!("{}: a video needs at least one frame", path.display());
    };
    let (width, height) = first.dimensions();
    let too_big = || {
        format!(
            "{}: frames of {width}×{height} are too large for a GIF",
            path.display()
        )
    };
    let gif_width = u16::try_from(width).ok().with_context(too_big)?;
    let gif_height = u16::try_from(height).ok().with_context(too_big)?;
    let samples = 8.min(frames.len());
    let mut training = Vec::new();
    for k in 0..samples {
        let frame = &frames[k * frames.len() / samples];
        training.extend(frame.pixels().flat_map(|p| [p[0], p[1], p[2], 255]));
    }
    let quantiser = color_quant::NeuQuant::new(10, 256, &training);
    let bucket = |c: u8| usize::from(c >> 3);
    let lookup: Vec<u8> = (0..32 * 32 * 32)
        .map(|i: usize| {
            let centre = |shift: usize| (((i >> shift) & 31) << 3 | 4) as u8;
            quantiser.index_of(&[centre(10), centre(5), centre(0), 255]) as u8
        })
        .collect();
    let mut bytes = Vec::new();
    {
        let mut encoder = gif::Encoder::new(
            &mut bytes,
            gif_width,
            gif_height,
            &quantiser.color_map_rgb(),
        )
        .with_context(|| format!("encoding {}", path.display()))?;
        encoder
            .set_repeat(gif::Repeat::Infinite)
            .with_context(|| format!("encoding {}", path.display()))?;
        for frame in frames {
            anyhow::ensure!(
                frame.dimensions() == (width, height),
                "{}: frames differ in size ({}×{} after {width}×{height})",
                path.display(),
                frame.width(),
                frame.height()
            );
            let indices: Vec<u8> = frame
                .pixels()
                .map(|p| lookup[bucket(p[0]) << 10 | bucket(p[1]) << 5 | bucket(p[2])])
                .collect();
            let mut gif_frame =
                gif::Frame::from_indexed_pixels(gif_width, gif_height, indices, None);
            gif_frame.delay = u16::try_from(delay_cs).unwrap_or(u16::MAX);
            encoder
                .write_frame(&gif_frame)
                .with_context(|| format!("encoding {}", path.display()))?;
        }
    }
    write_atomic(path, &bytes)
}

/// The envelope of every `--json` report.
#[derive(Debug, Serialize)]
pub struct Report<'a, C: Serialize, R: Serialize> {
    /// `graspmap.<command>/1`.
    pub schema: String,
    /// Crate version.
    pub version: &'static str,
    /// Git commit the binary was built from.
    pub git_commit: &'static str,
    /// Seeds that drove the run.
    pub seed: u64,
    /// The fully resolved configuration.
    pub config: &'a C,
    /// The command's results.
    pub results: &'a R,
}

/// Writes a report to `target` (`-` = stdout) with schema `graspmap.<command>/1`.
pub fn write_report<C: Serialize, R: Serialize>(
    target: &Path,
    command: &str,
    seed: u64,
    config: &C,
    results: &R,
) -> anyhow::Result<()> {
    let report = Report {
        schema: format!("graspmap.{command}/1"),
        version: env!("CARGO_PKG_VERSION"),
        git_commit: env!("GRASPMAP_GIT_COMMIT"),
        seed,
        config,
        results,
    };
    let mut text = serde_json::to_string_pretty(&report)?;
    text.push('\n');
    if target == Path::new("-") {
        std::io::stdout().write_all(text.as_bytes())?;
        Ok(())
    } else {
        write_atomic(target, text.as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_and_leaves_no_temp_files() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.json");
        write_atomic(&path, b"one").unwrap();
        write_atomic(&path, b"two").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"two");
        let entries: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(entries.len(), 1);
    }
}
