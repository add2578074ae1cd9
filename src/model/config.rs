//! What a training run is set to, and the learning-rate schedule's state: both recorded in
//! every checkpoint, so that inference and `--resume` rebuild exactly what was trained.

use serde::{Deserialize, Serialize};

use crate::data::dataset::TrialWeighting;
use crate::data::input::InputKind;

/// The training crop's side by default (docs/departures.md, "Crop training").
pub(crate) const DEFAULT_CROP: u32 = 64;
use crate::model::unet::Precision;

/// Training settings (the reference's defaults).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainConfig {
    /// Epochs to run (30: the reference runs 101, but its validation loss settles by 30;
    /// docs/departures.md).
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
    /// Side of the square crop around each supervised pixel that a training step sees; 0 trains
    /// on whole images (as checkpoints made before crops read). Validation always sees whole
    /// images.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub(crate) crop: u32,
    /// A trial sample's total loss weight against a label's 1 (`--trial-weight`).
    #[serde(
        default = "default_trial_weight",
        skip_serializing_if = "is_default_trial_weight"
    )]
    pub(crate) trial_weight: f32,
    /// σ of a trial's weighted window in pixels; 0 weights the executed pixel alone.
    #[serde(default, skip_serializing_if = "is_zero_f32")]
    pub(crate) trial_sigma_px: f32,
    /// At most this many training images per epoch (improve's `--epoch-samples`), so that an
    /// epoch costs the same however many trial stores there are: every label, then trials
    /// drawn afresh each epoch; and at most a ninth of it validates (the same images every
    /// epoch). 0: every image, as `train` does.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub(crate) epoch_samples: u32,
    /// fp32 training steps run their batches in channels_last layout, where this machine
    /// measured them faster (model::autotune). Not recorded: the arithmetic is the same, only
    /// the kernels' order of operations differs; a resumed run on the machine measures alike.
    #[serde(skip)]
    pub(crate) channels_last: bool,
}

fn is_zero(value: &u32) -> bool {
    *value == 0
}

fn is_zero_f32(value: &f32) -> bool {
    *value == 0.0
}

fn default_trial_weight() -> f32 {
    TrialWeighting::default().weight
}

fn is_default_trial_weight(value: &f32) -> bool {
    *value == default_trial_weight()
}

impl TrainConfig {
    /// The validation images an epoch scores: the first of `val_indices` (a random split)
    /// under an epoch budget, else all.
    pub(crate) fn validated<'a>(&self, val_indices: &'a [usize]) -> &'a [usize] {
        match self.epoch_samples {
            0 => val_indices,
            budget => &val_indices[..val_indices.len().min((budget as usize / 9).max(1))],
        }
    }

    /// How its trial samples are weighted.
    pub(crate) fn trial_weighting(&self) -> TrialWeighting {
        TrialWeighting {
            weight: self.trial_weight,
            sigma_px: self.trial_sigma_px,
        }
    }
}

impl Default for TrainConfig {
    fn default() -> Self {
        Self {
            epochs: 30,
            batch_size: 8,
            lr: 1e-3,
            seed: 0,
            lr_factor: 0.1,
            patience: 3,
            precision: Precision::Fp32,
            input: InputKind::Rgb,
            crop: DEFAULT_CROP,
            trial_weight: default_trial_weight(),
            trial_sigma_px: 0.0,
            epoch_samples: 0,
            channels_last: false,
        }
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
