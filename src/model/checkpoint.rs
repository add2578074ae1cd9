//! Checkpoint files: weights (and optimiser state) in safetensors, with the training state
//! embedded in the file's metadata, so that one atomic rename replaces both together.
//!
//! The JSON sidecar beside each checkpoint (`best.json`, `last.json`) is a copy for people and
//! tools to read; graspmap itself reads the state from the safetensors header, so a reader can
//! never pair new weights with an old sidecar. Files are decoded from bytes in memory, which is
//! also what the parsers' fuzz tests feed.

use std::borrow::Cow;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use safetensors::tensor::{Dtype, SafeTensors, View};
use serde::{Deserialize, Serialize};
use tch::{nn, Kind, Tensor};

use super::config::{Plateau, TrainConfig};
use crate::data::atomic::write_atomic;

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
    /// What the run was trained on, when it is more than the labels alone (trials, a starting
    /// checkpoint); absent otherwise, so label-only checkpoints keep their bytes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trained_on: Option<TrainingData>,
}

/// The data behind a run: the labels, the trial stores, and the weights it started from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainingData {
    /// Labelled images (0 when trained on trials alone).
    pub labels: usize,
    /// Each trial store, in the order its samples follow the labels.
    pub trials: Vec<TrialSource>,
    /// The checkpoint whose weights the run started from, and its SHA-256; none for fresh
    /// weights.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<StartWeights>,
}

/// One trial store a run was trained on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrialSource {
    /// The store's folder as given.
    pub dir: PathBuf,
    /// Its complete scenes.
    pub scenes: usize,
    /// Its trials.
    pub trials: usize,
    /// How many of them succeeded.
    pub successes: usize,
}

/// The weights a run started from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartWeights {
    /// The checkpoint file.
    pub path: PathBuf,
    /// Its SHA-256, hex.
    pub sha256: String,
}

/// The SHA-256 of a file, hex: how trial stores and checkpoints name the weights they came
/// from.
pub(crate) fn file_sha256(path: &Path) -> anyhow::Result<String> {
    use sha2::Digest;
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let digest = sha2::Sha256::digest(&bytes);
    Ok(digest.iter().map(|b| format!("{b:02x}")).collect())
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
    write(named, meta, dir, name)
}

/// Reads a checkpoint's tensors and training state, with errors that name the file and the
/// fix. The state comes from inside the weights file; a checkpoint from before it was embedded
/// falls back to its JSON sidecar.
pub fn read_checkpoint(
    dir: &Path,
    name: &str,
) -> anyhow::Result<(BTreeMap<String, Tensor>, CheckpointMeta)> {
    let (weights, sidecar) = checkpoint_paths(dir, name);
    let decoded = read(
        &weights,
        "train anew with --force, or restore the file from a copy",
    )?;
    let sidecar_meta = || -> anyhow::Result<CheckpointMeta> {
        let text = std::fs::read_to_string(&sidecar)
            .with_context(|| format!("reading {}", sidecar.display()))?;
        parse_meta(&text, &sidecar)
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

/// The metadata key that holds the training state's JSON.
pub const META_KEY: &str = "graspmap.checkpoint";

/// Paths of a checkpoint's weights and its JSON copy.
pub(crate) fn checkpoint_paths(dir: &Path, name: &str) -> (PathBuf, PathBuf) {
    (
        dir.join(format!("{name}.safetensors")),
        dir.join(format!("{name}.json")),
    )
}

/// A tensor as safetensors sees it: dtype, shape and little-endian bytes.
struct Raw {
    dtype: Dtype,
    shape: Vec<usize>,
    bytes: Vec<u8>,
}

impl Raw {
    fn of(tensor: &Tensor) -> anyhow::Result<Self> {
        let tensor = tensor.contiguous();
        let dtype = match tensor.kind() {
            Kind::Float => Dtype::F32,
            Kind::Double => Dtype::F64,
            Kind::Int64 => Dtype::I64,
            Kind::BFloat16 => Dtype::BF16,
            other => bail!("cannot save a {other:?} tensor"),
        };
        let numel = tensor.numel();
        let mut bytes = vec![0u8; numel * tensor.kind().elt_size_in_bytes()];
        tensor
            .f_copy_data_u8(&mut bytes, numel)
            .context("copying a tensor out of libtorch")?;
        let shape = tensor.size().iter().map(|&d| d as usize).collect();
        Ok(Self {
            dtype,
            shape,
            bytes,
        })
    }
}

impl View for &Raw {
    fn dtype(&self) -> Dtype {
        self.dtype
    }
    fn shape(&self) -> &[usize] {
        &self.shape
    }
    fn data(&self) -> Cow<'_, [u8]> {
        Cow::Borrowed(&self.bytes)
    }
    fn data_len(&self) -> usize {
        self.bytes.len()
    }
}

/// The safetensors bytes of `tensors` with `meta` in the header.
pub(crate) fn encode(
    tensors: &[(String, Tensor)],
    meta: &CheckpointMeta,
) -> anyhow::Result<Vec<u8>> {
    let mut meta = meta.clone();
    for record in &mut meta.history {
        record.seconds = 0.0;
    }
    let raw: Vec<(String, Raw)> = tensors
        .iter()
        .map(|(name, t)| Ok((name.clone(), Raw::of(t)?)))
        .collect::<anyhow::Result<_>>()?;
    let info = HashMap::from([(META_KEY.to_owned(), serde_json::to_string(&meta)?)]);
    safetensors::tensor::serialize(raw.iter().map(|(n, r)| (n.as_str(), r)), &Some(info))
        .context("encoding the checkpoint")
}

/// A checkpoint read from bytes: its tensors, and its training state when it has one (the
/// files that `graspmap train` writes always do; weights from elsewhere may not).
pub(crate) struct Decoded {
    pub(crate) tensors: BTreeMap<String, Tensor>,
    pub(crate) meta: Option<CheckpointMeta>,
}

/// Decodes safetensors bytes; `source` names the file in errors, which end with `fix`.
pub(crate) fn decode(bytes: &[u8], source: &Path, fix: &str) -> anyhow::Result<Decoded> {
    let corrupt = || {
        format!(
            "{} is not a readable safetensors checkpoint ({fix})",
            source.display()
        )
    };
    let (_, header) = SafeTensors::read_metadata(bytes)
        .map_err(|e| anyhow::anyhow!("{e:?}"))
        .with_context(corrupt)?;
    let file = SafeTensors::deserialize(bytes)
        .map_err(|e| anyhow::anyhow!("{e:?}"))
        .with_context(corrupt)?;
    let mut tensors = BTreeMap::new();
    for (name, view) in file.tensors() {
        let kind = match view.dtype() {
            Dtype::F32 => Kind::Float,
            Dtype::F64 => Kind::Double,
            Dtype::I64 => Kind::Int64,
            Dtype::BF16 => Kind::BFloat16,
            other => bail!(
                "{}: tensor '{name}' has unsupported dtype {other:?}",
                source.display()
            ),
        };
        let shape: Vec<i64> = view.shape().iter().map(|&d| d as i64).collect();
        let tensor = Tensor::f_from_data_size(view.data(), &shape, kind)
            .with_context(|| format!("{}: tensor '{name}' is malformed", source.display()))?;
        tensors.insert(name, tensor);
    }
    let meta = match header.metadata().as_ref().and_then(|m| m.get(META_KEY)) {
        Some(text) => Some(parse_meta(text, source)?),
        None => None,
    };
    Ok(Decoded { tensors, meta })
}

/// Parses and checks the training state's JSON.
pub(crate) fn parse_meta(text: &str, source: &Path) -> anyhow::Result<CheckpointMeta> {
    let meta: CheckpointMeta = serde_json::from_str(text).with_context(|| {
        format!(
            "{}: the training state is corrupt (delete it and retrain)",
            source.display()
        )
    })?;
    if meta.schema != CheckpointMeta::SCHEMA {
        bail!(
            "{} has schema '{}', expected '{}'",
            source.display(),
            meta.schema,
            CheckpointMeta::SCHEMA
        );
    }
    Ok(meta)
}

/// Reads and decodes a checkpoint file; errors end with `fix`, the way forward for the command
/// that reads it.
pub(crate) fn read(path: &Path, fix: &str) -> anyhow::Result<Decoded> {
    let bytes =
        std::fs::read(path).with_context(|| format!("reading {} ({fix})", path.display()))?;
    decode(&bytes, path, fix)
}

/// Writes the weights (plus any extra tensors, sorted by name) with the training state inside,
/// then the state's JSON copy; each through the atomic writer, the weights first.
pub(crate) fn write(
    named: Vec<(String, Tensor)>,
    meta: &CheckpointMeta,
    dir: &Path,
    name: &str,
) -> anyhow::Result<()> {
    let (weights, sidecar) = checkpoint_paths(dir, name);
    let mut named = named;
    named.sort_by(|a, b| a.0.cmp(&b.0));
    write_atomic(&weights, &encode(&named, meta)?)?;
    let mut text = serde_json::to_string_pretty(meta)?;
    text.push('\n');
    write_atomic(&sidecar, text.as_bytes())
}

#[cfg(test)]
mod fuzz {
    use std::path::Path;

    use proptest::prelude::*;

    use crate::data::fuzzing::{check, config, edits, mutate, text};

    fn checkpoint_meta() -> crate::model::checkpoint::CheckpointMeta {
        use crate::model::checkpoint::{CheckpointMeta, EpochRecord};
        use crate::model::config::{Plateau, TrainConfig};
        CheckpointMeta {
            schema: CheckpointMeta::SCHEMA.to_owned(),
            config: TrainConfig::default(),
            epoch: 2,
            history: vec![EpochRecord {
                epoch: 1,
                train_loss: 0.5,
                val_loss: 0.25,
                lr: 1e-3,
                seconds: 1.5,
            }],
            best_val_loss: 0.25,
            best_epoch: 1,
            lr: 1e-3,
            plateau: Plateau::default(),
            adam_steps: 16,
            train_indices: vec![0, 2, 3],
            val_indices: vec![1],
            trained_on: None,
        }
    }

    fn small_safetensors() -> &'static [u8] {
        static BYTES: std::sync::LazyLock<Vec<u8>> = std::sync::LazyLock::new(|| {
            let tensors = vec![
                (
                    "inc.0.bias".to_owned(),
                    tch::Tensor::from_slice(&[0.5f32, -1.0, 2.0]),
                ),
                (
                    "outc.weight".to_owned(),
                    tch::Tensor::from_slice(&[1.0f32, 2.0, 3.0, 4.0]).view([1, 4, 1, 1]),
                ),
            ];
            crate::model::checkpoint::encode(&tensors, &checkpoint_meta()).unwrap()
        });
        &BYTES
    }

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn fuzz_json_checkpoint_state(edits in edits()) {
            let seed = serde_json::to_string_pretty(&checkpoint_meta()).unwrap();
            let input = text(&mutate(seed.as_bytes(), &edits));
            check(|| crate::model::checkpoint::parse_meta(&input, Path::new("last.json")))?;
        }

        #[test]
        fn fuzz_safetensors(edits in edits()) {
            let input = mutate(small_safetensors(), &edits);
            check(|| crate::model::checkpoint::decode(&input, Path::new("last.safetensors"), "retrain"))?;
        }
    }
}
