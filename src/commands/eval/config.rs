//! What one `graspmap eval` run does, as the CLI resolves it, and the reference's constants of
//! the tasks.

use std::path::PathBuf;

use crate::commands::RunBy;
use crate::data::seeds::{derived_seed, SeedOverflow};
use crate::data::shard::Shard;
use crate::model::unet::Precision;
use crate::policy::model::ModelPolicyConfig;
use crate::policy::suppression::SuppressionConfig;
use crate::policy::PolicyKind;
use crate::present::eval_report::Task;

/// Attempts per object in the train and test tasks (the reference's).
pub(crate) const ATTEMPTS_PER_OBJECT: u32 = 3;
/// Offset of the train/test drop seeds (the reference's): seed + 100·i + a + 10000.
pub(crate) const SINGLE_OBJECT_SEED_OFFSET: u64 = 10_000;

/// The drop seed of train/test attempt `a` of object `i` under base seed `seed`.
pub(crate) fn single_object_seed(seed: u64, i: usize, a: u32) -> Result<u64, SeedOverflow> {
    let offset = 100 * i as u64 + u64::from(a) + SINGLE_OBJECT_SEED_OFFSET;
    derived_seed(
        seed,
        1,
        offset,
        "seed + 100·i + a + 10000 for attempt a of object i",
    )
}

/// Physics steps between episode video frames: 10 fps, so that a 25-attempt episode stays small
/// (its MP4 and GIF sizes: BENCHMARKS.md#videos-and-the-report); `grasp --record` films one
/// attempt at 24 fps.
pub(crate) const EPISODE_EVERY_STEPS: u64 = 24;
/// Whether the model policy pushes where no grasp passes verification, unless told: in
/// empty_bin, where the grasps it would execute there rarely hold and a push can free an object
/// for a later attempt (`--push-unverified false` in BENCHMARKS.md#verification); not in train
/// and test, where every attempt drops its object afresh and a push would only take an attempt
/// (docs/evaluation.md, "Pushing").
pub(crate) fn pushes_by_default(task: Task) -> bool {
    task.clears_a_bin()
}
/// VPG's give-up rule for scenes: a run ends after more than 10 failed actions in a row.
pub(crate) const VPG_GIVE_UP_AFTER: u32 = 11;
/// How many failed actions in a row end a run, unless told: never in empty_bin (the
/// reference's fixed budget of attempts), VPG's rule in scenes.
pub(crate) fn give_up_by_default(task: Task) -> u32 {
    match task {
        Task::Scenes => VPG_GIVE_UP_AFTER,
        _ => 0,
    }
}
/// Everything one `graspmap eval` run needs, resolved and checked by the CLI.
#[derive(Debug, Clone)]
pub(crate) struct EvalConfig {
    /// Which evaluation.
    pub(crate) task: Task,
    /// Who chooses the grasps.
    pub(crate) policy: PolicyKind,
    /// The model's weights (model policy).
    pub(crate) checkpoint: PathBuf,
    /// Arithmetic of the network.
    pub(crate) precision: Precision,
    /// Base seeds, run one after another and aggregated.
    pub(crate) seeds: Vec<u64>,
    /// scenes: the scene files and folders of them.
    pub(crate) scenes: Vec<PathBuf>,
    /// Failure suppression (model policy).
    pub(crate) suppression: SuppressionConfig,
    /// The model policy's checks.
    pub(crate) model: ModelPolicyConfig,
    /// empty_bin: most pick attempts per scene. Default 25.
    pub(crate) max_attempts: u32,
    /// empty_bin: end a scene after this many failed attempts in a row; 0 = never.
    pub(crate) give_up_after: u32,
    /// Model policy: push instead of executing a grasp that failed verification.
    pub(crate) push_unverified: bool,
    /// Where to write the episode video (one seed only).
    pub(crate) record: Option<PathBuf>,
    /// Skip the scenes that the `--json` report already holds.
    pub(crate) resume: bool,
    /// Check the physics invariants after every step (the soak test).
    pub(crate) check_invariants: bool,
    /// The part of `seeds` this run evaluates: seed number i (0-based, in the order given)
    /// belongs to shard i mod N + 1.
    pub(crate) shard: Shard,
    /// Who runs it, for the advice of its errors.
    pub(crate) run_by: RunBy,
}

impl EvalConfig {
    /// The seeds this run evaluates: all of them, or its shard's.
    pub(crate) fn run_seeds(&self) -> Vec<u64> {
        self.seeds
            .iter()
            .enumerate()
            .filter(|(i, _)| self.shard.holds(*i as u64))
            .map(|(_, &seed)| seed)
            .collect()
    }
}
