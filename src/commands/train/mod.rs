//! `graspmap train`: fit the MiniUNet to the labels, with best/last checkpoints, per-epoch visualisations and exact resume.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context as _};
use tch::nn;

mod epoch_files;

use super::{Context, RunBy};
use crate::data::augment::AugmentConfig;
use crate::data::dataset::{load_dataset, split_train_validation, LabelledImage, Supervision};
use crate::data::labels::LabelStore;
use crate::data::lock::{LockError, StoreLock};
use crate::data::output::check_output_dir;
use crate::data::trials::TrialStore;
use crate::interrupt::{self, Interrupted};
use crate::model::checkpoint::{
    file_sha256, load_weights, read_checkpoint, save_checkpoint, CheckpointMeta, EpochRecord,
    StartWeights, TrainingData, TrialSource,
};
use crate::model::config::{Plateau, TrainConfig};
use crate::model::train::{train_epoch, validate, Adam, Subset};
use crate::model::unet::{MiniUNet, Precision};
use crate::named::{counted, Named};
use crate::present::envelope::write_report;
use epoch_files::{save_loss_curve, save_training_vis, write_losses_csv};

/// What `graspmap train` runs.
#[derive(Debug, Clone)]
pub(crate) struct TrainOptions {
    /// The training run's settings.
    pub(crate) config: TrainConfig,
    /// Continue from DATA/affordance/last.* exactly where it stopped.
    pub(crate) resume: bool,
    /// Train anew over an existing model, keeping its best as best.prev.*.
    pub(crate) force: bool,
    /// Where the model goes (DATA/affordance by default).
    pub(crate) out_dir: PathBuf,
    /// The labels folder, or `None` to train on trials alone.
    pub(crate) labels: Option<PathBuf>,
    /// Trial stores to train on as well (`--trials`).
    pub(crate) trials: Vec<PathBuf>,
    /// `--precision auto`: a run that continues the folder's model keeps the precision it was
    /// trained in, whatever this machine's measurement says now.
    pub(crate) precision_auto: bool,
    /// A checkpoint whose weights the run starts from, instead of fresh ones.
    pub(crate) start_from: Option<PathBuf>,
    /// Who runs it, for the advice of its errors.
    pub(crate) run_by: RunBy,
}

#[derive(Debug, serde::Serialize)]
struct TrainResults {
    labels: usize,
    trials: usize,
    train_samples: usize,
    val_samples: usize,
    epochs_run: u32,
    best_epoch: u32,
    best_val_loss: f64,
    final_train_loss: f64,
    final_val_loss: f64,
    wall_seconds: f64,
    checkpoint: String,
}

/// The network, its optimiser and the state that a checkpoint carries.
struct Run {
    vs: nn::VarStore,
    net: MiniUNet,
    adam: Adam,
    meta: CheckpointMeta,
}

/// Runs the command.
pub(crate) fn run(context: &Context, mut options: TrainOptions) -> anyhow::Result<()> {
    if options.precision_auto && !options.force {
        if let Ok((_, meta)) = read_checkpoint(&options.out_dir, "last") {
            options.config.precision = meta.config.precision;
        }
    }
    options.config.channels_last = options.config.precision == Precision::Fp32
        && crate::model::autotune::fp32_trains_channels_last();
    let config = options.config.clone();
    crate::model::use_threads(context.threads);
    tch::manual_seed(config.seed as i64);
    let (images, trained_on) = load_training_data(&options)?;
    let n_labels = trained_on.as_ref().map_or(images.len(), |t| t.labels);
    if images.len() < 2 {
        let what = match &options.labels {
            Some(dir) => format!("{} has {}", dir.display(), counted(n_labels, "label")),
            None => "the trial stores hold".to_owned(),
        };
        bail!(
            "{what} and {}; training needs at least 2 (run graspmap label or graspmap collect first)",
            counted(images.len() - n_labels, "trial")
        );
    }
    let out_dir = options.out_dir.clone();
    check_output_dir(&out_dir.join("training_vis"), "the model folder")?;
    let _writer = StoreLock::acquire(&out_dir, "train")?;
    let resume = resume_or_refuse(context, &options, &out_dir, images.len(), &trained_on)?;
    let mut run = start(&options, &out_dir, images.len(), resume, trained_on)?;
    if run.meta.epoch >= config.epochs {
        context.note(&format!(
            "already trained {} (--epochs {}); nothing to do",
            counted(run.meta.epoch as usize, "epoch"),
            config.epochs
        ));
    }
    let start = Instant::now();
    let augment = AugmentConfig::default();
    run.epochs(context, &options, &images, &augment)?;
    let meta = &run.meta;
    let last = meta.history.last();
    let results = TrainResults {
        labels: n_labels,
        trials: images.len() - n_labels,
        train_samples: meta.train_indices.len(),
        val_samples: meta.val_indices.len(),
        epochs_run: meta.epoch,
        best_epoch: meta.best_epoch,
        best_val_loss: meta.best_val_loss,
        final_train_loss: last.map_or(f64::NAN, |r| r.train_loss),
        final_val_loss: last.map_or(f64::NAN, |r| r.val_loss),
        wall_seconds: start.elapsed().as_secs_f64(),
        checkpoint: out_dir.join("best.safetensors").display().to_string(),
    };
    report(context, &options, &augment, resume, &results)
}

/// Prints the line of a finished training and writes its JSON report.
fn report(
    context: &Context,
    options: &TrainOptions,
    augment: &AugmentConfig,
    resume: bool,
    results: &TrainResults,
) -> anyhow::Result<()> {
    context.say(&format!(
        "trained {} on {}{} ({} train / {} validation): best validation loss {:.5} at epoch {} -> {} ({:.1} s)",
        counted(results.epochs_run as usize, "epoch"),
        counted(results.labels, "label"),
        match results.trials {
            0 => String::new(),
            n => format!(" and {}", counted(n, "trial")),
        },
        results.train_samples,
        results.val_samples,
        results.best_val_loss,
        results.best_epoch,
        results.checkpoint,
        results.wall_seconds
    ));
    if let Some(json) = &context.json {
        let config = &options.config;
        let resolved = serde_json::json!({
            "global": context,
            "train": config,
            "augment": augment,
            "resume": resume,
            "force": options.force,
            "out_dir": options.out_dir,
            "labels": options.labels,
            "trials": options.trials,
            "start_from": options.start_from,
        });
        write_report(json, "train", config.seed, &resolved, results)?;
    }
    Ok(())
}

impl Run {
    /// Trains the epochs left up to `--epochs`, with a progress bar and a line per epoch; a
    /// signal abandons the epoch under way, and ends the command once the last whole one is
    /// named.
    fn epochs(
        &mut self,
        context: &Context,
        options: &TrainOptions,
        images: &[LabelledImage],
        augment: &AugmentConfig,
    ) -> anyhow::Result<()> {
        let config = &options.config;
        let out_dir = &options.out_dir;
        let bar = context.progress_bar("epochs", config.epochs as u64, self.meta.epoch as u64);
        while self.meta.epoch < config.epochs {
            let Some(improved) = self.epoch(images, config, augment, out_dir, &bar)? else {
                bar.finish_and_clear();
                let interrupted = interrupt::requested().unwrap_or(Interrupted { signal: 2 });
                context.stopped(&format!(
                    "{interrupted}: epoch {} was abandoned; {} holds epoch {} complete; {}",
                    self.meta.epoch + 1,
                    out_dir.join("last.safetensors").display(),
                    self.meta.epoch,
                    match options.run_by {
                        RunBy::Own => "rerun with --resume to continue exactly",
                        RunBy::Improve => "rerun the same improve command to continue exactly",
                    }
                ));
                return Err(interrupted.into());
            };
            bar.inc(1);
            let record = self.meta.history.last().copied();
            bar.suspend(|| {
                if let (false, Some(r)) = (context.quiet, record) {
                    eprintln!(
                        "epoch {:>3}: train {:.5}  val {:.5}  lr {:.0e}{}",
                        r.epoch,
                        r.train_loss,
                        r.val_loss,
                        r.lr,
                        if improved { "  best" } else { "" }
                    );
                }
            });
        }
        bar.finish_and_clear();
        Ok(())
    }
}

/// The labels (unless left out) and then every trial store's trials, as training items, with
/// the record of them a checkpoint keeps (`None` for labels alone from fresh weights).
fn load_training_data(
    options: &TrainOptions,
) -> anyhow::Result<(Vec<LabelledImage>, Option<TrainingData>)> {
    let input = options.config.input;
    let mut images = match &options.labels {
        Some(dir) => {
            let store = LabelStore::new(dir);
            let _labels = labels_not_being_written(store.dir())?;
            if options.trials.is_empty() || store.labels_path().exists() {
                load_dataset(&store, input)?
            } else {
                Vec::new()
            }
        }
        None => Vec::new(),
    };
    let labels = images.len();
    let mut sources = Vec::new();
    for dir in &options.trials {
        let store = TrialStore::new(dir);
        let _collecting = match StoreLock::acquire(dir, "collect") {
            Ok(lock) => Some(lock),
            Err(held @ LockError::Held { .. }) => {
                return Err(anyhow::Error::new(held)
                    .context("training needs the finished trials; wait for the collection to end"))
            }
            Err(LockError::Io { .. }) => None,
        };
        let trials = store.load_all(input)?;
        let scenes: std::collections::BTreeSet<u64> = trials.iter().map(|t| t.scene).collect();
        sources.push(TrialSource {
            dir: dir.clone(),
            scenes: scenes.len(),
            trials: trials.len(),
            successes: trials.iter().filter(|t| t.trial.success).count(),
        });
        images.extend(trials.into_iter().enumerate().map(|(k, t)| LabelledImage {
            object: t.trial.held.or(t.trial.aimed_at).unwrap_or_default(),
            k: k + 1,
            image: t.image,
            height: t.height,
            grasp: t.trial.grasp,
            supervision: Supervision::Trial {
                success: t.trial.success,
            },
        }));
    }
    let start = match &options.start_from {
        Some(path) => Some(StartWeights {
            path: path.clone(),
            sha256: file_sha256(path)?,
        }),
        None => None,
    };
    let trained_on = (!sources.is_empty() || start.is_some()).then_some(TrainingData {
        labels,
        trials: sources,
        start,
    });
    Ok((images, trained_on))
}

/// Holds the labels' lock while the dataset is read, so that training never starts on a
/// dataset that a running `graspmap label` is still appending to. A labels folder that cannot
/// be locked for another reason (a read-only copy, say) cannot be written by `label` either.
fn labels_not_being_written(dir: &Path) -> anyhow::Result<Option<StoreLock>> {
    if !dir.is_dir() {
        return Ok(None);
    }
    match StoreLock::acquire(dir, "label") {
        Ok(lock) => Ok(Some(lock)),
        Err(held @ LockError::Held { .. }) => Err(anyhow::Error::new(held)
            .context("training needs the finished labels; wait for the labelling run to end")),
        Err(LockError::Io { .. }) => Ok(None),
    }
}

/// Whether training continues the run in `out_dir`: with `--resume`, always; with `--force`,
/// never (the old best is kept as best.prev.*); otherwise only when the model there was
/// trained with the same settings on the same number of labels, and a refusal that names both
/// ways forward when not.
fn resume_or_refuse(
    context: &Context,
    options: &TrainOptions,
    out_dir: &Path,
    n_images: usize,
    trained_on: &Option<TrainingData>,
) -> anyhow::Result<bool> {
    let best = out_dir.join("best.safetensors");
    let last = out_dir.join("last.safetensors");
    if options.resume {
        return Ok(true);
    }
    if !best.exists() && !last.exists() {
        return Ok(false);
    }
    if options.force {
        keep_previous_best(out_dir)?;
        context.say(&format!(
            "--force: training anew; the previous best model is kept as {}",
            out_dir.join("best.prev.safetensors").display()
        ));
        return Ok(false);
    }
    let why = match read_checkpoint(out_dir, "last") {
        Ok((_, meta)) => match resumable(&meta, &options.config, n_images, trained_on) {
            Ok(()) => {
                context.note(&format!(
                    "resuming {} at epoch {} (same settings and labels; --force trains anew)",
                    last.display(),
                    meta.epoch
                ));
                return Ok(true);
            }
            Err(why) => why,
        },
        Err(e) => format!("has no readable training state ({e:#})"),
    };
    // --resume would meet the same difference: the ways forward are a new run here, or
    // another folder.
    let fix = match options.run_by {
        RunBy::Own => "pass --force to train anew (the old best is kept as best.prev.safetensors), or --out-dir DIR to train into another folder",
        RunBy::Improve => "rerun improve with the flags that made it, or give improve another --out folder",
    };
    bail!(
        "{} already holds a trained model, and {} {why}; {fix}",
        best.display(),
        last.display()
    )
}

/// Why the run a checkpoint holds cannot continue with `config` on `n_images` labels.
fn resumable(
    meta: &CheckpointMeta,
    config: &TrainConfig,
    n_images: usize,
    trained_on: &Option<TrainingData>,
) -> Result<(), String> {
    let saved = &meta.config;
    if saved.seed != config.seed
        || saved.batch_size != config.batch_size
        || saved.lr != config.lr
        || saved.precision != config.precision
        || saved.input != config.input
        || saved.crop != config.crop
        || saved.trial_weight != config.trial_weight
        || saved.trial_sigma_px != config.trial_sigma_px
        || saved.epoch_samples != config.epoch_samples
    {
        return Err(format!(
            "was trained with --seed {} --batch-size {} --lr {} --precision {} --input {} --crop {} --trial-weight {} --trial-sigma {}",
            saved.seed,
            saved.batch_size,
            saved.lr,
            saved.precision.name(),
            saved.input,
            saved.crop,
            saved.trial_weight,
            saved.trial_sigma_px
        ));
    }
    if &meta.trained_on != trained_on {
        let describe = |t: &Option<TrainingData>| match t {
            None => "the labels alone from fresh weights".to_owned(),
            Some(t) => format!(
                "{} and {} from {}",
                counted(t.labels, "label"),
                counted(t.trials.iter().map(|s| s.trials).sum::<usize>(), "trial"),
                t.start
                    .as_ref()
                    .map_or("fresh weights".to_owned(), |s| s.path.display().to_string())
            ),
        };
        return Err(format!(
            "was trained on {}, and this run has {}",
            describe(&meta.trained_on),
            describe(trained_on)
        ));
    }
    let known = meta.train_indices.len() + meta.val_indices.len();
    if known != n_images {
        return Err(format!(
            "was trained on {known} labels, and the labels folder holds {n_images} now"
        ));
    }
    Ok(())
}

/// Moves best.* to best.prev.* (replacing an older pair) and drops the abandoned run's
/// resume state, last.*.
fn keep_previous_best(out_dir: &Path) -> anyhow::Result<()> {
    for (from, to) in [
        ("best.safetensors", "best.prev.safetensors"),
        ("best.json", "best.prev.json"),
    ] {
        let from = out_dir.join(from);
        if from.exists() {
            let to = out_dir.join(to);
            std::fs::rename(&from, &to)
                .with_context(|| format!("keeping {} as {}", from.display(), to.display()))?;
        }
    }
    for name in ["last.safetensors", "last.json"] {
        let path = out_dir.join(name);
        if path.exists() {
            std::fs::remove_file(&path).with_context(|| format!("removing {}", path.display()))?;
        }
    }
    Ok(())
}

/// A fresh network with its 90/10 split, or the run that last.* holds.
fn start(
    options: &TrainOptions,
    out_dir: &Path,
    n_images: usize,
    resume: bool,
    trained_on: Option<TrainingData>,
) -> anyhow::Result<Run> {
    let config = &options.config;
    let mut vs = nn::VarStore::new(tch::Device::Cpu);
    let net = MiniUNet::with_input(&vs.root(), config.input);
    let mut adam = Adam::new(&vs, config.lr);
    if !resume {
        if let Some(path) = &options.start_from {
            let decoded = crate::model::checkpoint::read(
                path,
                "give another --start-from, or train from fresh weights without it",
            )?;
            load_weights(&mut vs, &decoded.tensors, path)?;
        }
        let (train_indices, val_indices) = split_train_validation(n_images, config.seed);
        let meta = CheckpointMeta {
            schema: CheckpointMeta::SCHEMA.to_owned(),
            config: config.clone(),
            epoch: 0,
            history: Vec::new(),
            best_val_loss: f64::INFINITY,
            best_epoch: 0,
            lr: config.lr,
            plateau: Plateau::default(),
            adam_steps: 0,
            train_indices,
            val_indices,
            trained_on,
        };
        return Ok(Run {
            vs,
            net,
            adam,
            meta,
        });
    }
    let (tensors, mut meta) = read_checkpoint(out_dir, "last")?;
    if let Err(why) = resumable(&meta, config, n_images, &trained_on) {
        bail!(
            "{} {why}; resume with the same settings and labels, or train anew with --force",
            out_dir.join("last.json").display()
        );
    }
    load_weights(&mut vs, &tensors, &out_dir.join("last.safetensors"))?;
    adam.restore(&tensors, meta.adam_steps)?;
    adam.lr = meta.lr;
    meta.config.epochs = config.epochs;
    Ok(Run {
        vs,
        net,
        adam,
        meta,
    })
}

impl Run {
    /// Trains and validates one epoch, then saves best.* (when validation improved), last.*,
    /// the loss table and curve, and the epoch's visualisation. Returns whether it improved, or
    /// `None` when a signal asked to stop mid-epoch: nothing of it is saved, so the files on disk
    /// still hold the last complete epoch.
    fn epoch(
        &mut self,
        images: &[LabelledImage],
        config: &TrainConfig,
        augment: &AugmentConfig,
        out_dir: &Path,
        bar: &indicatif::ProgressBar,
    ) -> anyhow::Result<Option<bool>> {
        let meta = &mut self.meta;
        let epoch = meta.epoch + 1;
        let epoch_start = Instant::now();
        let batches = meta.train_indices.len().div_ceil(config.batch_size);
        let train_loss = train_epoch(
            &self.net,
            &mut self.adam,
            Subset {
                images,
                indices: &meta.train_indices,
            },
            config,
            epoch,
            augment,
            |b, loss| {
                bar.set_message(format!(
                    "epoch {epoch} batch {}/{batches} loss {loss:.5}",
                    b + 1
                ));
                match interrupt::requested() {
                    Some(_) => ControlFlow::Break(()),
                    None => ControlFlow::Continue(()),
                }
            },
        );
        let Some(train_loss) = train_loss else {
            return Ok(None);
        };
        let validation = validate(
            &self.net,
            Subset {
                images,
                indices: config.validated(&meta.val_indices),
            },
            config,
        );
        let val_loss = validation.loss;
        meta.history.push(EpochRecord {
            epoch,
            train_loss,
            val_loss,
            lr: self.adam.lr,
            seconds: epoch_start.elapsed().as_secs_f64(),
        });
        self.adam.lr = meta.plateau.update(val_loss, self.adam.lr, config);
        meta.epoch = epoch;
        meta.lr = self.adam.lr;
        meta.adam_steps = self.adam.steps();
        let improved = val_loss < meta.best_val_loss;
        if improved {
            meta.best_val_loss = val_loss;
            meta.best_epoch = epoch;
            save_checkpoint(&self.vs, &[], meta, out_dir, "best")?;
        }
        save_checkpoint(&self.vs, &self.adam.named_state(), meta, out_dir, "last")?;
        write_losses_csv(&out_dir.join("losses.csv"), &meta.history)?;
        save_loss_curve(&out_dir.join("losses.png"), &meta.history)?;
        if let (Some(&first), Some(map)) = (meta.val_indices.first(), &validation.first_map) {
            let vis_dir = out_dir.join("training_vis");
            save_training_vis(map, &images[first], &vis_dir, epoch)?;
        }
        Ok(Some(improved))
    }
}
