//! Episode videos as H.264 in an MP4 file: OpenH264 (built from its bundled source) encodes,
//! the `mp4` crate writes the ISO-BMFF boxes, and [`fast_start`] moves the index (`moov`) in
//! front of the media data, so that a browser can start playing before it has the whole file.

use std::io::Cursor;

use anyhow::{bail, ensure, Context};
use openh264::encoder::{
    Complexity, Encoder, EncoderConfig, FrameRate, FrameType, IntraFramePeriod, QpRange,
    RateControlMode,
};
use openh264::formats::{RgbSliceU8, YUVBuffer};
use openh264::OpenH264API;

/// The quantiser of every frame (no rate control: constant quality, and no encoder decision
/// that depends on anything but the frames).
const QP: u8 = 30;
/// A key frame every 10 s of video at 10 fps, so that seeking in a player stays quick.
const KEY_FRAME_EVERY: u32 = 100;

/// One encoded frame: its NAL units in MP4's length-prefixed form.
struct Sample {
    bytes: Vec<u8>,
    key: bool,
    /// Duration in track ticks (a skipped frame lengthens the one before it).
    ticks: u32,
}

/// Encodes `frames` (all the same even size) as H.264 in MP4, each shown `frame_ticks` ticks of
/// a `timescale` Hz clock. Deterministic: one thread, no timing-driven decisions.
pub(crate) fn encode_mp4(
    frames: &[image::RgbImage],
    timescale: u32,
    frame_ticks: u32,
) -> anyhow::Result<Vec<u8>> {
    let mut video = Mp4Stream::new(timescale, frame_ticks);
    for frame in frames {
        video.push(frame)?;
    }
    video.finish()
}

/// An MP4 being encoded a frame at a time, so that a recording can encode while it films and
/// hold compressed samples rather than raw frames; the bytes are those of [`encode_mp4`] on
/// the same frames.
pub(crate) struct Mp4Stream {
    timescale: u32,
    frame_ticks: u32,
    /// Started by the first frame, whose size every later frame must have.
    encoder: Option<(Encoder, u32, u32)>,
    sps: Option<Vec<u8>>,
    pps: Option<Vec<u8>>,
    samples: Vec<Sample>,
    /// Frames pushed so far.
    frames: u64,
}

impl Mp4Stream {
    /// A video whose frames each last `frame_ticks` ticks of a `timescale` Hz clock.
    pub(crate) fn new(timescale: u32, frame_ticks: u32) -> Self {
        Self {
            timescale,
            frame_ticks,
            encoder: None,
            sps: None,
            pps: None,
            samples: Vec::new(),
            frames: 0,
        }
    }

    /// Encodes the next frame.
    pub(crate) fn push(&mut self, frame: &image::RgbImage) -> anyhow::Result<()> {
        let (timescale, frame_ticks) = (self.timescale, self.frame_ticks);
        let (encoder, width, height) = match &mut self.encoder {
            Some(started) => started,
            None => self
                .encoder
                .insert(start_encoder(frame, timescale, frame_ticks)?),
        };
        let (width, height) = (*width, *height);
        let i = self.frames;
        ensure!(
            frame.dimensions() == (width, height),
            "frames differ in size ({}×{} after {width}×{height})",
            frame.width(),
            frame.height()
        );
        let rgb = RgbSliceU8::new(frame.as_raw(), (width as usize, height as usize));
        let yuv = YUVBuffer::from_rgb8_source(rgb);
        let millis = i * u64::from(frame_ticks) * 1000 / u64::from(timescale.max(1));
        let stream = encoder
            .encode_at(&yuv, openh264::Timestamp::from_millis(millis))
            .with_context(|| format!("encoding frame {i}"))?;
        let mut sample = Sample {
            bytes: Vec::new(),
            key: stream.frame_type() == FrameType::IDR,
            ticks: frame_ticks,
        };
        for layer in (0..stream.num_layers()).filter_map(|l| stream.layer(l)) {
            for nal in (0..layer.nal_count()).filter_map(|n| layer.nal_unit(n)) {
                let nal = strip_start_code(nal);
                match nal.first().map(|b| b & 0x1f) {
                    // Parameter sets live once in the track's avcC box, not in the samples.
                    Some(7) => drop(self.sps.get_or_insert_with(|| nal.to_vec())),
                    Some(8) => drop(self.pps.get_or_insert_with(|| nal.to_vec())),
                    Some(_) => {
                        sample.bytes.extend((nal.len() as u32).to_be_bytes());
                        sample.bytes.extend_from_slice(nal);
                    }
                    None => {}
                }
            }
        }
        match self.samples.last_mut() {
            Some(previous) if sample.bytes.is_empty() => previous.ticks += frame_ticks,
            _ => self.samples.push(sample),
        }
        self.frames += 1;
        Ok(())
    }

    /// The frames pushed so far, as an MP4 file's bytes (index first).
    pub(crate) fn finish(self) -> anyhow::Result<Vec<u8>> {
        let Some((_, width, height)) = self.encoder else {
            bail!("a video needs at least one frame");
        };
        let (Some(sps), Some(pps)) = (self.sps, self.pps) else {
            bail!("the H.264 encoder produced no parameter sets");
        };
        let avc = mp4::AvcConfig {
            width: u16::try_from(width)?,
            height: u16::try_from(height)?,
            seq_param_set: sps,
            pic_param_set: pps,
        };
        fast_start(&mux(avc, self.timescale, &self.samples)?)
    }
}

/// An encoder for frames the size of `first`, which H.264 here must accept.
fn start_encoder(
    first: &image::RgbImage,
    timescale: u32,
    frame_ticks: u32,
) -> anyhow::Result<(Encoder, u32, u32)> {
    let (width, height) = first.dimensions();
    ensure!(
        width % 2 == 0 && height % 2 == 0 && width <= 3840 && height <= 2160,
        "frames of {width}×{height} cannot be H.264 here (even sizes up to 3840×2160 only)"
    );
    let fps = timescale as f32 / frame_ticks.max(1) as f32;
    let config = EncoderConfig::new()
        .rate_control_mode(RateControlMode::Off)
        .qp(QpRange::new(QP, QP))
        .max_frame_rate(FrameRate::from_hz(fps))
        .skip_frames(false)
        .complexity(Complexity::Low)
        .intra_frame_period(IntraFramePeriod::from_num_frames(KEY_FRAME_EVERY))
        .num_threads(1);
    let encoder = Encoder::with_api_config(OpenH264API::from_source(), config)
        .context("starting the H.264 encoder")?;
    Ok((encoder, width, height))
}

/// The NAL unit without its Annex B start code (`00 00 01` or `00 00 00 01`).
fn strip_start_code(nal: &[u8]) -> &[u8] {
    let zeros = nal.iter().take_while(|&&b| b == 0).count();
    if zeros >= 2 && nal.get(zeros) == Some(&1) {
        &nal[zeros + 1..]
    } else {
        nal
    }
}

/// Writes the samples as one video track.
fn mux(avc: mp4::AvcConfig, timescale: u32, samples: &[Sample]) -> anyhow::Result<Vec<u8>> {
    let brand = |s: &str| s.parse::<mp4::FourCC>().expect("four ASCII letters");
    let config = mp4::Mp4Config {
        major_brand: brand("isom"),
        minor_version: 512,
        compatible_brands: ["isom", "iso2", "avc1", "mp41"].map(brand).to_vec(),
        timescale,
    };
    let mut writer = mp4::Mp4Writer::write_start(Cursor::new(Vec::new()), &config)?;
    writer.add_track(&mp4::TrackConfig {
        track_type: mp4::TrackType::Video,
        timescale,
        language: "und".into(),
        media_conf: mp4::MediaConfig::AvcConfig(avc),
    })?;
    let mut start = 0u64;
    for sample in samples {
        writer.write_sample(
            1,
            &mp4::Mp4Sample {
                start_time: start,
                duration: sample.ticks,
                rendering_offset: 0,
                is_sync: sample.key,
                bytes: sample.bytes.clone().into(),
            },
        )?;
        start += u64::from(sample.ticks);
    }
    writer.write_end()?;
    Ok(writer.into_writer().into_inner())
}

/// One ISO-BMFF box: its type and where it lies (header included) in the buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct BoxSpan {
    kind: [u8; 4],
    start: usize,
    /// Where its content begins (after the header).
    body: usize,
    end: usize,
}

/// The boxes that follow one another in `data[from..to]`; an error when a size does not fit.
fn boxes(data: &[u8], from: usize, to: usize) -> anyhow::Result<Vec<BoxSpan>> {
    let mut spans = Vec::new();
    let mut at = from;
    while at < to {
        ensure!(to - at >= 8, "a box header at byte {at} is cut short");
        let word = |i: usize| u32::from_be_bytes(data[i..i + 4].try_into().expect("4 bytes"));
        let kind: [u8; 4] = data[at + 4..at + 8].try_into().expect("4 bytes");
        let (size, header) = match word(at) {
            0 => (to - at, 8),
            1 => {
                ensure!(
                    to - at >= 16,
                    "a large box header at byte {at} is cut short"
                );
                let large = u64::from(word(at + 8)) << 32 | u64::from(word(at + 12));
                (usize::try_from(large)?, 16)
            }
            n => (n as usize, 8),
        };
        ensure!(
            size >= header && size <= to - at,
            "box '{}' at byte {at} claims {size} bytes, {} are left",
            String::from_utf8_lossy(&kind),
            to - at
        );
        spans.push(BoxSpan {
            kind,
            start: at,
            body: at + header,
            end: at + size,
        });
        at += size;
    }
    Ok(spans)
}

/// The first box of type `kind` among `spans`.
fn find(spans: &[BoxSpan], kind: &[u8; 4]) -> anyhow::Result<BoxSpan> {
    spans
        .iter()
        .find(|s| &s.kind == kind)
        .copied()
        .with_context(|| format!("no '{}' box", String::from_utf8_lossy(kind)))
}

/// Follows a path of container boxes from the top level, e.g. moov/trak/mdia/minf/stbl.
#[cfg(test)]
fn descend(data: &[u8], path: &[&[u8; 4]]) -> anyhow::Result<BoxSpan> {
    let mut span = BoxSpan {
        kind: *b"root",
        start: 0,
        body: 0,
        end: data.len(),
    };
    for kind in path {
        span = find(&boxes(data, span.body, span.end)?, kind)?;
    }
    Ok(span)
}

/// Rewrites `ftyp mdat moov` as `ftyp moov mdat`, shifting the chunk offsets (`stco`) by the
/// size of `moov`: players read the index first and start at once ("fast start").
fn fast_start(data: &[u8]) -> anyhow::Result<Vec<u8>> {
    let top = boxes(data, 0, data.len())?;
    let (ftyp, mdat, moov) = (
        find(&top, b"ftyp")?,
        find(&top, b"mdat")?,
        find(&top, b"moov")?,
    );
    ensure!(
        ftyp.end == mdat.start && mdat.end == moov.start && moov.end == data.len(),
        "unexpected box order from the MP4 writer"
    );
    let shift = u32::try_from(moov.end - moov.start)?;
    let mut moved = data[moov.start..moov.end].to_vec();
    let traks = boxes(&moved, 8, moved.len())?;
    for trak in traks.iter().filter(|b| &b.kind == b"trak") {
        let mut span = *trak;
        for kind in [b"mdia", b"minf", b"stbl"] {
            span = find(&boxes(&moved, span.body, span.end)?, kind)?;
        }
        let tables = boxes(&moved, span.body, span.end)?;
        ensure!(
            find(&tables, b"co64").is_err(),
            "64-bit chunk offsets are not expected in an episode video"
        );
        let stco = find(&tables, b"stco")?;
        let count = u32::from_be_bytes(moved[stco.body + 4..stco.body + 8].try_into()?) as usize;
        ensure!(stco.body + 8 + 4 * count <= stco.end, "stco is cut short");
        for k in 0..count {
            let at = stco.body + 8 + 4 * k;
            let offset = u32::from_be_bytes(moved[at..at + 4].try_into()?);
            let shifted = offset.checked_add(shift).context("chunk offset overflow")?;
            moved[at..at + 4].copy_from_slice(&shifted.to_be_bytes());
        }
    }
    let mut out = Vec::with_capacity(data.len());
    out.extend_from_slice(&data[..ftyp.end]);
    out.extend_from_slice(&moved);
    out.extend_from_slice(&data[mdat.start..mdat.end]);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frames of a square moving over a grey floor.
    fn moving_square(n: u32) -> Vec<image::RgbImage> {
        (0..n)
            .map(|i| {
                image::RgbImage::from_fn(64, 48, |x, y| {
                    let inside = (x + 64 - 2 * i % 64) % 64 < 12 && (10..22).contains(&y);
                    if inside {
                        image::Rgb([200, 40, 30])
                    } else {
                        image::Rgb([90, 90, 100])
                    }
                })
            })
            .collect()
    }

    fn u32_at(data: &[u8], at: usize) -> u32 {
        u32::from_be_bytes(data[at..at + 4].try_into().unwrap())
    }

    #[test]
    fn the_index_comes_first_and_points_at_the_frames_in_mdat() {
        let frames = moving_square(25);
        let data = encode_mp4(&frames, 240, 24).unwrap();
        let top = boxes(&data, 0, data.len()).unwrap();
        let kinds: Vec<&[u8; 4]> = top.iter().map(|b| &b.kind).collect();
        assert_eq!(kinds, [b"ftyp", b"moov", b"mdat"]);
        assert_eq!(&data[8..12], b"isom");
        let stbl = descend(&data, &[b"moov", b"trak", b"mdia", b"minf", b"stbl"]).unwrap();
        let tables = boxes(&data, stbl.body, stbl.end).unwrap();
        // stsd holds one avc1 entry whose avcC carries the encoder's SPS (NAL type 7).
        let stsd = find(&tables, b"stsd").unwrap();
        let avc1 = find(&boxes(&data, stsd.body + 8, stsd.end).unwrap(), b"avc1").unwrap();
        assert_eq!(
            u16::from_be_bytes([data[avc1.body + 24], data[avc1.body + 25]]),
            64
        );
        let avcc = find(&boxes(&data, avc1.body + 78, avc1.end).unwrap(), b"avcC").unwrap();
        assert_eq!(data[avcc.body], 1, "avcC version");
        assert_eq!(data[avcc.body + 8] & 0x1f, 7, "the SPS");
        // One sample per frame (nothing skipped here), each 24 ticks of 240 Hz.
        let stsz = find(&tables, b"stsz").unwrap();
        assert_eq!(u32_at(&data, stsz.body + 8), 25);
        let stts = find(&tables, b"stts").unwrap();
        assert_eq!(u32_at(&data, stts.body + 4), 1);
        assert_eq!(u32_at(&data, stts.body + 8), 25);
        assert_eq!(u32_at(&data, stts.body + 12), 24);
        // The first chunk offset lands inside mdat on a length-prefixed NAL unit of a key frame
        // (IDR slice, type 5) that fills the first sample exactly.
        let mdat = find(&top, b"mdat").unwrap();
        let stco = find(&tables, b"stco").unwrap();
        let first = u32_at(&data, stco.body + 8) as usize;
        assert!(first >= mdat.body && first < mdat.end);
        let first_size = u32_at(&data, stsz.body + 12) as usize;
        let mut at = first;
        let mut saw_idr = false;
        while at < first + first_size {
            let len = u32_at(&data, at) as usize;
            saw_idr |= data[at + 4] & 0x1f == 5;
            at += 4 + len;
        }
        assert_eq!(at, first + first_size);
        assert!(saw_idr);
    }

    #[test]
    fn the_same_frames_give_the_same_bytes() {
        let frames = moving_square(12);
        assert_eq!(
            encode_mp4(&frames, 240, 10).unwrap(),
            encode_mp4(&frames, 240, 10).unwrap()
        );
    }

    #[test]
    fn garbage_is_not_a_box_structure() {
        assert!(boxes(b"\0\0\0\x40moovshort", 0, 12).is_err());
        assert!(boxes(b"\0\0\0\x04abcd", 0, 8).is_err());
        assert!(fast_start(b"\0\0\0\x08ftyp\0\0\0\x08moov").is_err());
        assert!(descend(b"\0\0\0\x08free", &[b"moov"]).is_err());
    }

    #[test]
    fn odd_sizes_and_empty_videos_are_refused() {
        assert!(encode_mp4(&[], 240, 24).is_err());
        let odd = vec![image::RgbImage::new(63, 48)];
        assert!(encode_mp4(&odd, 240, 24)
            .unwrap_err()
            .to_string()
            .contains("63×48"));
    }
}
