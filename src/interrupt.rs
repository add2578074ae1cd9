//! Ctrl-C and SIGTERM: the first asks the running command to stop at its next safe point
//! (after the current label round, before saving a half-trained epoch, after the current
//! evaluation scene); a second ends the process at once. What was written stays valid either
//! way, since every file is replaced atomically.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

use signal_hook::consts::{SIGINT, SIGTERM};

/// The signal asked for, set by the handlers.
struct Flags {
    pending: Arc<AtomicBool>,
    signal: Arc<AtomicUsize>,
}

static FLAGS: OnceLock<Flags> = OnceLock::new();

/// Installs the handlers; call once, before the work starts.
pub(crate) fn install() -> std::io::Result<()> {
    let flags = FLAGS.get_or_init(|| Flags {
        pending: Arc::new(AtomicBool::new(false)),
        signal: Arc::new(AtomicUsize::new(0)),
    });
    for signal in [SIGINT, SIGTERM] {
        // Registered first, so it sees the flag still clear on the first signal and set on
        // the second, which then exits at once.
        signal_hook::flag::register_conditional_shutdown(
            signal,
            128 + signal,
            Arc::clone(&flags.pending),
        )?;
        signal_hook::flag::register(signal, Arc::clone(&flags.pending))?;
        signal_hook::flag::register_usize(signal, Arc::clone(&flags.signal), signal as usize)?;
    }
    Ok(())
}

/// The signal that asked the command to stop, if one did.
pub(crate) fn requested() -> Option<Interrupted> {
    let flags = FLAGS.get()?;
    if !flags.pending.load(Ordering::SeqCst) {
        return None;
    }
    Some(Interrupted {
        signal: flags.signal.load(Ordering::SeqCst) as i32,
    })
}

/// A command stopped early by a signal, after keeping what it had finished.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("interrupted by {}", if *signal == SIGTERM { "SIGTERM" } else { "SIGINT" })]
pub struct Interrupted {
    /// The signal number.
    pub signal: i32,
}

impl Interrupted {
    /// The shell's convention: 128 + the signal (130 for SIGINT, 143 for SIGTERM).
    pub fn exit_code(self) -> u8 {
        u8::try_from(128 + self.signal).unwrap_or(130)
    }
}
