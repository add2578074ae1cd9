//! The network: MiniUNet, its training loop and checkpoints, and prediction over 8 rotations.
//!
//! This layer owns tch and uses the pure core (`grasp`, `data`); it never sees the simulator.
//! docs/learning.md describes the network and its training.

pub(crate) mod autotune;
pub mod checkpoint;
pub mod config;
pub(crate) mod inference;
pub(crate) mod maps;
pub(crate) mod picture;
pub mod train;
pub mod unet;

/// Sets how many threads libtorch's operators use.
pub(crate) fn use_threads(threads: u16) {
    tch::set_num_threads(i32::from(threads));
}
