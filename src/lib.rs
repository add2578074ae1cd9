//! graspmap: learn top-down grasps for a simulated UR5 from a few dozen labels (spatial action maps).
//!
//! The folders are the layers, and imports run one way, downwards. A module may use the
//! modules of its own layer (without a cycle between files) and those of the layers it names;
//! `tests/suite/layers.rs` reads every `crate::` path in src/ and checks it against this table:
//!
//! | layer | modules | may use |
//! |---|---|---|
//! | core | vision, grasp, data, metrics, named, interrupt | |
//! | assets | assets | core |
//! | sim | sim | core, assets |
//! | model | model | core |
//! | policy | policy | core, model |
//! | present | present | core, assets, sim, model, policy |
//! | commands | commands | core, assets, sim, model, policy, present |
//! | cli | cli | core, assets, sim, model, policy, present, commands |
//!
//! - core: the pure parts (geometry, camera, labels and their parsers, statistics); no rapier
//!   world, no tch.
//! - assets: the robot and object models (URDF and meshes).
//! - sim: the rapier workcell (no tch). model: the network (tch, no rapier).
//! - policy: who chooses a grasp from the camera's view, and the checks on it (never the
//!   simulator: commands wire the two together).
//! - present: what people look at: the HTML report, the labelling page and its server, videos,
//!   and the JSON reports.
//! - commands: one module per subcommand; cli: the flags, resolved into the commands' configs.
//!
//! rapier's math types (glam `Vector`, `Pose`, …) are the crate's math types and appear in
//! every layer. The conventions and numbers the code follows are in the repository's docs/.

pub mod assets;
pub mod cli;
pub(crate) mod commands;
pub mod data;
pub mod grasp;
pub(crate) mod interrupt;
pub mod metrics;
pub mod model;
pub(crate) mod named;
pub mod policy;
pub(crate) mod present;
pub mod sim;
pub mod vision;

pub use interrupt::Interrupted;
