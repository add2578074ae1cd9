//! Training the affordance model (docs/learning.md): Adam with our own moment tensors, LR reduction on plateau, exact resume.
//!
//! tch's optimiser cannot export its moments, so Adam lives here as plain tensors; together
//! with the step count, the schedule state and per-epoch seeded data order, `last.*` holds
//! everything needed to continue a run exactly where it stopped.

use std::collections::BTreeMap;
use std::ops::ControlFlow;
use std::path::Path;

use anyhow::{bail, Context};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use tch::nn;
use tch::{Device, Kind, Reduction, Tensor};

use super::checkpoint;
use crate::data::augment::AugmentConfig;
use crate::data::dataset::{training_sample, LabelledImage, Sample};
use crate::data::input::InputKind;
use crate::model::unet::{MiniUNet, Precision};

/// Training settings (the reference's defaults).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainConfig {
    /// Epochs to run (101).
    pub(crate) epochs: u32,
    /// Images per optimiser step (8).
    pub(crate) batch_size: usize,
    /// Initial Adam learning rate (1e-3).
    pub(crate) lr: f64,
    /// Seed of the split, the initial weights, the data order and the augmentation.
    pub(crate) seed: u64,
    /// Multiply the LR by this after `patience` epochs without validation improvement (0.1).
    pub(crate) lr_factor: f64,
    /// Epochs without improvement before the LR drops (3).
    pub(crate) patience: u32,
    /// Arithmetic of the forward and backward passes.
    pub precision: Precision,
    /// What the network sees (`--input`). Left out of the JSON when rgb, so rgb checkpoints keep
    /// the bytes they had before the option existed, and older checkpoints read as rgb.
    #[serde(default, skip_serializing_if = "InputKind::is_rgb")]
    pub input: InputKind,
}

impl Default for TrainConfig {
    fn default() -> Self {
        Self {
            epochs: 101,
            batch_size: 8,
            lr: 1e-3,
            seed: 0,
            lr_factor: 0.1,
            patience: 3,
            precision: Precision::Fp32,
            input: InputKind::Rgb,
        }
    }
}

/// Adam (β 0.9/0.999, ε 1e-8, no weight decay), PyTorch's update rule.
pub(crate) struct Adam {
    /// Current learning rate.
    pub(crate) lr: f64,
    step: i64,
    names: Vec<String>,
    params: Vec<Tensor>,
    exp_avg: Vec<Tensor>,
    exp_avg_sq: Vec<Tensor>,
}

const BETA1: f64 = 0.9;
const BETA2: f64 = 0.999;
const EPSILON: f64 = 1e-8;

impl Adam {
    /// Adam over every variable of `vs`, in name order.
    pub(crate) fn new(vs: &nn::VarStore, lr: f64) -> Self {
        let vars: BTreeMap<String, Tensor> = vs.variables().into_iter().collect();
        let names: Vec<String> = vars.keys().cloned().collect();
        let params: Vec<Tensor> = vars.into_values().collect();
        let exp_avg = params.iter().map(|p| p.zeros_like()).collect();
        let exp_avg_sq = params.iter().map(|p| p.zeros_like()).collect();
        Self {
            lr,
            step: 0,
            names,
            params,
            exp_avg,
            exp_avg_sq,
        }
    }

    /// One update from the gradients in the parameters; then clears them.
    pub(crate) fn step(&mut self) {
        self.step += 1;
        let bias1 = 1.0 - BETA1.powi(self.step as i32);
        let bias2 = 1.0 - BETA2.powi(self.step as i32);
        tch::no_grad(|| {
            for ((p, m), v) in self
                .params
                .iter_mut()
                .zip(&mut self.exp_avg)
                .zip(&mut self.exp_avg_sq)
            {
                let grad = p.grad();
                if !grad.defined() {
                    continue;
                }
                let _ = m.g_mul_scalar_(BETA1).g_add_(&(&grad * (1.0 - BETA1)));
                let _ = v
                    .g_mul_scalar_(BETA2)
                    .g_add_(&(&grad * &grad * (1.0 - BETA2)));
                let denom = (v.sqrt() / bias2.sqrt()) + EPSILON;
                let update = m.divide(&denom) * (self.lr / bias1);
                let _ = p.g_sub_(&update);
                p.zero_grad();
            }
        });
    }

    /// Optimiser steps taken.
    pub(crate) fn steps(&self) -> i64 {
        self.step
    }

    /// The moment tensors, named after their parameters.
    pub(crate) fn named_state(&self) -> Vec<(String, Tensor)> {
        self.names
            .iter()
            .zip(&self.exp_avg)
            .map(|(n, t)| (format!("optimizer.exp_avg.{n}"), t.shallow_clone()))
            .chain(
                self.names
                    .iter()
                    .zip(&self.exp_avg_sq)
                    .map(|(n, t)| (format!("optimizer.exp_avg_sq.{n}"), t.shallow_clone())),
            )
            .collect()
    }

    /// Restores moments and step count saved by [`Adam::named_state`].
    pub(crate) fn restore(
        &mut self,
        tensors: &BTreeMap<String, Tensor>,
        steps: i64,
    ) -> anyhow::Result<()> {
        for (i, name) in self.names.iter().enumerate() {
            for (prefix, slot) in [
                ("optimizer.exp_avg.", &mut self.exp_avg[i]),
                ("optimizer.exp_avg_sq.", &mut self.exp_avg_sq[i]),
            ] {
                let key = format!("{prefix}{name}");
                let saved = tensors
                    .get(&key)
                    .with_context(|| format!("the checkpoint has no {key}"))?;
                if saved.size() != slot.size() {
                    bail!(
                        "{key} has shape {:?}, expected {:?}",
                        saved.size(),
                        slot.size()
                    );
                }
                tch::no_grad(|| slot.copy_(saved));
            }
        }
        self.step = steps;
        Ok(())
    }
}

/// ReduceLROnPlateau in PyTorch's default mode: relative threshold 1e-4.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plateau {
    /// Best validation loss so far (none before the first epoch).
    pub(crate) best: Option<f64>,
    /// Epochs since it improved.
    pub(crate) bad_epochs: u32,
}

impl Plateau {
    /// Feeds one epoch's validation loss; returns the new learning rate.
    pub(crate) fn update(&mut self, loss: f64, lr: f64, config: &TrainConfig) -> f64 {
        if self.best.is_none_or(|best| loss < best * (1.0 - 1e-4)) {
            self.best = Some(loss);
            self.bad_epochs = 0;
            lr
        } else {
            self.bad_epochs += 1;
            if self.bad_epochs > config.patience {
                self.bad_epochs = 0;
                lr * config.lr_factor
            } else {
                lr
            }
        }
    }
}

/// One epoch's record.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EpochRecord {
    /// 1-based epoch.
    pub epoch: u32,
    /// Mean training loss (BCE with logits).
    pub train_loss: f64,
    /// Mean validation loss.
    pub val_loss: f64,
    /// Learning rate used in the epoch.
    pub lr: f64,
    /// Wall seconds of the epoch.
    pub(crate) seconds: f64,
}

/// The JSON sidecar of a checkpoint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckpointMeta {
    /// `graspmap.checkpoint/1`.
    pub schema: String,
    /// Settings of the run.
    pub config: TrainConfig,
    /// Epochs completed.
    pub epoch: u32,
    /// Every epoch so far.
    pub history: Vec<EpochRecord>,
    /// Best validation loss and its epoch.
    pub best_val_loss: f64,
    /// Epoch of the best validation loss.
    pub best_epoch: u32,
    /// Learning rate for the next epoch.
    pub lr: f64,
    /// LR schedule state.
    pub plateau: Plateau,
    /// Adam steps taken.
    pub adam_steps: i64,
    /// Indices (into the labelled images) used for training and validation.
    pub train_indices: Vec<usize>,
    /// Validation indices.
    pub val_indices: Vec<usize>,
}

impl CheckpointMeta {
    /// The schema name.
    pub const SCHEMA: &'static str = "graspmap.checkpoint/1";
}

/// Writes weights (plus any extra tensors) with the training state inside, and its JSON copy.
pub fn save_checkpoint(
    vs: &nn::VarStore,
    extra: &[(String, Tensor)],
    meta: &CheckpointMeta,
    dir: &Path,
    name: &str,
) -> anyhow::Result<()> {
    let mut named: Vec<(String, Tensor)> = vs.variables().into_iter().collect();
    named.extend(extra.iter().map(|(n, t)| (n.clone(), t.shallow_clone())));
    checkpoint::write(named, meta, dir, name)
}

/// Reads a checkpoint's tensors and training state, with errors that name the file and the
/// fix. The state comes from inside the weights file; a checkpoint from before it was embedded
/// falls back to its JSON sidecar.
pub fn read_checkpoint(
    dir: &Path,
    name: &str,
) -> anyhow::Result<(BTreeMap<String, Tensor>, CheckpointMeta)> {
    let (weights, sidecar) = checkpoint::checkpoint_paths(dir, name);
    let decoded = checkpoint::read(&weights)?;
    let sidecar_meta = || -> anyhow::Result<CheckpointMeta> {
        let text = std::fs::read_to_string(&sidecar)
            .with_context(|| format!("reading {}", sidecar.display()))?;
        checkpoint::parse_meta(&text, &sidecar)
    };
    let meta = match decoded.meta {
        Some(mut meta) => {
            // The wall times live in the JSON copy only; take them when it is this epoch's.
            if let Ok(copy) = sidecar_meta() {
                if copy.epoch == meta.epoch && copy.history.len() == meta.history.len() {
                    for (record, timed) in meta.history.iter_mut().zip(&copy.history) {
                        record.seconds = timed.seconds;
                    }
                }
            }
            meta
        }
        None => sidecar_meta().with_context(|| {
            format!(
                "{} holds no training state; train from scratch",
                weights.display()
            )
        })?,
    };
    Ok((decoded.tensors, meta))
}

/// Copies the model's weights out of a checkpoint's tensors.
pub fn load_weights(
    vs: &mut nn::VarStore,
    tensors: &BTreeMap<String, Tensor>,
    source: &Path,
) -> anyhow::Result<()> {
    for (name, mut var) in vs.variables() {
        let saved = tensors
            .get(&name)
            .with_context(|| format!("{} has no tensor '{name}'", source.display()))?;
        if saved.size() != var.size() {
            bail!(
                "{}: '{name}' has shape {:?}, the model needs {:?}",
                source.display(),
                saved.size(),
                var.size()
            );
        }
        tch::no_grad(|| var.copy_(&saved.to_kind(var.kind())));
    }
    Ok(())
}

/// Stacks samples into an input batch N×C×H×W (C = 3, or 4 for rgbd) and a target batch
/// N×1×H×W.
pub(crate) fn batch(samples: &[Sample], size: i64) -> (Tensor, Tensor) {
    let n = samples.len() as i64;
    let inputs: Vec<f32> = samples
        .iter()
        .flat_map(|s| s.input.iter().copied())
        .collect();
    let targets: Vec<f32> = samples
        .iter()
        .flat_map(|s| s.target.iter().copied())
        .collect();
    (
        Tensor::from_slice(&inputs).view([n, -1, size, size]),
        Tensor::from_slice(&targets).view([n, 1, size, size]),
    )
}

/// Mean BCE-with-logits of a batch (computed in float32 whatever the precision).
pub(crate) fn loss(
    net: &MiniUNet,
    input: &Tensor,
    target: &Tensor,
    precision: Precision,
) -> Tensor {
    net.forward_with(input, precision)
        .binary_cross_entropy_with_logits::<Tensor>(target, None, None, Reduction::Mean)
}

/// The per-epoch RNG: a pure function of the seed and the epoch, so a resumed run draws the
/// same data order and augmentations as an uninterrupted one.
pub(crate) fn epoch_rng(seed: u64, epoch: u32) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(1000 + epoch as u64);
    rng
}

/// The images an epoch draws from, and which of them it uses.
#[derive(Clone, Copy)]
pub(crate) struct Subset<'a> {
    /// Every labelled image.
    pub(crate) images: &'a [LabelledImage],
    /// The ones in this subset.
    pub(crate) indices: &'a [usize],
}

/// Trains one epoch; returns the mean training loss, or `None` when `on_batch` breaks off
/// (the epoch is then abandoned half-way and must not be saved).
pub(crate) fn train_epoch(
    net: &MiniUNet,
    adam: &mut Adam,
    data: Subset,
    config: &TrainConfig,
    epoch: u32,
    augment: &AugmentConfig,
    mut on_batch: impl FnMut(usize, f64) -> ControlFlow<()>,
) -> Option<f64> {
    let mut rng = epoch_rng(config.seed, epoch);
    let mut order = data.indices.to_vec();
    order.shuffle(&mut rng);
    let mut total = 0.0;
    let mut count = 0usize;
    for (b, chunk) in order.chunks(config.batch_size).enumerate() {
        let samples: Vec<Sample> = chunk
            .iter()
            .map(|&i| training_sample(&data.images[i], Some((augment, &mut rng))))
            .collect();
        let (input, target) = batch(&samples, crate::grasp::IMAGE_SIZE as i64);
        let l = loss(
            net,
            &input.to_device(Device::Cpu),
            &target,
            config.precision,
        );
        l.backward();
        adam.step();
        let value = l.double_value(&[]);
        total += value * chunk.len() as f64;
        count += chunk.len();
        if on_batch(b, value).is_break() {
            return None;
        }
    }
    Some(total / count.max(1) as f64)
}

/// Mean validation loss over unaugmented samples.
pub(crate) fn validate(net: &MiniUNet, data: Subset, config: &TrainConfig) -> f64 {
    let (images, indices, batch_size) = (data.images, data.indices, config.batch_size);
    tch::no_grad(|| {
        let mut total = 0.0;
        for chunk in indices.chunks(batch_size) {
            let samples: Vec<Sample> = chunk
                .iter()
                .map(|&i| training_sample(&images[i], None))
                .collect();
            let (input, target) = batch(&samples, crate::grasp::IMAGE_SIZE as i64);
            total +=
                loss(net, &input, &target, config.precision).double_value(&[]) * chunk.len() as f64;
        }
        total / indices.len().max(1) as f64
    })
}

/// The predicted affordance (sigmoid) for one sample, H×W in [0, 1].
pub(crate) fn predict_map(net: &MiniUNet, sample: &Sample, precision: Precision) -> Vec<f32> {
    tch::no_grad(|| {
        let (input, _) = batch(
            std::slice::from_ref(sample),
            crate::grasp::IMAGE_SIZE as i64,
        );
        let out = net
            .forward_with(&input, precision)
            .sigmoid()
            .to_kind(Kind::Float)
            .flatten(0, -1);
        Vec::<f32>::try_from(out).expect("a float tensor converts to Vec<f32>")
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use tch::nn::{Module, OptimizerConfig};

    #[test]
    fn adam_matches_libtorch_adam_step_for_step() {
        let data = Tensor::from_slice(&[0.3f32, -1.2, 2.0, 0.7, -0.1, 1.5]).view([2, 3]);
        let run = |ours: bool| {
            let vs = nn::VarStore::new(Device::Cpu);
            let mut layer = nn::linear(vs.root() / "l", 3, 2, Default::default());
            // Fixed starting weights, not the global seed: other tests draw from libtorch's one
            // generator on their own threads, and a draw between seeding and init made this flaky.
            tch::no_grad(|| {
                layer
                    .ws
                    .copy_(&Tensor::from_slice(&[0.5f32, -0.3, 0.2, 0.1, 0.4, -0.6]).view([2, 3]));
                if let Some(bs) = &mut layer.bs {
                    bs.copy_(&Tensor::from_slice(&[0.05f32, -0.02]));
                }
            });
            let mut mine = Adam::new(&vs, 1e-2);
            let mut theirs = nn::Adam::default().build(&vs, 1e-2).unwrap();
            for _ in 0..20 {
                let loss = layer.forward(&data).pow_tensor_scalar(2).mean(Kind::Float);
                if ours {
                    loss.backward();
                    mine.step();
                } else {
                    theirs.backward_step(&loss);
                }
            }
            layer.ws.copy()
        };
        let diff = (run(true) - run(false)).abs().max().double_value(&[]);
        assert!(diff < 1e-6, "max difference {diff}");
    }

    #[test]
    fn plateau_drops_the_rate_after_patience_epochs_without_improvement() {
        let config = TrainConfig::default();
        let mut plateau = Plateau::default();
        let mut lr = 1e-3;
        let mut rates = Vec::new();
        for loss in [1.0, 0.9, 0.95, 0.95, 0.95, 0.95, 0.95, 0.8] {
            lr = plateau.update(loss, lr, &config);
            rates.push(lr);
        }
        // Three bad epochs are tolerated; the fourth cuts the rate tenfold.
        assert_eq!(rates[..5], [1e-3; 5]);
        assert!((rates[5] - 1e-4).abs() < 1e-12, "{rates:?}");
        assert!((rates[7] - 1e-4).abs() < 1e-12, "{rates:?}");
    }

    #[test]
    fn epoch_rngs_differ_by_epoch_and_repeat_by_seed() {
        use rand::Rng;
        let a: u64 = epoch_rng(1, 3).random();
        assert_eq!(a, epoch_rng(1, 3).random::<u64>());
        assert_ne!(a, epoch_rng(1, 4).random::<u64>());
        assert_ne!(a, epoch_rng(2, 3).random::<u64>());
    }
}
