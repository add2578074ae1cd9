//! Episode videos: `--record X.mp4` is H.264 in MP4 that ffprobe reads frame by frame, with the
//! same frames and timing as the GIF of the same episode, and the same bytes every time.

use std::path::Path;
use std::process::Command;

use crate::common::{assert_ok, assert_user_error};
use crate::eval::Setup;

/// What ffprobe reads from the video stream: codec, decoded frames and duration in seconds.
fn probe(video: &Path) -> (String, u64, f64) {
    let output = Command::new("ffprobe")
        .args(["-v", "error", "-select_streams", "v:0", "-count_frames"])
        .args(["-show_entries", "stream=codec_name,nb_read_frames,duration"])
        .args(["-of", "json"])
        .arg(video)
        .output()
        .unwrap_or_else(|e| {
            panic!(
                "ffprobe cannot run ({e}): install it with `apt-get install -y ffmpeg` \
                 (scripts/setup-system.sh ffmpeg does it, and test.sh calls it as root)"
            )
        });
    assert!(
        output.status.success(),
        "ffprobe rejects {}: {}",
        video.display(),
        String::from_utf8_lossy(&output.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let stream = &json["streams"][0];
    let number = |key: &str| -> f64 { stream[key].as_str().unwrap().parse().unwrap() };
    (
        stream["codec_name"].as_str().unwrap().to_owned(),
        number("nb_read_frames") as u64,
        number("duration"),
    )
}

fn gif_frames(path: &Path) -> usize {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let decoder = image::codecs::gif::GifDecoder::new(file).unwrap();
    image::AnimationDecoder::into_frames(decoder)
        .collect_frames()
        .unwrap()
        .len()
}

#[test]
fn an_mp4_episode_is_h264_with_every_frame_of_the_gif_and_repeats_byte_for_byte() {
    let setup = Setup::new();
    let (mp4, again, gif) = (
        setup.path("episode.mp4"),
        setup.path("again.mp4"),
        setup.path("episode.gif"),
    );
    let mut recorded = None;
    for video in [&mp4, &gif, &again] {
        let out = setup.oracle_empty_bin(1, &["--record", video.to_str().unwrap()]);
        assert_ok(&out);
        recorded = Some(out);
    }
    let recorded = recorded.unwrap();
    let (codec, frames, duration) = probe(&mp4);
    assert_eq!(codec, "h264");
    let expected = gif_frames(&gif) as u64;
    assert!(expected > 10, "{expected} frames");
    assert_eq!(frames, expected, "frames of the MP4 against the GIF's");
    // 10 frames per second: one every 24 physics steps at 240 Hz.
    assert!(
        (duration - expected as f64 / 10.0).abs() < 0.051,
        "{duration} s for {expected} frames"
    );
    let bytes = std::fs::read(&mp4).unwrap();
    assert_eq!(
        bytes,
        std::fs::read(&again).unwrap(),
        "same episode, other bytes"
    );
    assert!(bytes.len() < std::fs::metadata(&gif).unwrap().len() as usize / 4);
    // The kept report says where the video went, and how long encoding and writing it took.
    let kept = crate::eval::read_json(&crate::common::kept_report(&recorded));
    assert_eq!(kept["results"]["video"], again.to_str().unwrap());
    let encoding = kept["results"]["video_encode_s"].as_f64().unwrap();
    assert!(encoding > 0.0 && encoding < 60.0, "{encoding} s");
}

#[test]
fn grasp_records_mp4_too_and_other_extensions_are_refused() {
    let setup = Setup::new();
    let mp4 = setup.path("pick.mp4");
    let out = setup.run(&[
        "grasp",
        "--object",
        "YcbTomatoSoupCan",
        "--seed",
        "1",
        "--oracle",
        "--record",
        mp4.to_str().unwrap(),
    ]);
    assert_ok(&out);
    let (codec, frames, duration) = probe(&mp4);
    assert_eq!(codec, "h264");
    // 24 frames per second: one every 10 physics steps.
    assert!(
        (duration - frames as f64 * 10.0 / 240.0).abs() < 0.03,
        "{duration} s, {frames}"
    );
    for command in [
        &[
            "grasp",
            "--object",
            "YcbTomatoSoupCan",
            "--oracle",
            "--record",
            "pick.avi",
        ][..],
        &["eval", "--task", "train", "--record", "episode.webm"][..],
    ] {
        let bad = command.last().unwrap();
        let out = setup.run(command);
        assert_user_error(&out, &[bad, ".mp4", ".gif"]);
    }
    let out = setup.run(&["eval", "--task", "train", "--record", "episode"]);
    assert_user_error(&out, &["episode", "without an extension", ".mp4"]);
}
