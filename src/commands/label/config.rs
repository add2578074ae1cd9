//! What one `graspmap label` run does, as the CLI resolves it: the counts, the seed, where the
//! clicks come from, and the modes that only check, delete or backfill.

use std::path::PathBuf;

/// One `graspmap label` run, resolved by the CLI.
#[derive(Debug, Clone)]
pub(crate) struct LabelConfig {
    /// Successful labels wanted per training object. Default 12.
    pub(crate) per_object: u32,
    /// Rounds allowed per object before giving up on it. Default 40.
    pub(crate) max_rounds: u32,
    /// Base seed: round r of training object j drops with seed + 100·j + r. Default 0.
    pub(crate) seed: u64,
    /// Where clicks come from.
    pub(crate) source: ClickSource,
    /// Scripted clicks' human-like noise.
    pub(crate) noise: ClickNoise,
    /// Delete existing labels first.
    pub(crate) force: bool,
    /// Only validate the existing dataset.
    pub(crate) check: bool,
    /// Only delete this label (object, k from 1), renumbering the object's later ones.
    pub(crate) delete: Option<(String, usize)>,
    /// Objects dropped per round: the round's object and `clutter` − 1 others. Default 1.
    pub(crate) clutter: u32,
    /// Only write the depth files that an older dataset lacks.
    pub(crate) backfill_depth: bool,
}

/// Where a round's click comes from.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum ClickSource {
    /// The oracle planner in 22.5° steps, with [`ClickNoise`].
    Scripted,
    /// A JSON list of {"object", "x", "y", "angle"}, one per round.
    File(PathBuf),
    /// A person at stdin; the preview image goes to this path.
    Interactive {
        /// Where the image with the cursor's grasp is written.
        preview: PathBuf,
    },
    /// A person at a page in the browser, served on this address (port 0: any free one).
    Web {
        /// The address to bind.
        host: std::net::IpAddr,
        /// The port; 0 picks a free one.
        port: u16,
    },
}

/// Standard deviations of the scripted clicker's noise.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct ClickNoise {
    /// Of the click position, in pixels.
    pub(crate) px: f32,
    /// Of the angle, in degrees (before snapping to 22.5°).
    pub(crate) deg: f32,
}
