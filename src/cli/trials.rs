//! The flags of the trial commands (`collect`, `merge`, `improve`) and the values they parse.

use std::path::PathBuf;

use clap::Args;

use super::scoped::ObjectsAndSplit;
use super::values::{fraction, named, parse_seed_list, positive_up_to, PrecisionChoice, SeedList};
use crate::commands::collect::CollectPolicy;
use crate::commands::improve::ROUND_LR;
use crate::data::shard::Shard;
use crate::model::config::TrainConfig;

/// `graspmap collect`.
#[derive(Debug, Args)]
pub(crate) struct CollectArgs {
    /// The trial store [default: DATA/trials].
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    /// Seed of every scene's drop and of the policies' draws.
    #[arg(long, default_value_t = 0)]
    pub(crate) seed: u64,
    /// Scenes of the whole run (all shards together).
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u64).range(1..))]
    pub(crate) scenes: u64,
    #[command(flatten)]
    pub(crate) trials: TrialArgs,
    /// Collect only part of the scenes: shard I of N holds scenes s with s mod N = I − 1.
    #[arg(long, value_name = "I/N", value_parser = parse_shard)]
    pub(crate) shard: Option<Shard>,
    /// Delete the store's scenes and start over.
    #[arg(long, conflicts_with = "check")]
    pub(crate) force: bool,
    /// Only validate the store (--out, or DATA/trials); exit 2 if anything is wrong.
    #[arg(long, conflicts_with_all = ["seed", "scenes", "shard", "clutter", "max_attempts", "policy", "explore", "temperature", "oracle_share", "n_past_action", "checkpoint", "precision", "objects_dir", "split"])]
    pub(crate) check: bool,
    #[command(flatten)]
    pub(crate) scope: ObjectsAndSplit,
}

/// How trials are collected: shared by `collect` and `improve`.
#[derive(Debug, Args, Clone)]
pub(crate) struct TrialArgs {
    /// Training objects dropped per scene (at most the split's training objects).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) clutter: u32,
    /// Most attempts per scene (a scene also ends when bin 1 is empty).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=99))]
    pub(crate) max_attempts: u32,
    /// Who chooses the grasps.
    #[arg(long, value_parser = named::<CollectPolicy>(), default_value = "mix")]
    pub(crate) policy: CollectPolicy,
    /// Chance that a model attempt samples its action from the maps instead (0 to 1).
    #[arg(long, value_name = "P", default_value_t = 0.3, value_parser = fraction)]
    pub(crate) explore: f32,
    /// Exploration's temperature: actions are drawn ∝ score^(1/T) (above 0, at most 10).
    #[arg(long, value_name = "T", default_value_t = 1.0, value_parser = positive_up_to::<f32>(10.0))]
    pub(crate) temperature: f32,
    /// mix: chance that the oracle chooses an attempt (0 to 1).
    #[arg(long, value_name = "P", default_value_t = 0.5, value_parser = fraction)]
    pub(crate) oracle_share: f32,
    /// Failure suppression within a scene, as eval's --n-past-action.
    #[arg(
        long = "n-past-action",
        visible_alias = "n_past_action",
        value_name = "N",
        default_value_t = 8
    )]
    pub(crate) n_past_action: usize,
    /// Model weights for model and mix [default: DATA/affordance/best.safetensors].
    #[arg(long, value_name = "PATH")]
    pub(crate) checkpoint: Option<PathBuf>,
    /// Arithmetic of the network.
    #[arg(long, value_enum, default_value_t = PrecisionChoice::Auto)]
    pub(crate) precision: PrecisionChoice,
}

/// `graspmap merge`.
#[derive(Debug, Args)]
pub(crate) struct MergeArgs {
    /// The shard stores, as `collect --shard I/N` wrote them.
    #[arg(required = true, value_name = "SHARD_DIR")]
    pub(crate) inputs: Vec<PathBuf>,
    /// The merged trial store, a new (or empty) folder; or for eval shard reports, the merged
    /// report file.
    #[arg(long, value_name = "DIR")]
    pub(crate) out: PathBuf,
    /// Merge the shards that are there when some are missing; the store says which.
    #[arg(long)]
    pub(crate) allow_partial: bool,
    /// Replace an existing --out report file (never one of the inputs).
    #[arg(long)]
    pub(crate) force: bool,
}

/// Improve's default training images per epoch: 40 steps of 8, so that the loop's time on 2
/// cores without AMX stays within a quarter of an hour (BENCHMARKS.md, "Learning from trials").
const EPOCH_SAMPLES: u32 = 320;

/// `graspmap improve`.
#[derive(Debug, Args)]
pub(crate) struct ImproveArgs {
    /// Rounds of collect-then-retrain.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=20))]
    pub(crate) rounds: u32,
    /// Scenes collected per round.
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u64).range(1..))]
    pub(crate) scenes: u64,
    /// Epochs of retraining per round, starting from the round's model.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) epochs: u32,
    /// Training images per epoch of a round's retraining: every label, then trials drawn afresh
    /// each epoch from every store so far, so that each round costs the same (0: every image,
    /// a cost that grows with each round).
    #[arg(long, value_name = "N", default_value_t = EPOCH_SAMPLES)]
    pub(crate) epoch_samples: u32,
    /// Seed of the rounds' collection and training.
    #[arg(long, default_value_t = 0)]
    pub(crate) seed: u64,
    /// After each round, evaluate its model on empty_bin with these seeds (with
    /// --n-past-action 8), and put the figures in the round's summary.
    #[arg(long, value_name = "LIST", value_parser = parse_seed_list)]
    pub(crate) eval_seeds: Option<SeedList>,
    #[command(flatten)]
    pub(crate) trials: TrialArgs,
    /// Train on PX × PX crops (as train --crop).
    #[arg(long, value_name = "PX", default_value_t = TrainConfig::default().crop, value_parser = parse_crop)]
    pub(crate) crop: u32,
    /// A trial's loss weight (as train --trial-weight).
    #[arg(long, value_name = "W", default_value_t = TrainConfig::default().trial_weight, value_parser = positive_up_to::<f32>(1.0))]
    pub(crate) trial_weight: f32,
    /// Learning rate of each round's retraining, which starts from the round's model: a tenth of
    /// train's, as at 1e-3 a round can drift from what the labels taught (docs/learning.md).
    #[arg(long, default_value_t = ROUND_LR, value_parser = positive_up_to::<f64>(1.0))]
    pub(crate) lr: f64,
    /// Where the rounds go [default: DATA/improve].
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) scope: ObjectsAndSplit,
}

/// `--shard` values.
pub(super) fn parse_shard(text: &str) -> Result<Shard, String> {
    Shard::parse(text)
}

/// `--crop` values: 0, or a multiple of 4 from 32 to 128.
pub(super) fn parse_crop(text: &str) -> Result<u32, String> {
    let crop: u32 = text.trim().parse().map_err(|_| {
        format!("'{text}' is not a whole number of pixels (e.g. 64, or 0 for whole images)")
    })?;
    if crop != 0 && (!crop.is_multiple_of(4) || !(32..=128).contains(&crop)) {
        return Err(format!(
            "{crop} px: a crop is a multiple of 4 from 32 to 128, or 0 for whole images"
        ));
    }
    Ok(crop)
}
