//! Policies: who chooses a grasp from the camera's view, and the checks between a network's
//! maps and the executed grasp.
//!
//! A policy sees what a camera sees (the frame: RGB, depth and, for the oracle alone, the
//! object mask) and answers with a pixel grasp. It may use the pure core and `model`, never the
//! simulator: commands wire the two together. docs/evaluation.md describes each check.

pub(crate) mod baselines;
pub(crate) mod collision;
pub mod heights;
pub(crate) mod model;
pub mod oracle;
pub mod push;
pub(crate) mod suppression;
#[cfg(test)]
pub(crate) mod synthetic;
pub mod verify;

use image::RgbImage;

use crate::grasp::PixelGrasp;
use crate::model::maps::Choice;
use crate::named::named_enum;
use crate::vision::camera::Camera;
use crate::vision::render::Frame;
use oracle::OracleError;
use suppression::Suppression;

named_enum! {
    /// Who chooses the grasps.
    #[derive(serde::Deserialize)]
    pub enum PolicyKind {
        /// The trained affordance model.
        Model = "model", "the trained affordance model (argmax over 8 rotations)",
        /// A random point of bin 1's floor and a random angle.
        Random = "random", "a uniformly random point of bin 1's floor and a random angle",
        /// The planner, from ground-truth masks and depth.
        Oracle = "oracle", "the workcell's planner, from ground-truth masks and depth",
    }
}

/// Why a policy has no grasp to offer (only the oracle can fail: it plans on ground truth).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum NoGrasp {
    /// None of the objects in the bin is visible, so there is nothing to plan on.
    #[error("no object is visible in bin 1")]
    NothingInBin,
    /// The planner found no grasp on any visible object (the last one's reasons).
    #[error(transparent)]
    Planner(#[from] OracleError),
}

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
    pub(crate) grasp: Result<PixelGrasp, NoGrasp>,
    /// The network's action behind the grasp (model policy).
    pub(crate) choice: Option<Choice>,
    /// The maps the choice came from, drawn as the reference's grid (model policy).
    pub(crate) vis: Option<RgbImage>,
    /// Wall seconds spent on rotations, network, checks and argmax (model policy).
    pub(crate) network_seconds: f64,
    /// Model policy with verification: whether the executed grasp passed it (false: nothing
    /// did, and the argmax was executed anyway).
    pub(crate) verified: Option<bool>,
}

impl Decision {
    /// A decision that only names a grasp (or why there is none).
    pub(crate) fn grasp_only(grasp: Result<PixelGrasp, NoGrasp>) -> Self {
        Self {
            grasp,
            choice: None,
            vis: None,
            network_seconds: 0.0,
            verified: None,
        }
    }
}

/// Who chooses grasps.
pub(crate) trait Policy {
    /// Chooses the grasp for one observation; `memory` holds the scene's past actions.
    fn decide(&self, view: &Observation, memory: &Suppression) -> Decision;
}
