//! Training the affordance model (docs/learning.md): Adam with our own moment tensors, LR reduction on plateau, exact resume.
//!
//! tch's optimiser cannot export its moments, so Adam lives here as plain tensors; together
//! with the step count, the schedule state and per-epoch seeded data order, `last.*` holds
//! everything needed to continue a run exactly where it stopped.

use std::collections::BTreeMap;
use std::ops::ControlFlow;

use anyhow::{bail, Context};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tch::nn;
use tch::{Kind, Reduction, Tensor};

use super::config::TrainConfig;
use crate::data::augment::AugmentConfig;
use crate::data::dataset::{crop_sample, training_sample, LabelledImage, Sample, Supervision};
use crate::model::inference::network_layout;
use crate::model::unet::{MiniUNet, Precision};

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

/// Stacks samples into an input batch N×C×H×W (C = 3, or 4 for rgbd) and a target batch
/// N×1×H×W.
pub(crate) fn batch(samples: &[Sample], size: i64) -> (Tensor, Tensor) {
    let n = samples.len() as i64;
    debug_assert!(samples.iter().all(|s| s.target.len() as i64 == size * size));
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

/// The per-pixel weights of a batch, N×1×H×W, when any sample is a trial: a label's pixels
/// share its weight of 1 evenly, a trial's sit where its sample puts them. `None` for labels
/// alone, whose loss is then the plain mean.
pub(crate) fn batch_weights(samples: &[Sample], size: i64) -> Option<Tensor> {
    if samples.iter().all(|s| s.weight.is_none()) {
        return None;
    }
    let plane = (size * size) as usize;
    let uniform = 1.0 / plane as f32;
    let mut weights = Vec::with_capacity(samples.len() * plane);
    for sample in samples {
        match &sample.weight {
            Some(w) => weights.extend_from_slice(w),
            None => weights.extend(std::iter::repeat_n(uniform, plane)),
        }
    }
    Some(Tensor::from_slice(&weights).view([samples.len() as i64, 1, size, size]))
}

/// BCE-with-logits of a batch's logits: the plain mean over every pixel without weights, else
/// the weighted sum per sample, averaged over the samples (which equals the plain mean for
/// labels alone).
pub(crate) fn weighted_loss(logits: &Tensor, target: &Tensor, weights: Option<&Tensor>) -> Tensor {
    match weights {
        None => {
            logits.binary_cross_entropy_with_logits::<Tensor>(target, None, None, Reduction::Mean)
        }
        Some(w) => {
            let n = logits.size()[0] as f64;
            logits.binary_cross_entropy_with_logits::<&Tensor>(
                target,
                Some(w),
                None,
                Reduction::Sum,
            ) / n
        }
    }
}

/// How a batch is laid out before the network sees it.
#[derive(Clone, Copy)]
enum Layout {
    /// A training step's: fp32 batches in channels_last where the machine's measurement found
    /// its backward pass faster so.
    Training { channels_last: bool },
    /// Eval's ([`network_layout`]): a forward pass alone, whose faster layout validation
    /// shares.
    Inference,
}

/// The logits of a batch of samples and its loss.
fn samples_loss(
    net: &MiniUNet,
    samples: &[Sample],
    precision: Precision,
    layout: Layout,
) -> (Tensor, Tensor) {
    let size = (samples[0].target.len() as f64).sqrt() as i64;
    let (input, target) = batch(samples, size);
    let input = match (layout, precision) {
        (Layout::Inference, _) => network_layout(&input, precision),
        (
            Layout::Training {
                channels_last: true,
            },
            Precision::Fp32,
        ) => crate::model::unet::channels_last(&input),
        (Layout::Training { .. }, _) => input,
    };
    let weights = batch_weights(samples, size);
    let logits = net.forward_with(&input, precision);
    let loss = weighted_loss(&logits, &target, weights.as_ref());
    (logits, loss)
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
    within_budget(&mut order, data.images, config.epoch_samples as usize);
    let mut total = 0.0;
    let mut count = 0usize;
    let weighting = config.trial_weighting();
    for (b, chunk) in order.chunks(config.batch_size).enumerate() {
        let samples: Vec<Sample> = chunk
            .iter()
            .map(|&i| {
                let sample = training_sample(&data.images[i], weighting, Some((augment, &mut rng)));
                match config.crop {
                    0 => sample,
                    crop => crop_sample(&sample, crop, &mut rng),
                }
            })
            .collect();
        let layout = Layout::Training {
            channels_last: config.channels_last,
        };
        let (_, l) = samples_loss(net, &samples, config.precision, layout);
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

/// Keeps at most `budget` of the shuffled `order` (0: all): every label, then the trials that
/// come first in it, in their shuffled order.
fn within_budget(order: &mut Vec<usize>, images: &[LabelledImage], budget: usize) {
    if budget == 0 || order.len() <= budget {
        return;
    }
    let is_label = |i: usize| images[i].supervision == Supervision::Label;
    let labels = order.iter().filter(|&&i| is_label(i)).count();
    let mut trials_left = budget.saturating_sub(labels);
    order.retain(|&i| {
        if is_label(i) {
            return true;
        }
        let keep = trials_left > 0;
        trials_left = trials_left.saturating_sub(1);
        keep
    });
}

/// An epoch's validation.
pub(crate) struct Validation {
    /// Mean loss over the unaugmented samples.
    pub(crate) loss: f64,
    /// The first sample's predicted affordance (sigmoid), H×W in [0, 1], for the epoch's
    /// picture: the pass that scored it, so the picture costs no forward pass of its own.
    pub(crate) first_map: Option<Vec<f32>>,
}

/// Scores the validation samples, unaugmented.
pub(crate) fn validate(net: &MiniUNet, data: Subset, config: &TrainConfig) -> Validation {
    let (images, indices, batch_size) = (data.images, data.indices, config.batch_size);
    tch::no_grad(|| {
        let mut total = 0.0;
        let mut first_map = None;
        for chunk in indices.chunks(batch_size) {
            let samples: Vec<Sample> = chunk
                .iter()
                .map(|&i| training_sample(&images[i], config.trial_weighting(), None))
                .collect();
            let (logits, loss) = samples_loss(net, &samples, config.precision, Layout::Inference);
            total += loss.double_value(&[]) * chunk.len() as f64;
            if first_map.is_none() {
                let map = logits.get(0).sigmoid().to_kind(Kind::Float).flatten(0, -1);
                first_map =
                    Some(Vec::<f32>::try_from(map).expect("a float tensor converts to Vec<f32>"));
            }
        }
        Validation {
            loss: total / indices.len().max(1) as f64,
            first_map,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use tch::nn::{Module, OptimizerConfig};
    use tch::Device;

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
    fn epoch_rngs_differ_by_epoch_and_repeat_by_seed() {
        use rand::Rng;
        let a: u64 = epoch_rng(1, 3).random();
        assert_eq!(a, epoch_rng(1, 3).random::<u64>());
        assert_ne!(a, epoch_rng(1, 4).random::<u64>());
        assert_ne!(a, epoch_rng(2, 3).random::<u64>());
    }

    /// A trial item: a bright square under the grasp, executed at `angle_deg`.
    fn trial_item(success: bool, angle_deg: f32) -> LabelledImage {
        use crate::data::dataset::Supervision;
        let grasp = crate::grasp::PixelGrasp {
            u: 70,
            v: 52,
            angle_deg,
        };
        LabelledImage {
            object: "Box".into(),
            k: 1,
            image: image::RgbImage::from_fn(128, 128, |u, v| {
                let inside = (60..80).contains(&u) && (45..60).contains(&v);
                image::Rgb(if inside { [220, 40, 40] } else { [90, 90, 90] })
            }),
            height: None,
            grasp,
            supervision: Supervision::Trial { success },
        }
    }

    #[test]
    fn an_epoch_budget_keeps_every_label_and_fills_with_trials_in_shuffled_order() {
        let mut images: Vec<LabelledImage> = (0..10).map(|_| trial_item(true, 0.0)).collect();
        for i in [2, 7] {
            images[i].supervision = Supervision::Label;
        }
        let mut order = vec![9, 2, 4, 0, 7, 1, 3, 8, 6, 5];
        within_budget(&mut order, &images, 5);
        assert_eq!(order, [9, 2, 4, 0, 7]);
        let mut order = vec![1, 3, 8, 6, 5, 9, 2, 4, 0, 7];
        within_budget(&mut order, &images, 5);
        assert_eq!(
            order,
            [1, 3, 8, 2, 7],
            "labels last in the order still stay"
        );
        let mut all = vec![3, 1, 2];
        within_budget(&mut all, &images, 0);
        assert_eq!(all, [3, 1, 2], "0 keeps everything");
    }

    #[test]
    fn a_trial_puts_gradient_only_at_its_executed_pixel_and_rotation() {
        use crate::data::dataset::TrialWeighting;
        let weighting = TrialWeighting {
            weight: 0.01,
            sigma_px: 0.0,
        };
        for (success, angle) in [(true, 45.0), (false, 112.5)] {
            let sample = training_sample(&trial_item(success, angle), weighting, None);
            // The sample is the image turned to the executed rotation's bin.
            assert_eq!(sample.bin, crate::grasp::angle_bin(angle));
            let (pu, pv) = sample.center_pixel(128).expect("the centre stays inside");
            let logits = Tensor::zeros([1, 1, 128, 128], (Kind::Float, tch::Device::Cpu))
                .set_requires_grad(true);
            let (_, target) = batch(std::slice::from_ref(&sample), 128);
            let weights = batch_weights(std::slice::from_ref(&sample), 128).unwrap();
            weighted_loss(&logits, &target, Some(&weights)).backward();
            let grad = Vec::<f32>::try_from(logits.grad().flatten(0, -1)).unwrap();
            let nonzero: Vec<usize> = (0..grad.len()).filter(|&i| grad[i] != 0.0).collect();
            assert_eq!(nonzero, [(pv * 128 + pu) as usize], "success {success}");
            // BCE at logit 0: the gradient is the weight times (σ(0) − target).
            let expected = 0.01 * (0.5 - if success { 1.0 } else { 0.0 });
            assert!(
                (grad[nonzero[0]] - expected).abs() < 1e-7,
                "{}",
                grad[nonzero[0]]
            );
        }
    }

    #[test]
    fn labels_alone_keep_the_plain_mean_loss() {
        tch::manual_seed(3);
        let logits = Tensor::randn([2, 1, 16, 16], (Kind::Float, tch::Device::Cpu));
        let target = Tensor::rand([2, 1, 16, 16], (Kind::Float, tch::Device::Cpu));
        let uniform = Tensor::full([2, 1, 16, 16], 1.0 / 256.0, (Kind::Float, tch::Device::Cpu));
        let plain = weighted_loss(&logits, &target, None).double_value(&[]);
        let weighted = weighted_loss(&logits, &target, Some(&uniform)).double_value(&[]);
        assert!(
            (plain - weighted).abs() < 1e-6,
            "{plain} against {weighted}"
        );
    }

    #[test]
    fn a_crop_scores_as_the_whole_image_away_from_its_edge() {
        tch::manual_seed(5);
        let vs = nn::VarStore::new(tch::Device::Cpu);
        let net = MiniUNet::new(&vs.root());
        let image = Tensor::rand([1, 3, 128, 128], (Kind::Float, tch::Device::Cpu));
        let whole = tch::no_grad(|| net.forward_with(&image, Precision::Fp32));
        let margin = crate::data::dataset::CROP_MARGIN_PX as i64;
        let worst_inside = |x0: i64, y0: i64| {
            let crop = image.narrow(2, y0, 64).narrow(3, x0, 64);
            let out = tch::no_grad(|| net.forward_with(&crop, Precision::Fp32));
            let inner = |t: &Tensor| {
                t.narrow(2, margin, 64 - 2 * margin)
                    .narrow(3, margin, 64 - 2 * margin)
            };
            let whole_part = whole.narrow(2, y0, 64).narrow(3, x0, 64);
            let inside = (inner(&out) - inner(&whole_part))
                .abs()
                .max()
                .double_value(&[]);
            let anywhere = (&out - &whole_part).abs().max().double_value(&[]);
            (inside, anywhere)
        };
        // On the pooling grid, the inside of the crop is the whole image's output...
        let (inside, anywhere) = worst_inside(32, 44);
        assert!(
            inside < 1e-5,
            "inside the margin the crop differs by {inside}"
        );
        // ...and the edge, where the crop's zero padding replaces the image, is not: the test
        // can tell.
        assert!(
            anywhere > 1e-3,
            "the edge matches too ({anywhere}): the margin is not needed"
        );
        // Off the grid (an odd offset), the pooling windows differ everywhere.
        let (inside, _) = worst_inside(33, 44);
        assert!(inside > 1e-4, "an off-grid crop matched ({inside})");
    }
}
