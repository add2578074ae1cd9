//! From parsed flags to the commands' typed configs: defaults that depend on other flags,
//! combinations that do not work together, and paths under the data directory.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _};

use super::{
    CollectArgs, EvalArgs, GlobalArgs, GraspArgs, ImproveArgs, LabelArgs, PredictArgs, ReportArgs,
    TrainArgs, TrialArgs,
};
use crate::assets::objects::{ObjectLibrary, SplitFile};
use crate::commands::collect::{CollectConfig, CollectPolicy};
use crate::commands::eval::{pushes_by_default, EvalConfig};
use crate::commands::grasp::{GraspChoice, GraspConfig};
use crate::commands::improve::ImproveConfig;
use crate::commands::label::{ClickNoise, ClickSource, LabelConfig};
use crate::commands::predict::PredictConfig;
use crate::commands::report::ReportConfig;
use crate::commands::train::TrainOptions;
use crate::commands::Context;
use crate::data::trials::Shard;
use crate::grasp::PixelGrasp;
use crate::model::config::TrainConfig;
use crate::policy::model::ModelPolicyConfig;
use crate::policy::suppression::SuppressionConfig;
use crate::present::video::VideoFormat;
use crate::sim::WorkcellConfig;

impl GlobalArgs {
    /// The settings every command shares.
    pub(super) fn context(&self) -> anyhow::Result<Context> {
        let objects = match &self.objects_dir {
            Some(dir) if !dir.is_dir() => bail!(
                "--objects-dir {} is not a directory (it should hold <Name>/model.urdf)",
                dir.display()
            ),
            Some(dir) => ObjectLibrary::new(dir),
            None => ObjectLibrary::bundled(),
        };
        let split = match &self.split {
            Some(path) => SplitFile::Path(path.clone()),
            None => objects.default_split(),
        };
        let threads = self.threads.unwrap_or_else(|| {
            std::thread::available_parallelism()
                .map_or(1, |n| n.get().min(u16::MAX as usize) as u16)
        });
        Ok(Context {
            data: self.data.clone(),
            objects,
            split,
            threads,
            json: self.json.clone(),
            quiet: self.quiet,
        })
    }
}

/// The `--checkpoint` given, or where `predict` and `eval` find the model by default.
fn checkpoint_path(data: &Path, given: Option<PathBuf>) -> PathBuf {
    given.unwrap_or_else(|| data.join("affordance").join("best.safetensors"))
}

impl EvalArgs {
    pub(super) fn config(self, data: &Path) -> anyhow::Result<EvalConfig> {
        let model = ModelPolicyConfig {
            check: self.collision_check,
            verify_top: self.verify_top,
            verify_floor: self.verify_floor,
            verify_strips: usize::from(self.verify_strips),
            verify_square: self.verify_square / 1000.0,
            verify_margin: self.verify_margin / 1000.0,
            verify_rejected: self.verify_rejected.unwrap_or(self.verify_top),
            centring: self.centring,
        };
        model.validate()?;
        if let Some(path) = &self.record {
            VideoFormat::of(path)?;
        }
        let seeds = match (self.seeds, self.seed) {
            (Some(list), _) => list.0,
            (None, Some(seed)) => vec![seed],
            (None, None) => vec![self.task.default_seed()],
        };
        if let (Some(path), [_, _, ..]) = (&self.record, seeds.as_slice()) {
            bail!(
                "--record {} films one episode, and --seeds gives {}; record one seed (--seed S)",
                path.display(),
                seeds.len()
            );
        }
        Ok(EvalConfig {
            task: self.task,
            policy: self.policy,
            checkpoint: checkpoint_path(data, self.checkpoint),
            precision: self.precision.resolve(),
            seeds,
            suppression: SuppressionConfig {
                remember: self.n_past_action,
                sigma_px: self.suppression_sigma,
                rotation_reach: usize::from(self.suppress_rotation_reach),
                other_rotations: self.suppress_other_rotations,
                remember_successes: self.suppress_successes,
            },
            model,
            max_attempts: self.max_attempts,
            give_up_after: self.give_up_after,
            push_unverified: self.push_unverified.unwrap_or(pushes_by_default(self.task)),
            record: self.record,
            resume: self.resume,
            check_invariants: self.check_invariants,
            shard: self.shard.unwrap_or(Shard::WHOLE),
        })
    }
}

impl TrialArgs {
    /// The collection settings of these flags; the store, seed, scenes and shard come from the
    /// command.
    fn collect_config(self, data: &Path, out: PathBuf, seed: u64, scenes: u64) -> CollectConfig {
        CollectConfig {
            out,
            seed,
            scenes,
            clutter: self.clutter as usize,
            max_attempts: self.max_attempts,
            policy: self.policy,
            explore: f64::from(self.explore),
            temperature: self.temperature,
            oracle_share: f64::from(self.oracle_share),
            checkpoint: checkpoint_path(data, self.checkpoint),
            precision: self.precision.resolve(),
            model: ModelPolicyConfig::default(),
            suppression: SuppressionConfig {
                remember: self.n_past_action,
                ..SuppressionConfig::default()
            },
            shard: Shard::WHOLE,
            force: false,
        }
    }
}

impl CollectArgs {
    pub(super) fn config(self, data: &Path) -> anyhow::Result<CollectConfig> {
        if let (Some(path), CollectPolicy::Oracle | CollectPolicy::Random) =
            (&self.trials.checkpoint, self.trials.policy)
        {
            bail!(
                "--checkpoint {} is used only by --policy model and mix, and this run is --policy {}; leave it out",
                path.display(),
                self.trials.policy
            );
        }
        let out = self.out.unwrap_or_else(|| data.join("trials"));
        let mut config = self
            .trials
            .collect_config(data, out, self.seed, self.scenes);
        config.shard = self.shard.unwrap_or(Shard::WHOLE);
        config.force = self.force;
        Ok(config)
    }
}

impl ImproveArgs {
    pub(super) fn config(self, data: &Path) -> anyhow::Result<ImproveConfig> {
        let out = self.out.unwrap_or_else(|| data.join("improve"));
        let start = checkpoint_path(data, self.trials.checkpoint.clone());
        let precision = self.trials.precision.resolve();
        let collect = self
            .trials
            .collect_config(data, out.join("trials"), self.seed, self.scenes);
        Ok(ImproveConfig {
            out,
            rounds: self.rounds,
            start,
            labels: data.join("labels"),
            collect,
            train: TrainConfig {
                epochs: self.epochs,
                seed: self.seed,
                precision,
                crop: self.crop,
                trial_weight: self.trial_weight,
                lr: self.lr,
                ..TrainConfig::default()
            },
            eval_seeds: self.eval_seeds.map(|s| s.0),
        })
    }
}

impl PredictArgs {
    pub(super) fn config(self, data: &Path) -> PredictConfig {
        let out = self.out.unwrap_or_else(|| {
            let stem = self
                .image
                .file_stem()
                .map_or_else(|| "image".into(), |s| s.to_string_lossy().into_owned());
            data.join("affordance")
                .join("predict_vis")
                .join(format!("{stem}.png"))
        });
        PredictConfig {
            checkpoint: checkpoint_path(data, self.checkpoint),
            image: self.image,
            depth: self.depth,
            out,
            precision: self.precision.resolve(),
        }
    }
}

impl GraspArgs {
    pub(super) fn config(self) -> anyhow::Result<GraspConfig> {
        let choice = match (&self.pixel, self.angle) {
            (Some(pixel), Some(angle)) => {
                let (u, v) = super::parse_pixel(pixel)?;
                let grasp = PixelGrasp::checked(f64::from(u), f64::from(v), angle)
                    .with_context(|| format!("--angle {angle:?}"))?;
                GraspChoice::Given(grasp)
            }
            _ if self.oracle => GraspChoice::Oracle,
            _ => GraspChoice::Random,
        };
        if let Some(path) = &self.record {
            VideoFormat::of(path)?;
        }
        Ok(GraspConfig {
            object: self.object,
            seed: self.seed,
            choice,
            workcell: WorkcellConfig {
                grip_force: self.grip_force,
                ..WorkcellConfig::default()
            },
            record: self.record,
            image: self.image,
        })
    }
}

impl LabelArgs {
    pub(super) fn config(self, data: &Path) -> LabelConfig {
        let source = match (self.clicks, self.interactive) {
            _ if self.web => ClickSource::Web {
                host: self.host,
                port: self.port,
            },
            (Some(path), _) => ClickSource::File(path),
            (None, true) => ClickSource::Interactive {
                preview: self
                    .preview
                    .unwrap_or_else(|| data.join("labels").join("preview.png")),
            },
            (None, false) => ClickSource::Scripted,
        };
        LabelConfig {
            per_object: self.per_object,
            max_rounds: self.max_rounds,
            seed: self.seed,
            source,
            noise: ClickNoise {
                px: self.click_noise_px,
                deg: self.angle_noise_deg,
            },
            force: self.force,
            check: self.check,
            delete: self.delete,
            clutter: self.clutter,
            backfill_depth: self.backfill_depth,
        }
    }
}

impl TrainArgs {
    pub(super) fn options(self, data: &Path) -> TrainOptions {
        TrainOptions {
            config: TrainConfig {
                epochs: self.epochs,
                batch_size: self.batch_size as usize,
                lr: self.lr,
                seed: self.seed,
                precision: self.precision.resolve(),
                input: self.input,
                crop: self.crop,
                trial_weight: self.trial_weight,
                trial_sigma_px: self.trial_sigma,
                ..TrainConfig::default()
            },
            resume: self.resume,
            force: self.force,
            out_dir: self.out_dir.unwrap_or_else(|| data.join("affordance")),
            labels: (!self.no_labels).then(|| data.join("labels")),
            trials: self.trials,
            start_from: self.start_from,
        }
    }
}

impl ReportArgs {
    pub(super) fn config(self, data: &Path) -> anyhow::Result<ReportConfig> {
        let out = self.out.unwrap_or_else(|| data.join("report.html"));
        let html = out
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("html") || e.eq_ignore_ascii_case("htm"));
        if !html {
            bail!(
                "--out {}: the report is an HTML page; end the name in .html (e.g. --out report.html)",
                out.display()
            );
        }
        Ok(ReportConfig {
            out,
            serve: self.serve.then_some((self.host, self.port)),
        })
    }
}
