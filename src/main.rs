//! The `graspmap` binary: parse flags, run, print errors as one line and exit 2 (130 or 143
//! after SIGINT or SIGTERM).

use std::process::ExitCode;

fn main() -> ExitCode {
    keep_freed_memory();
    match graspmap::cli::run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => match error.downcast_ref::<graspmap::Interrupted>() {
            // The command has already said what it kept and how to continue.
            Some(interrupted) => ExitCode::from(interrupted.exit_code()),
            None => {
                eprintln!("error: {error:#}");
                ExitCode::from(2)
            }
        },
    }
}

/// Lets glibc's malloc reuse freed memory instead of handing it back to the kernel.
///
/// The network's activations at batch 8 are 32 MiB tensors, just over glibc's largest mmap
/// threshold, so by default every one was a fresh mmap and every first touch of its pages a
/// fault the kernel zero-fills: a third of training's wall time went to the kernel. Served from
/// the heap and never trimmed, the same memory is reused step after step (measured on an AVX2-only
/// CPU: "Training: glibc's heap" in `git show 2c24231:docs/history.md`).
fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only changes allocator tuning parameters; it is called before any thread
    // starts, and every value is in the range glibc documents.
    unsafe {
        libc::mallopt(libc::M_MMAP_MAX, 0);
        libc::mallopt(libc::M_TRIM_THRESHOLD, i32::MAX);
        libc::mallopt(libc::M_TOP_PAD, 64 << 20);
    }
}
