//! The trained model at prediction time: load a checkpoint's weights and score the 8 rotated observations in one batch.

use std::path::Path;

use anyhow::bail;
use tch::{nn, Device, Kind, Tensor};

use crate::data::dataset::write_chw;
use crate::data::input::{rotated_inputs, InputKind, NetInput};
use crate::grasp::BINS;
use crate::model::maps::AffordanceMaps;
use crate::model::unet::{MiniUNet, Precision};

/// A MiniUNet with its weights, ready to predict.
pub(crate) struct AffordanceModel {
    // Owns the weights the network's layers point into.
    _weights: nn::VarStore,
    net: MiniUNet,
    precision: Precision,
    input: InputKind,
    path: std::path::PathBuf,
}

impl AffordanceModel {
    /// Loads the weights of a `.safetensors` checkpoint (as `graspmap train` writes them).
    pub(crate) fn load(path: &Path, precision: Precision) -> anyhow::Result<Self> {
        if path.is_dir() {
            bail!(
                "checkpoint {} is a directory; give the weights file, e.g. {}",
                path.display(),
                path.join("best.safetensors").display()
            );
        }
        if !path.is_file() {
            bail!(
                "checkpoint {} not found: run `graspmap train` first, or pass --checkpoint PATH",
                path.display()
            );
        }
        let decoded = super::checkpoint::read(
            path,
            "train first, or pass another --checkpoint, or check --data",
        )?;
        // The input the model was trained on comes with it; weights without a training state
        // (e.g. the reference's) are rgb.
        let input = decoded
            .meta
            .map_or(InputKind::Rgb, |meta| meta.config.input);
        let mut weights = nn::VarStore::new(Device::Cpu);
        let net = MiniUNet::with_input(&weights.root(), input);
        super::checkpoint::load_weights(&mut weights, &decoded.tensors, path)?;
        Ok(Self {
            _weights: weights,
            net,
            precision,
            input,
            path: path.to_owned(),
        })
    }

    /// The input the model takes, as its checkpoint records it.
    pub(crate) fn input(&self) -> InputKind {
        self.input
    }

    /// Scores one observation: rotates it to each of the [`BINS`] angles and runs the batch.
    /// The one scoring step of `predict` and the model policy.
    pub(crate) fn score(&self, input: &NetInput) -> anyhow::Result<AffordanceMaps> {
        self.predict(&rotated_inputs(input))
    }

    /// Affordance (sigmoid of the logits) for the [`BINS`] rotated observations, one batch.
    /// Fails, naming the checkpoint, when the observations are not the input it was trained on.
    pub(crate) fn predict(&self, rotated: &[NetInput]) -> anyhow::Result<AffordanceMaps> {
        assert_eq!(rotated.len(), BINS, "one observation per bin");
        let (w, h) = rotated[0].rgb.dimensions();
        assert_eq!(w, h, "square observations");
        let channels = rotated[0].channels();
        if rotated.iter().any(|r| r.kind() != self.input) {
            bail!(
                "{} is an {} model ({} input planes); it was given {} planes ({})",
                self.path.display(),
                self.input,
                self.input.channels(),
                channels,
                rotated[0].kind()
            );
        }
        let plane = (w * h) as usize;
        let mut input = vec![0.0f32; BINS * channels * plane];
        for (image, chw) in rotated.iter().zip(input.chunks_exact_mut(channels * plane)) {
            write_chw(image, chw);
        }
        let values = tch::no_grad(|| {
            let batch =
                Tensor::from_slice(&input).view([BINS as i64, channels as i64, h as i64, w as i64]);
            let batch = network_layout(&batch, self.precision);
            let scores = self
                .net
                .forward_with(&batch, self.precision)
                .sigmoid()
                .to_kind(Kind::Float)
                .flatten(0, -1);
            Vec::<f32>::try_from(scores).expect("a float tensor converts to Vec<f32>")
        });
        Ok(AffordanceMaps::new(w, values))
    }
}

/// The 8-rotation batch in the layout inference runs it in. oneDNN's fp32 convolutions ran
/// faster in channels_last on an AVX2-only CPU (the measurement diary, `git show
/// 2c24231:docs/history.md`); only for inference, since its backward pass is slower there.
/// bf16's forward pass converts its input itself.
pub(crate) fn network_layout(batch: &Tensor, precision: Precision) -> Tensor {
    match precision {
        Precision::Fp32 => crate::model::unet::channels_last(batch),
        Precision::Bf16 => batch.shallow_clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::checkpoint::{save_checkpoint, CheckpointMeta};
    use crate::model::config::{Plateau, TrainConfig};

    /// A freshly initialised checkpoint of `input` saved as `dir/best.safetensors`.
    fn saved(dir: &Path, input: InputKind) -> std::path::PathBuf {
        let vs = nn::VarStore::new(Device::Cpu);
        let _net = MiniUNet::with_input(&vs.root(), input);
        let meta = CheckpointMeta {
            schema: CheckpointMeta::SCHEMA.to_owned(),
            config: TrainConfig {
                input,
                ..TrainConfig::default()
            },
            epoch: 1,
            history: Vec::new(),
            best_val_loss: 1.0,
            best_epoch: 1,
            lr: 1e-3,
            plateau: Plateau::default(),
            adam_steps: 1,
            train_indices: vec![0],
            val_indices: vec![1],
            trained_on: None,
        };
        save_checkpoint(&vs, &[], &meta, dir, "best").unwrap();
        dir.join("best.safetensors")
    }

    fn inputs(kind: InputKind) -> Vec<NetInput> {
        let rgb = image::RgbImage::from_pixel(32, 32, image::Rgb([90, 120, 30]));
        let depth = crate::data::input::DepthMm::from_pixel(32, 32, image::Luma([650]));
        let input = NetInput::new(kind, rgb, Some(&depth));
        vec![input; BINS]
    }

    #[test]
    fn a_checkpoint_keeps_its_input_and_refuses_another() {
        let dir = tempfile::tempdir().unwrap();
        for kind in [InputKind::Rgb, InputKind::Rgbd] {
            let sub = dir.path().join(kind.to_string());
            std::fs::create_dir_all(&sub).unwrap();
            let path = saved(&sub, kind);
            let model = AffordanceModel::load(&path, Precision::Fp32).unwrap();
            assert_eq!(model.input(), kind, "round trip");
            let maps = model.predict(&inputs(kind)).unwrap();
            assert!(maps.choose().score.is_finite());
        }
        let rgbd = AffordanceModel::load(
            &dir.path().join("rgbd").join("best.safetensors"),
            Precision::Fp32,
        )
        .unwrap();
        let Err(error) = rgbd.predict(&inputs(InputKind::Rgb)) else {
            panic!("an rgbd model took 3 planes");
        };
        let error = error.to_string();
        for needle in [
            "rgbd/best.safetensors",
            "an rgbd model (4 input planes)",
            "3 planes",
        ] {
            assert!(error.contains(needle), "{needle:?} missing from {error}");
        }
        // And an rgb checkpoint's JSON leaves the field out, as before it existed.
        let text = std::fs::read_to_string(dir.path().join("rgb").join("best.json")).unwrap();
        assert!(!text.contains("\"input\""), "{text}");
        let text = std::fs::read_to_string(dir.path().join("rgbd").join("best.json")).unwrap();
        assert!(text.contains("\"input\": \"rgbd\""), "{text}");
    }
}
