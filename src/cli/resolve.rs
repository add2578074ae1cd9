//! From parsed flags to the commands' typed configs: defaults that depend on other flags,
//! combinations that do not work together, and paths under the data directory.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _};

use super::given::{refuse_inapplicable, Given};
use super::scoped::Resolved;
use super::values::PrecisionChoice;
use super::{
    CollectArgs, EvalArgs, GlobalArgs, GraspArgs, ImproveArgs, LabelArgs, PredictArgs, ReportArgs,
    TrainArgs, TrialArgs,
};
use crate::assets::objects::{ObjectLibrary, SplitFile};
use crate::commands::collect::{CollectConfig, CollectPolicy};
use crate::commands::eval::{give_up_by_default, pushes_by_default, EvalConfig};
use crate::commands::grasp::{GraspChoice, GraspConfig};
use crate::commands::improve::ImproveConfig;
use crate::commands::label::{ClickNoise, ClickSource, LabelConfig};
use crate::commands::predict::PredictConfig;
use crate::commands::report::ReportConfig;
use crate::commands::train::TrainOptions;
use crate::commands::{Context, RunBy};
use crate::data::output::identity;
use crate::data::shard::Shard;
use crate::grasp::PixelGrasp;
use crate::model::autotune::Workload;
use crate::model::config::TrainConfig;
use crate::named::Named;
use crate::policy::model::ModelPolicyConfig;
use crate::policy::suppression::SuppressionConfig;
use crate::policy::PolicyKind;
use crate::present::eval_report::Task;
use crate::present::video::VideoFormat;
use crate::sim::WorkcellConfig;

impl GlobalArgs {
    /// The settings every command shares, from the global flags and the scoped flags the
    /// command took (wherever they were given).
    pub(super) fn context(
        &self,
        command: &'static str,
        scoped: Resolved,
    ) -> anyhow::Result<Context> {
        let objects = match &scoped.objects_dir {
            Some(dir) if !dir.is_dir() => bail!(
                "--objects-dir {} is not a directory (it should hold <Name>/model.urdf)",
                dir.display()
            ),
            Some(dir) => ObjectLibrary::new(dir),
            None => ObjectLibrary::bundled(),
        };
        let split = match &scoped.split {
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
            command,
        })
    }
}

/// The `--checkpoint` given, or where `predict` and `eval` find the model by default.
fn checkpoint_path(data: &Path, given: Option<PathBuf>) -> PathBuf {
    given.unwrap_or_else(|| data.join("affordance").join("best.safetensors"))
}

/// eval flags that only empty_bin reads: the attempt budget, and failure suppression (in train
/// and test every attempt drops its object afresh, so there is nothing to remember).
const EMPTY_BIN_ONLY: &[&str] = &[
    "max_attempts",
    "give_up_after",
    "n_past_action",
    "suppression_sigma",
    "suppress_rotation_reach",
    "suppress_other_rotations",
    "suppress_successes",
];
/// eval flags that only the model policy reads.
const EVAL_MODEL_ONLY: &[&str] = &[
    "checkpoint",
    "precision",
    "collision_check",
    "verify_top",
    "verify_floor",
    "verify_rejected",
    "verify_strips",
    "verify_square",
    "verify_margin",
    "centring",
    "push_unverified",
    "suppression_sigma",
    "suppress_rotation_reach",
    "suppress_other_rotations",
];
/// Failure memory: the model lowers its maps, the oracle reorders its objects; random ignores it.
const REMEMBERING: &[&str] = &["n_past_action", "suppress_successes"];
/// Trial flags of the model's turns (`--policy model` and `mix`).
const EXPLORING: &[&str] = &["explore", "temperature"];
/// The model's own flags in `collect` (in `improve` the checkpoint also starts the training).
const COLLECT_MODEL_ONLY: &[&str] = &["checkpoint", "precision"];

impl EvalArgs {
    /// Refuses the flags that this task and policy would not read.
    fn refuse_inapplicable(&self, given: &Given) -> anyhow::Result<()> {
        let task = format!("--task {}", self.task.name());
        let policy = format!("--policy {}", self.policy.name());
        if !self.task.clears_a_bin() {
            refuse_inapplicable(given, EMPTY_BIN_ONLY, "--task empty_bin or scenes", &task)?;
        }
        match (self.task, self.scenes.is_empty()) {
            (Task::Scenes, true) => bail!(
                "--task scenes needs --scenes PATH…: scene files (graspmap's JSON or VPG's test cases) or folders of them"
            ),
            (Task::Scenes, false) if self.shard.is_some() || self.resume => bail!(
                "--task scenes runs each scene file whole: drop --shard and --resume"
            ),
            (Task::Train | Task::Test | Task::EmptyBin, false) => {
                bail!("--scenes is read by --task scenes only, not {task}")
            }
            _ => {}
        }
        if self.policy != PolicyKind::Model {
            refuse_inapplicable(given, EVAL_MODEL_ONLY, "--policy model", &policy)?;
        }
        if self.policy == PolicyKind::Random {
            refuse_inapplicable(given, REMEMBERING, "--policy model and oracle", &policy)?;
        }
        Ok(())
    }

    pub(super) fn config(self, data: &Path, given: &Given) -> anyhow::Result<EvalConfig> {
        self.refuse_inapplicable(given)?;
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
            precision: (self.precision)
                .resolve_for(Workload::Infer, self.policy == PolicyKind::Model),
            seeds,
            scenes: self.scenes,
            suppression: SuppressionConfig {
                remember: self.n_past_action,
                sigma_px: self.suppression_sigma,
                rotation_reach: usize::from(self.suppress_rotation_reach),
                other_rotations: self.suppress_other_rotations,
                remember_successes: self.suppress_successes,
            },
            model,
            max_attempts: self.max_attempts,
            give_up_after: self.give_up_after.unwrap_or(give_up_by_default(self.task)),
            push_unverified: self.push_unverified.unwrap_or(pushes_by_default(self.task)),
            record: self.record,
            resume: self.resume,
            check_invariants: self.check_invariants,
            shard: self.shard.unwrap_or(Shard::WHOLE),
            run_by: RunBy::Own,
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
            precision: (self.precision).resolve_for(
                Workload::Infer,
                matches!(self.policy, CollectPolicy::Model | CollectPolicy::Mix),
            ),
            model: ModelPolicyConfig::default(),
            suppression: SuppressionConfig {
                remember: self.n_past_action,
                ..SuppressionConfig::default()
            },
            shard: Shard::WHOLE,
            force: false,
            run_by: RunBy::Own,
        }
    }
}

impl TrialArgs {
    /// Refuses the trial flags that this policy would not read; `model_only` are those of the
    /// model's own, beyond exploring.
    fn refuse_inapplicable(&self, given: &Given, model_only: &[&str]) -> anyhow::Result<()> {
        let policy = format!("--policy {}", self.policy);
        let exploring = EXPLORING
            .iter()
            .chain(model_only)
            .copied()
            .collect::<Vec<_>>();
        if matches!(self.policy, CollectPolicy::Oracle | CollectPolicy::Random) {
            refuse_inapplicable(given, &exploring, "--policy model and mix", &policy)?;
        }
        if self.policy != CollectPolicy::Mix {
            refuse_inapplicable(given, &["oracle_share"], "--policy mix", &policy)?;
        }
        if self.policy == CollectPolicy::Random {
            refuse_inapplicable(
                given,
                &["n_past_action"],
                "--policy model, mix and oracle",
                &policy,
            )?;
        }
        Ok(())
    }
}

impl CollectArgs {
    pub(super) fn config(self, data: &Path, given: &Given) -> anyhow::Result<CollectConfig> {
        self.trials.refuse_inapplicable(given, COLLECT_MODEL_ONLY)?;
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
    pub(super) fn config(self, data: &Path, given: &Given) -> anyhow::Result<ImproveConfig> {
        self.trials.refuse_inapplicable(given, &[])?;
        let out = self.out.unwrap_or_else(|| data.join("improve"));
        let start = checkpoint_path(data, self.trials.checkpoint.clone());
        let precision = self.trials.precision.resolve(Workload::Train);
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
                epoch_samples: self.epoch_samples,
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
            precision: self.precision.resolve(Workload::Infer),
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
    pub(super) fn options(self, data: &Path, given: &Given) -> anyhow::Result<TrainOptions> {
        if self.trials.is_empty() {
            if let Some(flag) = given.first_of(&["trial_weight", "trial_sigma"]) {
                bail!("{flag} weights the trials of --trials DIR, and none is given; add --trials DIR, or leave {flag} out");
            }
        }
        let out_dir = self.out_dir.unwrap_or_else(|| data.join("affordance"));
        for (i, store) in self.trials.iter().enumerate() {
            if let Some(twin) = self.trials[..i]
                .iter()
                .find(|t| identity(t) == identity(store))
            {
                let also = match twin == store {
                    true => String::new(),
                    false => format!(" (also as --trials {})", twin.display()),
                };
                bail!(
                    "--trials {} is given twice{also}; give each trial store once",
                    store.display()
                );
            }
            if identity(store) == identity(&out_dir) {
                bail!(
                    "--trials {} is also where the model goes (--out-dir); give another --out-dir",
                    store.display()
                );
            }
        }
        Ok(TrainOptions {
            config: TrainConfig {
                epochs: self.epochs,
                batch_size: self.batch_size as usize,
                lr: self.lr,
                seed: self.seed,
                precision: self.precision.resolve(Workload::Train),
                input: self.input,
                crop: self.crop,
                trial_weight: self.trial_weight,
                trial_sigma_px: self.trial_sigma,
                ..TrainConfig::default()
            },
            resume: self.resume,
            force: self.force,
            out_dir,
            labels: (!self.no_labels).then(|| data.join("labels")),
            trials: self.trials,
            start_from: self.start_from,
            precision_auto: self.precision == PrecisionChoice::Auto,
            run_by: RunBy::Own,
        })
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The refusals look flags up by id: each id must be one of the command's flags (a typo
    /// would never match, and the flag would be accepted silently).
    #[test]
    fn every_flag_a_refusal_names_is_one_of_the_command_s() {
        use clap::CommandFactory;
        let cli = super::super::Cli::command();
        let lists: [(&str, &[&str]); 9] = [
            ("eval", EMPTY_BIN_ONLY),
            ("eval", EVAL_MODEL_ONLY),
            ("eval", REMEMBERING),
            ("collect", EXPLORING),
            ("collect", COLLECT_MODEL_ONLY),
            ("collect", &["oracle_share", "n_past_action"]),
            ("improve", EXPLORING),
            ("improve", &["oracle_share", "n_past_action"]),
            ("train", &["trial_weight", "trial_sigma"]),
        ];
        for (command, ids) in lists {
            let known: Vec<String> = cli
                .find_subcommand(command)
                .unwrap()
                .get_arguments()
                .map(|a| a.get_id().to_string())
                .collect();
            for id in ids {
                assert!(known.iter().any(|k| k == id), "{command} has no flag {id}");
            }
        }
    }
}
