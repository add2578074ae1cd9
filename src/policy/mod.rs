//! Policies: who chooses a grasp from the camera's view, and the checks between a network's
//! maps and the executed grasp.
//!
//! A policy sees what a camera sees (the frame: RGB, depth and, for the oracle alone, the
//! object mask) and answers with a pixel grasp. It may use the pure core and `model`, never the
//! simulator: commands wire the two together. docs/evaluation.md describes each check.

pub(crate) mod affordance;
pub(crate) mod baselines;
pub(crate) mod collision;
pub(crate) mod model;
pub mod oracle;

use image::RgbImage;

use crate::grasp::PixelGrasp;
use crate::vision::camera::Camera;
use crate::vision::render::Frame;
use affordance::{Choice, Suppression};
use oracle::OracleError;

/// What a policy sees before one attempt.
pub(crate) struct Observation<'a> {
    /// The camera the frame was taken with.
    pub(crate) camera: &'a Camera,
    /// RGB, depth and mask of the top-down view.
    pub(crate) frame: &'a Frame,
    /// The frame's RGB as an image.
    pub(crate) rgb: &'a RgbImage,
    /// Mask ids of the objects still in bin 1 (ground truth: only the oracle reads it).
    pub(crate) in_bin: &'a [u16],
    /// Seed of this attempt's own random stream, independent of the drop.
    pub(crate) attempt_seed: u64,
}

/// A policy's answer for one observation.
pub(crate) struct Decision {
    /// The grasp to execute, or why there is none.
    pub(crate) grasp: Result<PixelGrasp, OracleError>,
    /// The network's action behind the grasp (model policy).
    pub(crate) choice: Option<Choice>,
    /// The maps the choice came from, drawn as the reference's grid (model policy).
    pub(crate) vis: Option<RgbImage>,
    /// Wall seconds spent on rotations, network, checks and argmax (model policy).
    pub(crate) network_seconds: f64,
}

impl Decision {
    /// A decision that only names a grasp (or why there is none).
    pub(crate) fn grasp_only(grasp: Result<PixelGrasp, OracleError>) -> Self {
        Self {
            grasp,
            choice: None,
            vis: None,
            network_seconds: 0.0,
        }
    }
}

/// Who chooses grasps.
pub(crate) trait Policy {
    /// Chooses the grasp for one observation; `memory` holds the scene's past actions.
    fn decide(&self, view: &Observation, memory: &Suppression) -> Decision;
}
