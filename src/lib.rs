//! graspmap: learn top-down grasps for a simulated UR5 from a few dozen labels (spatial action maps).
//!
//! Layers, one way only: the pure core (`camera`, `render`, `grasp`, `kinematics`, `oracle`,
//! `augment`, `dataset` but for `load_dataset`, `affordance`, `workspace`, `metrics`) does no I/O; `unet`, `train` and
//! `inference` are the model (tch, no rapier); `urdf` and `objects` read model files; `sim` is
//! the rapier workcell (no tch); `commands` and `cli` orchestrate.

pub mod affordance;
pub mod augment;
pub mod camera;
pub mod cli;
pub mod commands;
pub mod dataset;
pub mod grasp;
pub mod inference;
pub mod kinematics;
pub mod labels;
pub mod metrics;
pub mod objects;
pub mod oracle;
pub mod output;
pub mod raycast;
pub mod render;
pub mod sim;
pub mod train;
pub mod unet;
pub mod urdf;
pub mod workspace;
