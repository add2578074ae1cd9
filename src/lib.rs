//! graspmap: learn top-down grasps for a simulated UR5 from a few dozen labels (spatial action maps).
//!
//! The folders are the layers, and imports run one way, downwards:
//!
//! | layer | folders | may use |
//! |---|---|---|
//! | pure core | [`vision`], [`grasp`], [`data`], [`metrics`] | each other (no rapier world, no tch) |
//! | model files | [`assets`] | the core |
//! | simulator | [`sim`] | the core, `assets` (rapier, no tch) |
//! | network | [`model`] | the core (tch, no rapier) |
//! | policies | [`policy`] | the core, `model` (not `sim`) |
//! | orchestration | `commands`, `cli` | everything |
//!
//! rapier's math types (glam `Vector`, `Pose`, …) are the crate's math types and appear in
//! every layer. The conventions and numbers the code follows are in the repository's docs/.

pub mod assets;
pub mod cli;
pub(crate) mod commands;
pub mod data;
#[cfg(test)]
mod fuzz;
pub mod grasp;
pub mod metrics;
pub mod model;
pub(crate) mod named;
pub mod policy;
pub mod sim;
pub mod vision;

pub use commands::interrupt::Interrupted;
