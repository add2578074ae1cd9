//! The integration tests, built into one binary so that libtorch and rapier are linked once.
//!
//! Each module covers one area end to end: the CLI's outputs and errors, depth input and clutter
//! labels, evaluation, the mesh importer, labelling, libtorch itself, physics grasps, and
//! training.

mod cli;
mod common;
mod depth;
mod eval;
mod importer;
mod label;
mod libtorch;
mod physics;
mod train;
