//! The flags of the evaluation commands (`eval`, `predict`): the tasks, the policies and the
//! model policy's checks.

use std::path::PathBuf;

use clap::Args;

use super::scoped::ObjectsAndSplit;
use super::trials::parse_shard;
use super::values::{
    fraction, named, non_negative_up_to, parse_seed_list, positive_up_to, PrecisionChoice, SeedList,
};
use crate::data::shard::Shard;
use crate::policy::collision::CollisionCheck;
use crate::policy::model::ModelPolicyConfig;
use crate::policy::suppression::SuppressionConfig;
use crate::policy::PolicyKind;
use crate::present::eval_report::Task;
use crate::present::kept_reports::DEFAULT_MAX_ATTEMPTS;

/// `graspmap eval`.
#[derive(Debug, Args)]
pub(crate) struct EvalArgs {
    /// Which evaluation to run.
    #[arg(long, value_parser = named::<Task>())]
    pub(crate) task: Task,
    /// Who chooses the grasps.
    #[arg(long, value_parser = named::<PolicyKind>(), default_value = "model")]
    pub(crate) policy: PolicyKind,
    /// --task scenes: scene files, or folders of them: graspmap's JSON (`scene --save`) or VPG's
    /// test cases (.txt, which place VPG's blocks: add --objects-dir assets/blocks).
    #[arg(long, value_name = "PATH", num_args = 1..)]
    pub(crate) scenes: Vec<PathBuf>,
    /// Model weights [default: DATA/affordance/best.safetensors].
    #[arg(long, value_name = "PATH")]
    pub(crate) checkpoint: Option<PathBuf>,
    /// Base seed: train/test attempt a of object i drops with seed + 100·i + a + 10000;
    /// empty_bin drops all objects with it [default: 0, empty_bin 2].
    #[arg(long, conflicts_with = "seeds")]
    pub(crate) seed: Option<u64>,
    /// Several base seeds, aggregated: a list and/or ranges, e.g. 1-10 or 0,1000,2000.
    #[arg(long, value_name = "LIST", value_parser = parse_seed_list)]
    pub(crate) seeds: Option<SeedList>,
    /// Failure suppression: lower the affordance around the last N failed actions (0 = off);
    /// the oracle instead tries first the objects fewer of them landed on.
    #[arg(
        long = "n-past-action",
        visible_alias = "n_past_action",
        value_name = "N",
        default_value_t = 0
    )]
    pub(crate) n_past_action: usize,
    /// Suppression: standard deviation of the subtracted Gaussian in pixels (above 0, at most 64).
    #[arg(long, value_name = "PX", default_value_t = SuppressionConfig::default().sigma_px, value_parser = positive_up_to::<f32>(64.0))]
    pub(crate) suppression_sigma: f32,
    /// Suppression: also lower the rotations within this many 22.5° bins of the failed one
    /// (0 = its own rotation only, 4 = all).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u8).range(0..=4))]
    pub(crate) suppress_rotation_reach: u8,
    /// Suppression: lower the rotations beyond that reach too, by a Gaussian of this height
    /// (0 = leave them, 1 = as much as the failed one), so that spots that failed wait until
    /// the untried ones have had their turn.
    #[arg(long, value_name = "DEPTH", default_value_t = SuppressionConfig::default().other_rotations, value_parser = fraction)]
    pub(crate) suppress_other_rotations: f32,
    /// Suppression: remember successful actions too, not only failures.
    #[arg(long)]
    pub(crate) suppress_successes: bool,
    /// Model policy: before the argmax, zero the grasps whose open gripper would hit a tote wall
    /// (walls) or also land on a surface seen in the depth image (full); off = plain argmax.
    #[arg(long, value_parser = named::<CollisionCheck>(), default_value = "full")]
    pub(crate) collision_check: CollisionCheck,
    /// Model policy: execute the first of the N best actions (after suppression and the
    /// collision check) that passes verification, the planner's test on the depth image: the object fits the open jaw with
    /// room to spare, both pads come down in free space and seen, and they close on flat faces
    /// across the object, not on an edge; when none passes, the second pass (--verify-rejected),
    /// then the argmax (0 = plain argmax).
    #[arg(long, value_name = "N", default_value_t = ModelPolicyConfig::default().verify_top)]
    pub(crate) verify_top: usize,
    /// Model policy: verification may replace the argmax only with a candidate scoring at
    /// least this fraction of it (0 = any of the N best). 0.25 picks more objects alone in the
    /// bin and about as many in clutter (BENCHMARKS.md#verification).
    #[arg(long, value_name = "F", default_value_t = ModelPolicyConfig::default().verify_floor, value_parser = fraction)]
    pub(crate) verify_floor: f32,
    /// Model policy: when none of the N best allowed actions passes verification, verify the
    /// best M of the network's actions before the collision check, and execute the first that
    /// passes (0 = off; default: the same N as --verify-top).
    #[arg(long, value_name = "M")]
    pub(crate) verify_rejected: Option<usize>,
    /// Model policy: how many of a pad's three strips across its width (outer quarters, middle
    /// half) the squeezed part must reach to pass verification: 3 = the whole pad, 2 = the
    /// planner's rule, which also passes grasps near a box's edge (BENCHMARKS.md#verification).
    #[arg(long, value_name = "N", default_value_t = ModelPolicyConfig::default().verify_strips as u8, value_parser = clap::value_parser!(u8).range(1..=3))]
    pub(crate) verify_strips: u8,
    /// Model policy: verification first tries the candidates whose squeezed faces are within
    /// MM of square across a pad (5 ≈ 13°), then those within the planner's 10 mm (0 = one pass).
    #[arg(long, value_name = "MM", default_value_t = ModelPolicyConfig::default().verify_square * 1000.0, value_parser = non_negative_up_to(10.0))]
    pub(crate) verify_square: f32,
    /// Model policy: room verification keeps between the squeezed part and each open pad, in
    /// mm (the planner keeps 6, which leaves a flat 77 mm box only its corners).
    #[arg(long, value_name = "MM", default_value_t = ModelPolicyConfig::default().verify_margin * 1000.0, value_parser = non_negative_up_to(10.0))]
    pub(crate) verify_margin: f32,
    /// Model policy: move the chosen grasp to the middle of the surface under it, turning it to
    /// an angle that fits there if needed (needs `--collision-check full`). Off by default: it
    /// moves more objects in empty_bin but picks fewer training objects (BENCHMARKS.md#centring).
    #[arg(long)]
    pub(crate) centring: bool,
    /// empty_bin: most pick attempts per scene.
    #[arg(long, default_value_t = DEFAULT_MAX_ATTEMPTS, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) max_attempts: u32,
    /// empty_bin, scenes: end a scene after K failed actions in a row (a grasp that held
    /// nothing, a push that moved nothing), as a robot that declares the bin done; 0 = never
    /// [default: empty_bin 0, the reference's fixed budget of --max-attempts; scenes 11, VPG's
    /// "more than 10"].
    #[arg(long, value_name = "K")]
    pub(crate) give_up_after: Option<u32>,
    /// Model policy: where no grasp passes verification, push the object under the best one
    /// off its neighbours instead of executing that grasp; an attempt, not a grasp
    /// (docs/evaluation.md, "Pushing"). Default: true in empty_bin, false in train and test,
    /// where each attempt drops its object afresh.
    #[arg(long, value_name = "BOOL", num_args = 0..=1, default_missing_value = "true")]
    pub(crate) push_unverified: Option<bool>,
    /// Write the episode video: an oblique view beside the camera view with the chosen grasp
    /// (one seed only); .mp4 for H.264 (small, plays in browsers) or .gif.
    #[arg(long, value_name = "VIDEO")]
    pub(crate) record: Option<PathBuf>,
    /// Arithmetic of the network.
    #[arg(long, value_enum, default_value_t = PrecisionChoice::Auto)]
    pub(crate) precision: PrecisionChoice,
    /// Continue an interrupted sweep: skip the scenes that its report already holds (the --json
    /// file when given, else the copy kept in DATA/reports).
    #[arg(long, conflicts_with = "record")]
    pub(crate) resume: bool,
    /// Check the physics after every step (finite poses, nothing sunk into the totes) and
    /// report violations per attempt; slower, for scripts/soak.sh.
    #[arg(long, hide = true)]
    pub(crate) check_invariants: bool,
    /// Run only part of --seeds: the i-th seed given (from 0) belongs to shard i mod N + 1.
    /// Its report (kept in DATA/reports beside the whole sweep's, with _shard<I>of<N> before
    /// .json) says which part; `graspmap merge` joins the shards' reports into the whole sweep's.
    #[arg(long, value_name = "I/N", value_parser = parse_shard, conflicts_with = "record")]
    pub(crate) shard: Option<Shard>,
    #[command(flatten)]
    pub(crate) scope: ObjectsAndSplit,
}

/// `graspmap predict`.
#[derive(Debug, Args)]
pub(crate) struct PredictArgs {
    /// A 128 × 128 RGB image (PNG or JPEG) seen from the top-down camera.
    #[arg(long, value_name = "IMAGE")]
    pub(crate) image: PathBuf,
    /// Model weights [default: DATA/affordance/best.safetensors].
    #[arg(long, value_name = "PATH")]
    pub(crate) checkpoint: Option<PathBuf>,
    /// Where to write the picture of the maps over the image [default: DATA/affordance/predict_vis/<image stem>.png].
    #[arg(long, value_name = "PNG")]
    pub(crate) out: Option<PathBuf>,
    /// The image's depth, 16-bit millimetres as `scene --depth` writes it (rgbd models need it).
    #[arg(long, value_name = "PNG")]
    pub(crate) depth: Option<PathBuf>,
    /// Arithmetic of the network.
    #[arg(long, value_enum, default_value_t = PrecisionChoice::Auto)]
    pub(crate) precision: PrecisionChoice,
    /// Replace --out when it exists.
    #[arg(long)]
    pub(crate) force: bool,
}
