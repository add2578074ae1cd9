//! Episode videos of the oblique view, written atomically: H.264 in MP4 (small, plays in every
//! browser) or an animated GIF, chosen by the file's extension.

pub(crate) mod episode;
mod mp4;

use std::path::Path;

use anyhow::Context;

use crate::data::atomic::write_atomic;
use crate::sim::PHYSICS_HZ;

/// What a `--record` file's extension asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum VideoFormat {
    /// H.264 in an MP4 container.
    Mp4,
    /// An animated GIF.
    Gif,
}

impl VideoFormat {
    /// The format of `path`, from its extension (any case); an error naming the value and the fix.
    pub(crate) fn of(path: &Path) -> anyhow::Result<Self> {
        let extension = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match extension.as_deref() {
            Some("mp4") => Ok(Self::Mp4),
            Some("gif") => Ok(Self::Gif),
            other => anyhow::bail!(
                "--record {}: {} is not a video format graspmap writes; end the name in .mp4 (H.264) or .gif",
                path.display(),
                other.map_or_else(|| "a name without an extension".to_string(), |e| format!("'.{e}'"))
            ),
        }
    }
}

/// Writes an episode video atomically, one frame every `every_steps` physics steps; the format
/// follows the extension ([`VideoFormat::of`]).
pub(crate) fn save_video_atomic(
    frames: &[image::RgbImage],
    every_steps: u64,
    path: &Path,
) -> anyhow::Result<()> {
    let started = std::time::Instant::now();
    let format = VideoFormat::of(path)?;
    let written = match format {
        VideoFormat::Mp4 => {
            // Ticks of the physics clock, so that every frame lasts exactly its steps.
            let ticks = u32::try_from(every_steps.max(1)).unwrap_or(u32::MAX);
            let bytes = mp4::encode_mp4(frames, PHYSICS_HZ as u32, ticks)
                .with_context(|| format!("encoding {}", path.display()))?;
            write_atomic(path, &bytes)
        }
        VideoFormat::Gif => {
            let delay_cs = (every_steps as f32 * 100.0 / PHYSICS_HZ).round() as u32;
            save_gif_atomic(frames, delay_cs.max(1), path)
        }
    };
    // GRASPMAP_LOG=debug: the encoding's own share of a recording (BENCHMARKS.md#videos-and-the-report).
    tracing::debug!(
        "{format:?}: {} frames encoded and written in {:.2} s",
        frames.len(),
        started.elapsed().as_secs_f64()
    );
    written
}

/// Writes an animated GIF atomically, `delay_cs` hundredths of a second per frame.
///
/// All frames share one palette, learnt (NeuQuant) from a few frames spread over the video, and
/// each pixel finds its palette entry through a 32 × 32 × 32 lookup table. The workcell's colours
/// barely change from frame to frame, and quantising every frame on its own took most of an
/// episode video's time (the encoding's share now: BENCHMARKS.md#videos-and-the-report).
fn save_gif_atomic(frames: &[image::RgbImage], delay_cs: u32, path: &Path) -> anyhow::Result<()> {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_extension_picks_the_format_and_others_are_refused() {
        assert_eq!(
            VideoFormat::of(Path::new("a/ep.mp4")).unwrap(),
            VideoFormat::Mp4
        );
        assert_eq!(
            VideoFormat::of(Path::new("EP.MP4")).unwrap(),
            VideoFormat::Mp4
        );
        assert_eq!(
            VideoFormat::of(Path::new("ep.gif")).unwrap(),
            VideoFormat::Gif
        );
        let avi = VideoFormat::of(Path::new("ep.avi"))
            .unwrap_err()
            .to_string();
        assert!(
            avi.contains("ep.avi") && avi.contains("'.avi'") && avi.contains(".mp4"),
            "{avi}"
        );
        let bare = VideoFormat::of(Path::new("episode"))
            .unwrap_err()
            .to_string();
        assert!(bare.contains("without an extension"), "{bare}");
    }
}
