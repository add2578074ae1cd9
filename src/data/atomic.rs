//! Atomic file writes: a temporary file beside the target, synced, then renamed over it, so a
//! killed process leaves either the old file or the new one, never a torn one.
//!
//! Every file the tool writes goes through [`write_atomic`]. For the full-disk tests, in a build
//! with the `fault-injection` feature (never a release users run), the environment variable
//! `GRASPMAP_TEST_FAIL_WRITE=N` makes the process's N-th write fail with ENOSPC (`N:eio` for
//! EIO), as a full or failing disk would.

use std::io::Write;
use std::path::Path;
#[cfg(feature = "fault-injection")]
use std::sync::atomic::{AtomicU64, Ordering};
#[cfg(feature = "fault-injection")]
use std::sync::OnceLock;

use anyhow::Context;

/// The injected write failure, if the environment asks for one: (write number, errno).
#[cfg(feature = "fault-injection")]
fn fault_plan() -> Option<(u64, i32)> {
    static PLAN: OnceLock<Option<(u64, i32)>> = OnceLock::new();
    *PLAN.get_or_init(|| {
        let spec = std::env::var("GRASPMAP_TEST_FAIL_WRITE").ok()?;
        let (n, kind) = spec.split_once(':').unwrap_or((&spec, "enospc"));
        let errno = if kind.eq_ignore_ascii_case("eio") {
            libc::EIO
        } else {
            libc::ENOSPC
        };
        Some((n.trim().parse().ok()?, errno))
    })
}

/// Without the feature, no write is made to fail.
#[cfg(not(feature = "fault-injection"))]
fn injected_fault() -> Option<std::io::Error> {
    None
}

/// The error this write must fail with under fault injection.
#[cfg(feature = "fault-injection")]
fn injected_fault() -> Option<std::io::Error> {
    static WRITES: AtomicU64 = AtomicU64::new(0);
    let (at, errno) = fault_plan()?;
    let n = WRITES.fetch_add(1, Ordering::SeqCst) + 1;
    (n == at).then(|| std::io::Error::from_raw_os_error(errno))
}

/// Writes `bytes` to `path` atomically: a killed process leaves either the old file or the new one.
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
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
            std::fs::File::create(&tmp).with_context(|| format!("writing {}", path.display()))?;
        match injected_fault() {
            Some(fault) => Err(fault),
            None => file.write_all(bytes).and_then(|_| file.sync_all()),
        }
        .with_context(|| format!("writing {}", path.display()))?;
        std::fs::rename(&tmp, path).with_context(|| format!("replacing {}", path.display()))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Saves an image atomically; the format follows the extension.
pub(crate) fn save_image_atomic<P, C>(
    image: &image::ImageBuffer<P, C>,
    path: &Path,
) -> anyhow::Result<()>
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
