//! Property tests that feed every parser and loader random mutations of real files:
//! labels.json, the clicks file, split.json, progress.json, the checkpoint's training state and
//! its safetensors, URDF, OBJ, STL, and PNG and JPEG observations.
//!
//! Each input must end in a result or one error, never a panic, within 5 s, and the process
//! must stay under 2 GiB resident. `GRASPMAP_FUZZ_CASES` sets the cases per parser (1000 by
//! default, what CI runs); `scripts/fuzz.sh` runs the long pass.

use std::path::Path;
use std::time::{Duration, Instant};

use proptest::prelude::*;
use rapier3d::math::Vector;

/// Longest a single input may take.
const MAX_CASE_TIME: Duration = Duration::from_secs(5);
/// Most resident memory the process may reach.
const MAX_RESIDENT_BYTES: i64 = 2 << 30;

/// Cases per parser: `GRASPMAP_FUZZ_CASES`, or 1000.
fn config() -> ProptestConfig {
    let cases = std::env::var("GRASPMAP_FUZZ_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(1000);
    ProptestConfig {
        cases,
        // Failures are reported with their input; nothing is written into the source tree.
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// Replacements that a mutation puts where a number stood.
const ODD_VALUES: [&str; 10] = [
    "NaN",
    "1e999",
    "-1",
    "-0.0",
    "18446744073709551616",
    "1e-320",
    "\"text\"",
    "{}",
    "[]",
    "null",
];

/// One edit of an input: (kind, position, byte).
type Edit = (u8, u32, u8);

/// Applies edits in order: truncate, flip a byte, insert a byte, delete a run, put an odd value
/// where a number starts, nest the whole input deeply, or repeat a run.
fn mutate(seed: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut data = seed.to_vec();
    for &(kind, position, byte) in edits {
        let at = |len: usize| if len == 0 { 0 } else { position as usize % len };
        match kind % 7 {
            0 => data.truncate(at(data.len() + 1)),
            1 => {
                let i = at(data.len());
                if let Some(b) = data.get_mut(i) {
                    *b ^= byte.max(1);
                }
            }
            2 => {
                let i = at(data.len() + 1);
                data.insert(i, byte);
            }
            3 => {
                let i = at(data.len());
                let end = (i + usize::from(byte)).min(data.len());
                data.drain(i..end);
            }
            4 => {
                let start = at(data.len());
                if let Some(offset) = data[start..].iter().position(u8::is_ascii_digit) {
                    let i = start + offset;
                    let end = i + data[i..]
                        .iter()
                        .take_while(|b| b.is_ascii_digit() || **b == b'.')
                        .count();
                    let odd = ODD_VALUES[usize::from(byte) % ODD_VALUES.len()];
                    data.splice(i..end, odd.bytes());
                }
            }
            5 => {
                let depth = 1 + (position as usize % 5000);
                let mut nested = vec![b'['; depth];
                nested.extend_from_slice(&data);
                nested.extend(std::iter::repeat_n(b']', depth));
                data = nested;
            }
            _ => {
                let i = at(data.len());
                let end = (i + usize::from(byte)).min(data.len());
                let run = data[i..end].to_vec();
                data.splice(i..i, run);
            }
        }
    }
    data
}

fn edits() -> impl Strategy<Value = Vec<Edit>> {
    prop::collection::vec(any::<Edit>(), 1..6)
}

/// Runs one input through a parser, checking its time and the process's memory. The parser's
/// result is dropped: a clear error is as good an outcome as a value.
fn check<T, E>(parse: impl FnOnce() -> Result<T, E>) -> Result<(), TestCaseError> {
    let start = Instant::now();
    let _ = parse();
    let took = start.elapsed();
    prop_assert!(took < MAX_CASE_TIME, "one input took {took:?}");
    prop_assert!(
        resident_peak() < MAX_RESIDENT_BYTES,
        "resident peak {} bytes",
        resident_peak()
    );
    Ok(())
}

/// The process's resident-set peak in bytes.
fn resident_peak() -> i64 {
    // SAFETY: getrusage only writes the struct it is given.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) };
    usage.ru_maxrss * 1024
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

const LABELS: &str = include_str!("../tests/fixtures/reference-labels/labels.json");
const SPLIT: &str = include_str!("../assets/objects/split.json");
const HAMMER_URDF: &str = include_str!("../assets/objects/YcbHammer/model.urdf");
const OBSERVATION_PNG: &[u8] =
    include_bytes!("../tests/fixtures/reference-labels/YcbHammer_1_rgb.png");
const CLICKS: &str = r#"[{"object": "YcbHammer", "x": 64, "y": 70, "angle": 45},
 {"object": "YcbTomatoSoupCan", "x": 12, "y": 100, "angle": 112.5}]"#;
const CUBE_OBJ: &str =
    "o piece\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n";

fn progress_json() -> String {
    r#"{"schema": "graspmap.label-progress/1", "seed": 0, "source": "scripted",
        "rounds": [{"object": "YcbHammer", "rounds": 14, "labels": 12}]}"#
        .to_owned()
}

fn checkpoint_meta() -> crate::model::train::CheckpointMeta {
    use crate::model::train::{CheckpointMeta, EpochRecord, Plateau, TrainConfig};
    CheckpointMeta {
        schema: CheckpointMeta::SCHEMA.to_owned(),
        config: TrainConfig::default(),
        epoch: 2,
        history: vec![EpochRecord {
            epoch: 1,
            train_loss: 0.5,
            val_loss: 0.25,
            lr: 1e-3,
            seconds: 1.5,
        }],
        best_val_loss: 0.25,
        best_epoch: 1,
        lr: 1e-3,
        plateau: Plateau::default(),
        adam_steps: 16,
        train_indices: vec![0, 2, 3],
        val_indices: vec![1],
    }
}

fn small_safetensors() -> &'static [u8] {
    static BYTES: std::sync::LazyLock<Vec<u8>> = std::sync::LazyLock::new(|| {
        let tensors = vec![
            (
                "inc.0.bias".to_owned(),
                tch::Tensor::from_slice(&[0.5f32, -1.0, 2.0]),
            ),
            (
                "outc.weight".to_owned(),
                tch::Tensor::from_slice(&[1.0f32, 2.0, 3.0, 4.0]).view([1, 4, 1, 1]),
            ),
        ];
        crate::model::checkpoint::encode(&tensors, &checkpoint_meta()).unwrap()
    });
    &BYTES
}

fn binary_stl() -> Vec<u8> {
    let mut bytes = vec![0u8; 80];
    bytes.extend(2u32.to_le_bytes());
    for triangle in [[[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]; 2] {
        bytes.extend([0.0f32; 3].iter().flat_map(|c| c.to_le_bytes()));
        for vertex in triangle {
            bytes.extend(vertex.iter().flat_map(|c| c.to_le_bytes()));
        }
        bytes.extend(0u16.to_le_bytes());
    }
    bytes
}

fn observation_jpeg() -> &'static [u8] {
    static BYTES: std::sync::LazyLock<Vec<u8>> = std::sync::LazyLock::new(|| {
        let image = image::RgbImage::from_fn(128, 128, |u, v| image::Rgb([u as u8, v as u8, 90]));
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
    fn fuzz_json_labels(edits in edits()) {
        let input = text(&mutate(LABELS.as_bytes(), &edits));
        check(|| crate::data::labels::Labels::parse(&input, Path::new("labels.json")))?;
    }

    #[test]
    fn fuzz_json_clicks(edits in edits()) {
        let input = text(&mutate(CLICKS.as_bytes(), &edits));
        let train = ["YcbHammer".to_owned(), "YcbTomatoSoupCan".to_owned()];
        check(|| crate::commands::label::parse_clicks(&input, Path::new("clicks.json"), &train))?;
    }

    #[test]
    fn fuzz_json_split(edits in edits()) {
        let input = text(&mutate(SPLIT.as_bytes(), &edits));
        check(|| crate::assets::objects::Split::parse(&input, Path::new("split.json")))?;
    }

    #[test]
    fn fuzz_json_progress(edits in edits()) {
        let input = text(&mutate(progress_json().as_bytes(), &edits));
        check(|| crate::data::labels::Progress::parse(&input, Path::new("progress.json")))?;
    }

    #[test]
    fn fuzz_json_checkpoint_state(edits in edits()) {
        let seed = serde_json::to_string_pretty(&checkpoint_meta()).unwrap();
        let input = text(&mutate(seed.as_bytes(), &edits));
        check(|| crate::model::checkpoint::parse_meta(&input, Path::new("last.json")))?;
    }

    #[test]
    fn fuzz_safetensors(edits in edits()) {
        let input = mutate(small_safetensors(), &edits);
        check(|| crate::model::checkpoint::decode(&input, Path::new("last.safetensors")))?;
    }

    #[test]
    fn fuzz_urdf(edits in edits()) {
        let input = text(&mutate(HAMMER_URDF.as_bytes(), &edits));
        check(|| {
            let file = crate::assets::urdf::UrdfFile::parse(&input, Path::new("model.urdf"))?;
            crate::assets::objects::object_from_urdf("Fuzzed", &file)
                .map_err(|e| anyhow::anyhow!("{e}"))
        })?;
    }

    #[test]
    fn fuzz_obj(edits in edits()) {
        let input = mutate(CUBE_OBJ.as_bytes(), &edits);
        check(|| {
            crate::assets::urdf::load_mesh_bytes(input, Path::new("/nonexistent/piece.obj"), Vector::ONE)
        })?;
    }

    #[test]
    fn fuzz_stl(edits in edits()) {
        let input = mutate(&binary_stl(), &edits);
        check(|| {
            crate::assets::urdf::load_mesh_bytes(input, Path::new("/nonexistent/piece.stl"), Vector::ONE)
        })?;
    }

    #[test]
    fn fuzz_png_observation(edits in edits()) {
        let input = mutate(OBSERVATION_PNG, &edits);
        check(|| crate::commands::predict::decode_observation(&input, Path::new("image.png")))?;
    }

    #[test]
    fn fuzz_jpeg_observation(edits in edits()) {
        let input = mutate(observation_jpeg(), &edits);
        check(|| crate::commands::predict::decode_observation(&input, Path::new("image.jpg")))?;
    }
}

#[test]
fn mutations_change_inputs_in_every_way_they_claim() {
    let seed = br#"{"a": [12, 3.5]}"#;
    assert_eq!(mutate(seed, &[(0, 3, 0)]), b"{\"a");
    assert_eq!(mutate(seed, &[(4, 0, 0)]), br#"{"a": [NaN, 3.5]}"#);
    assert!(mutate(seed, &[(5, 9, 0)]).starts_with(b"[[[[[[[[[[{"));
    assert_ne!(mutate(seed, &[(1, 2, 7)]), seed);
}
