//! The fuzz harness that every parser's property tests share: random mutations of a real input
//! (labels.json, the clicks file, split.json, progress.json, the checkpoint's training state and
//! its safetensors, URDF, OBJ, STL, and PNG and JPEG observations), each fed to its parser in
//! the test module beside it.
//!
//! Each input must end in a result or one error, never a panic, within 5 s, and its parse
//! must allocate under 2 GiB at any one time (counted by this test binary's allocator, for the
//! parse's own thread: not the process's lifetime peak, which earlier tests and other threads
//! would set). `GRASPMAP_FUZZ_CASES` sets the cases per parser (1000 by default, what CI
//! runs); `scripts/fuzz.sh` runs the long pass.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::time::{Duration, Instant};

use proptest::prelude::*;

/// Longest a single input may take.
const MAX_CASE_TIME: Duration = Duration::from_secs(5);
/// Most that one parse may hold allocated at once.
const MAX_PARSE_BYTES: usize = 2 << 30;

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

/// Runs one input through a parser, checking its time and the most it held allocated. The
/// parser's result is dropped: a clear error is as good an outcome as a value.
pub(crate) fn check<T, E>(parse: impl FnOnce() -> Result<T, E>) -> Result<(), TestCaseError> {
    check_within(MAX_PARSE_BYTES, parse)
}

/// [`check`] with `limit` bytes for the parse.
fn check_within<T, E>(
    limit: usize,
    parse: impl FnOnce() -> Result<T, E>,
) -> Result<(), TestCaseError> {
    let start = Instant::now();
    let (_, most) = peak_allocation(parse);
    let took = start.elapsed();
    prop_assert!(took < MAX_CASE_TIME, "one input took {took:?}");
    prop_assert!(
        most < limit,
        "one input's parse held {most} bytes allocated"
    );
    Ok(())
}

/// Runs `f`: its result, and the most bytes it held allocated at once on this thread beyond
/// what the thread held before (the parsers run on the caller's thread).
fn peak_allocation<R>(f: impl FnOnce() -> R) -> (R, usize) {
    let before = HELD.with(Cell::get);
    PEAK.with(|peak| peak.set(before));
    let result = f();
    (result, PEAK.with(Cell::get) - before)
}

thread_local! {
    /// Bytes allocated on this thread and not yet freed (frees on another thread not counted).
    static HELD: Cell<usize> = const { Cell::new(0) };
    /// The most `HELD` reached since [`peak_allocation`] reset it.
    static PEAK: Cell<usize> = const { Cell::new(0) };
}

/// The test binary's allocator: the system's, counting each thread's allocation.
struct Counting;

#[global_allocator]
static COUNTING: Counting = Counting;

fn grew(bytes: usize) {
    // `try_with`: a thread being torn down has no counters left, and its allocations go uncounted.
    let _ = HELD.try_with(|held| {
        let now = held.get() + bytes;
        held.set(now);
        let _ = PEAK.try_with(|peak| peak.set(peak.get().max(now)));
    });
}

fn shrank(bytes: usize) {
    let _ = HELD.try_with(|held| held.set(held.get().saturating_sub(bytes)));
}

// SAFETY: every call goes to the system allocator unchanged; the counting only reads sizes.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, p: *mut u8, layout: Layout) {
        unsafe { System.dealloc(p, layout) };
        shrank(layout.size());
    }

    unsafe fn realloc(&self, p: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let q = unsafe { System.realloc(p, layout, new_size) };
        if !q.is_null() {
            match new_size >= layout.size() {
                true => grew(new_size - layout.size()),
                false => shrank(layout.size() - new_size),
            }
        }
        q
    }
}

pub(crate) fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn the_memory_check_counts_the_parse_s_own_allocation() {
    // Held before the parse, or by another thread meanwhile, is not the parse's.
    use std::hint::black_box;
    let kept = black_box(vec![1u8; 64 << 20]);
    let other = std::thread::spawn(|| black_box(vec![1u8; 64 << 20]));
    let (_, most) = peak_allocation(|| black_box(vec![0u8; 1 << 20]).len());
    assert!((1 << 20..2 << 20).contains(&most), "{most}");
    drop((kept, other.join().unwrap()));
    // Freed before the parse ended still counts at its peak.
    let (_, most) = peak_allocation(|| {
        drop(black_box(vec![0u8; 8 << 20]));
        black_box(vec![0u8; 1 << 20]).len()
    });
    assert!((8 << 20..9 << 20).contains(&most), "{most}");
    let parse = |bytes: usize| move || Ok::<_, ()>(black_box(vec![0u8; bytes]).len());
    assert!(check_within(4 << 20, parse(8 << 20)).is_err());
    assert!(check_within(4 << 20, parse(1 << 20)).is_ok());
}

#[test]
fn mutations_change_inputs_in_every_way_they_claim() {
    let seed = br#"{"a": [12, 3.5]}"#;
    assert_eq!(mutate(seed, &[(0, 3, 0)]), b"{\"a");
    assert_eq!(mutate(seed, &[(4, 0, 0)]), br#"{"a": [NaN, 3.5]}"#);
    assert!(mutate(seed, &[(5, 9, 0)]).starts_with(b"[[[[[[[[[[{"));
    assert_ne!(mutate(seed, &[(1, 2, 7)]), seed);
}
