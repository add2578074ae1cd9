//! Data: the label store in the reference tool's layout, training samples and augmentation.
//!
//! Pure core, but for the store's file I/O: it may use `grasp` and `vision`, never the
//! simulator or tch. Samples leave as plain `f32` arrays that the model layer turns into
//! tensors. The on-disk formats are in docs/data.md, the sample construction in
//! docs/learning.md.

pub(crate) mod atomic;
pub mod augment;
pub(crate) mod clicks;
pub mod clutter;
pub mod dataset;
pub mod depth_files;
#[cfg(test)]
pub(crate) mod fuzzing;
pub mod input;
pub mod labels;
pub mod lock;
pub(crate) mod observation;
pub(crate) mod output;
pub(crate) mod progress;
pub(crate) mod relabel;
pub mod scene_file;
pub(crate) mod seeds;
pub mod shard;
pub mod trials;
