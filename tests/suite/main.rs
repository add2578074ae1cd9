//! The integration tests, built into one binary so that libtorch and rapier are linked once.
//!
//! Each module covers one area end to end: the CLI's outputs and errors, depth input and clutter
//! labels, evaluation, the mesh importer, labelling, libtorch itself, physics grasps, `--precision auto`'s measurement, scene
//! files and VPG's test cases, training, the run report and videos, and the web pages (over HTTP and in a browser). `layers` reads
//! src/ itself: its imports against the layer table in src/lib.rs.

mod bad_input;
mod browser;
mod cli;
mod collect;
mod common;
mod depth;
mod docs;
mod eval;
mod importer;
mod label;
mod layers;
mod libtorch;
mod physics;
mod place;
mod precision;
mod report;
mod scenes;
mod slurm;
mod train;
mod video;
mod web;
