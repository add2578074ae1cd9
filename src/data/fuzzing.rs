//! The fuzz harness that every parser's property tests share: random mutations of a real input
//! (labels.json, the clicks file, split.json, progress.json, the checkpoint's training state and
//! its safetensors, URDF, OBJ, STL, and PNG and JPEG observations), each fed to its parser in
//! the test module beside it.
//!
//! Each input must end in a result or one error, never a panic, within 5 s, and the process
//! must stay under 2 GiB resident. `GRASPMAP_FUZZ_CASES` sets the cases per parser (1000 by
//! default, what CI runs); `scripts/fuzz.sh` runs the long pass.

use std::time::{Duration, Instant};

use proptest::prelude::*;

/// Longest a single input may take.
const MAX_CASE_TIME: Duration = Duration::from_secs(5);
/// Most resident memory the process may reach.
const MAX_RESIDENT_BYTES: i64 = 2 << 30;

/// Cases per parser: `GRASPMAP_FUZZ_CASES`, or 1000.
pub(crate) fn config() -> ProptestConfig {
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
pub(crate) type Edit = (u8, u32, u8);

/// Applies edits in order: truncate, flip a byte, insert a byte, delete a run, put an odd value
/// where a number starts, nest the whole input deeply, or repeat a run.
pub(crate) fn mutate(seed: &[u8], edits: &[Edit]) -> Vec<u8> {
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

pub(crate) fn edits() -> impl Strategy<Value = Vec<Edit>> {
    prop::collection::vec(any::<Edit>(), 1..6)
}

/// Runs one input through a parser, checking its time and the process's memory. The parser's
/// result is dropped: a clear error is as good an outcome as a value.
pub(crate) fn check<T, E>(parse: impl FnOnce() -> Result<T, E>) -> Result<(), TestCaseError> {
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

pub(crate) fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn mutations_change_inputs_in_every_way_they_claim() {
    let seed = br#"{"a": [12, 3.5]}"#;
    assert_eq!(mutate(seed, &[(0, 3, 0)]), b"{\"a");
    assert_eq!(mutate(seed, &[(4, 0, 0)]), br#"{"a": [NaN, 3.5]}"#);
    assert!(mutate(seed, &[(5, 9, 0)]).starts_with(b"[[[[[[[[[[{"));
    assert_ne!(mutate(seed, &[(1, 2, 7)]), seed);
}
