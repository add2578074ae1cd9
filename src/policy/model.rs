//! The model policy: the network's 8 rotated maps, the collision check, failure suppression,
//! the depth test and centring, in that order, then the argmax.

use std::time::Instant;

use super::affordance::{visualisation, Suppression};
use super::collision::{allowed_actions, CollisionCheck, GraspSite, GripperVolume, HeightMap};
use super::oracle::{DepthCheck, OracleConfig};
use super::{Decision, Observation, Policy};
use crate::data::input::{rotated_inputs, InputKind, NetInput};
use crate::grasp::gripper::GRIPPER;
use crate::grasp::tote::PICK_TOTE;
use crate::model::inference::AffordanceModel;

/// How the model policy checks the network's candidates (docs/evaluation.md).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub(crate) struct ModelPolicyConfig {
    /// Which grasps are zeroed before the argmax. Default `Full`.
    pub(crate) check: CollisionCheck,
    /// How many of the best actions the depth test may look at; 0 executes the argmax as it
    /// is. Default 200.
    pub(crate) verify_top: usize,
    /// Move the chosen grasp to the middle of its surface (needs `check` `Full`). Default off.
    pub(crate) centring: bool,
}

impl Default for ModelPolicyConfig {
    fn default() -> Self {
        Self {
            check: CollisionCheck::Full,
            verify_top: 200,
            centring: false,
        }
    }
}

/// Why a model policy configuration cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum ConfigError {
    /// Centring reads the depth image through the full collision check.
    #[error("--centring needs --collision-check full (it is {check})")]
    CentringNeedsFullCheck {
        /// The check asked for.
        check: CollisionCheck,
    },
}

impl ModelPolicyConfig {
    /// Checks that the options work together.
    pub(crate) fn validate(&self) -> Result<(), ConfigError> {
        if self.centring && self.check != CollisionCheck::Full {
            return Err(ConfigError::CentringNeedsFullCheck { check: self.check });
        }
        Ok(())
    }
}

/// The network and the checks between its maps and the executed grasp.
pub(crate) struct ModelPolicy {
    model: AffordanceModel,
    config: ModelPolicyConfig,
}

impl ModelPolicy {
    /// A policy over a loaded model; fails when the options do not work together.
    pub(crate) fn new(
        model: AffordanceModel,
        config: ModelPolicyConfig,
    ) -> Result<Self, ConfigError> {
        config.validate()?;
        Ok(Self { model, config })
    }
}

impl Policy for ModelPolicy {
    fn decide(&self, view: &Observation, memory: &Suppression) -> Decision {
        let ModelPolicyConfig {
            check,
            verify_top,
            centring,
        } = self.config;
        let (camera, frame) = (view.camera, view.frame);
        let start = Instant::now();
        // The same conversion as training: the frame's depth goes through the 16-bit millimetre
        // image that `label` stores, so the height plane gets the same rounding.
        let kind = self.model.input();
        let depth = (kind == InputKind::Rgbd).then(|| frame.to_depth_image_mm());
        let input = NetInput::new(kind, view.rgb.clone(), depth.as_ref());
        let rotated_input = rotated_inputs(&input);
        let mut maps = self
            .model
            .predict(&rotated_input)
            .expect("the policy builds the input its model was trained on");
        let rotated: Vec<_> = rotated_input.into_iter().map(|r| r.rgb).collect();
        let gripper = GripperVolume::from(&GRIPPER);
        if check != CollisionCheck::Off {
            maps.restrict(&allowed_actions(camera, frame, &PICK_TOTE, &gripper, check));
        }
        memory.apply(&mut maps);
        let mut choice = maps.choose();
        if verify_top > 0 {
            // The network ranks, the planner's depth test vetoes: in clutter its peak often
            // sits on a box's edge or corner, where the pads squeeze the box out, or across a
            // side wider than the jaw leaves room for. When none of the best passes, the
            // argmax is still tried (BENCHMARKS.md, "Depth test").
            let test = DepthCheck::new(camera, frame, OracleConfig::default());
            if let Some(passed) = maps
                .ranked(verify_top)
                .into_iter()
                .find(|c| test.assess(c.grasp).is_ok())
            {
                choice = passed;
            }
        }
        if centring {
            let heights = HeightMap::new(camera, frame);
            // A grasp that fits only at a corner is still executed: refusing it and taking
            // the next best did worse (BENCHMARKS.md, "Centring").
            let site = GraspSite {
                camera,
                frame,
                heights: &heights,
                tote: &PICK_TOTE,
                gripper: &gripper,
            };
            let refined = site.refine(choice.grasp, |g| maps.score_at(g));
            if let Some(grasp) = refined.filter(|&g| g != choice.grasp) {
                choice = maps.choice_of(grasp);
            }
        }
        let network_seconds = start.elapsed().as_secs_f64();
        Decision {
            grasp: Ok(choice.grasp),
            choice: Some(choice),
            vis: Some(visualisation(&rotated, &maps, &choice)),
            network_seconds,
        }
    }
}
