//! An episode video made while the episode runs: one thread for the whole episode renders each
//! snapshot from the oblique view, sets the camera view beside it and feeds the encoder, so that
//! neither the physics nor the attempts wait for the video, and only the file's index is left
//! to write when the episode ends.

use std::path::Path;
use std::sync::mpsc::{channel, Receiver};
use std::thread::JoinHandle;

use anyhow::Context as _;
use image::RgbImage;

use super::mp4::Mp4Stream;
use super::{save_gif_atomic, VideoFormat};
use crate::data::atomic::write_atomic;
use crate::sim::recording::{Footage, FootageSender, ObliqueFilm};
use crate::sim::PHYSICS_HZ;

/// A video being recorded; [`EpisodeVideo::finish`] writes it.
pub(crate) struct EpisodeVideo {
    footage: FootageSender,
    worker: JoinHandle<anyhow::Result<Encoded>>,
}

/// What the recording thread leaves when the footage ends.
enum Encoded {
    /// The H.264 samples, waiting for their index (boxed: the encoder's state is large).
    Mp4(Box<Mp4Stream>),
    /// The frames: a GIF's palette is learnt from frames spread over the whole video.
    Gif(Vec<RgbImage>),
}

impl EpisodeVideo {
    /// Starts recording a video for `path` (its format from the extension), one frame every
    /// `every_steps` physics steps.
    pub(crate) fn start(path: &Path, every_steps: u64) -> anyhow::Result<Self> {
        let format = VideoFormat::of(path)?;
        let (footage, received) = channel();
        let worker = std::thread::Builder::new()
            .name("episode video".into())
            .spawn(move || record(format, every_steps, &received))
            .context("starting the video's thread")?;
        Ok(Self { footage, worker })
    }

    /// Where a workcell sends its snapshots ([`crate::sim::Workcell::record_into`]).
    pub(crate) fn footage(&self) -> FootageSender {
        self.footage.clone()
    }

    /// Shows `image` beside the oblique view from the next frame on.
    pub(crate) fn inset(&self, image: RgbImage) {
        // A thread that stopped listening has failed, and says why in `finish`.
        let _ = self.footage.send(Footage::Inset(image));
    }

    /// Waits for the frames still being made, then writes the video to `path` atomically.
    pub(crate) fn finish(self, path: &Path, every_steps: u64) -> anyhow::Result<()> {
        drop(self.footage);
        let encoded = self
            .worker
            .join()
            .map_err(|_| anyhow::anyhow!("the video's thread failed"))??;
        match encoded {
            Encoded::Mp4(video) => write_atomic(path, &video.finish()?),
            Encoded::Gif(frames) => {
                let delay_cs = (every_steps as f32 * 100.0 / PHYSICS_HZ).round() as u32;
                save_gif_atomic(&frames, delay_cs.max(1), path)
            }
        }
    }
}

/// The recording thread: every snapshot rendered, composed and encoded as it arrives.
fn record(
    format: VideoFormat,
    every_steps: u64,
    received: &Receiver<Footage>,
) -> anyhow::Result<Encoded> {
    let mut film = ObliqueFilm::new();
    let mut encoded = match format {
        // Ticks of the physics clock, so that every frame lasts exactly its steps.
        VideoFormat::Mp4 => Encoded::Mp4(Box::new(Mp4Stream::new(
            PHYSICS_HZ as u32,
            u32::try_from(every_steps.max(1)).unwrap_or(u32::MAX),
        ))),
        VideoFormat::Gif => Encoded::Gif(Vec::new()),
    };
    let mut inset: Option<RgbImage> = None;
    for footage in received {
        match footage {
            // Scaled once here, not for each of the attempt's frames.
            Footage::Inset(image) => inset = Some(square(&image, film.height())),
            Footage::Scene(snapshot) => {
                let oblique = film.frame(&snapshot);
                let frame = match &inset {
                    Some(inset) => side_by_side(&oblique, inset),
                    None => oblique,
                };
                match &mut encoded {
                    Encoded::Mp4(video) => video.push(&frame)?,
                    Encoded::Gif(frames) => frames.push(frame),
                }
            }
        }
    }
    Ok(encoded)
}

/// `image` scaled to `side` × `side`, the height of the oblique view.
fn square(image: &RgbImage, side: u32) -> RgbImage {
    image::imageops::resize(image, side, side, image::imageops::FilterType::Nearest)
}

/// A video frame: the oblique view, and beside it the inset of its height.
fn side_by_side(oblique: &RgbImage, inset: &RgbImage) -> RgbImage {
    let height = oblique.height().min(inset.height());
    let mut out = RgbImage::new(oblique.width() + inset.width(), height);
    if oblique.width() == 0 || inset.width() == 0 {
        return out;
    }
    // Row by row: `imageops::replace` copies pixel by pixel, which took longer than encoding.
    let left = 3 * oblique.width() as usize;
    let right = 3 * inset.width() as usize;
    let rows = out
        .chunks_exact_mut(left + right)
        .zip(oblique.chunks_exact(left))
        .zip(inset.chunks_exact(right));
    for ((row, a), b) in rows {
        row[..left].copy_from_slice(a);
        row[left..].copy_from_slice(b);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_inset_is_scaled_to_the_height_and_set_on_the_right() {
        let oblique = RgbImage::from_fn(6, 4, |x, y| image::Rgb([x as u8, y as u8, 7]));
        let camera = RgbImage::from_fn(8, 8, |x, y| image::Rgb([100 + x as u8, y as u8, 9]));
        let frame = side_by_side(&oblique, &square(&camera, 4));
        // What imageops' pixel-by-pixel copies of the same pictures give.
        let mut expected = RgbImage::new(10, 4);
        image::imageops::replace(&mut expected, &oblique, 0, 0);
        let scaled = image::imageops::resize(&camera, 4, 4, image::imageops::FilterType::Nearest);
        image::imageops::replace(&mut expected, &scaled, 6, 0);
        assert!(frame == expected);
    }
}
