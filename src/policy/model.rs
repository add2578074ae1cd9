//! The model policy, in the order it runs: the network's 8 rotated maps; failure suppression
//! lowers them around past failures; the collision check zeroes grasps that would collide; the
//! argmax; verification replaces it with the best of the top candidates that passes the depth
//! image test (or, when none does, of the best candidates before the collision check); centring
//! moves the chosen grasp to the middle of its surface (docs/evaluation.md).

use std::time::Instant;

use super::collision::{allowed_actions, CollisionCheck, GraspSite, GripperVolume};
use super::heights::HeightMap;
use super::suppression::Suppression;
use super::verify::{CheckConfig, Verifier};
use super::{Decision, Observation, Policy};
use crate::data::input::{InputKind, NetInput};
use crate::grasp::draw::JawPx;
use crate::grasp::gripper::GRIPPER;
use crate::grasp::tote::PICK_TOTE;
use crate::grasp::PixelGrasp;
use crate::model::inference::AffordanceModel;
use crate::model::maps::{AffordanceMaps, Choice};
use crate::model::picture::affordance_picture;

/// How the model policy checks the network's candidates (docs/evaluation.md).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub(crate) struct ModelPolicyConfig {
    /// Which grasps are zeroed before the argmax. Default `Full`.
    pub(crate) check: CollisionCheck,
    /// How many of the best actions verification may look at; 0 executes the argmax as it
    /// is. Default 200.
    pub(crate) verify_top: usize,
    /// Verification replaces the argmax only with a candidate scoring at least this fraction
    /// of it; 0 (the default) lets any candidate in the N best replace it.
    pub(crate) verify_floor: f32,
    /// When none of the `verify_top` best allowed actions passes, how many of the best before
    /// the collision check verification looks at next; 0 skips that second pass. Default 200.
    pub(crate) verify_rejected: usize,
    /// How many of a pad's three strips the squeezed part must reach for a candidate to pass
    /// verification. Default 3, the whole pad width: the network, unlike the planner, does not
    /// know where an object's centre is, and in clutter its peak often sits near a box's edge,
    /// where a grasp that catches two strips lets the box pivot out
    /// (BENCHMARKS.md#verification).
    pub(crate) verify_strips: usize,
    /// Verification first looks for candidates whose squeezed outline shifts by at most this
    /// much across a pad (m), and only then up to the planner's 10 mm; 0 = one pass at 10 mm.
    /// Default 5 mm, about 13° off square (BENCHMARKS.md#verification).
    pub(crate) verify_square: f32,
    /// Room verification keeps between the squeezed part and each open pad (m). Default 3 mm,
    /// where the planner keeps 6: with 6, a 77 mm foam brick or a 73 mm gelatin box lying flat
    /// passes only where a pad catches a corner, and those grasps close on nothing
    /// (docs/evaluation.md, "Verification").
    pub(crate) verify_margin: f32,
    /// Move the chosen grasp to the middle of its surface (needs `check` `Full`). Default off.
    pub(crate) centring: bool,
}

impl Default for ModelPolicyConfig {
    fn default() -> Self {
        Self {
            check: CollisionCheck::Full,
            verify_top: 200,
            verify_floor: 0.0,
            verify_rejected: 200,
            verify_strips: 3,
            verify_square: 0.005,
            verify_margin: 0.003,
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
    /// The second pass belongs to verification, so it needs verification on.
    #[error("--verify-rejected {count} widens verification, which --verify-top 0 turns off; give --verify-top N with N > 0, or drop --verify-rejected")]
    RejectedWithoutDepthTest {
        /// The count asked for.
        count: usize,
    },
    /// The floor only narrows the candidates of verification, so it needs verification on.
    #[error("--verify-floor {floor} narrows verification, which --verify-top 0 turns off; give --verify-top N with N > 0, or drop --verify-floor")]
    FloorWithoutDepthTest {
        /// The floor asked for.
        floor: f32,
    },
}

impl ModelPolicyConfig {
    /// Checks that the options work together.
    pub(crate) fn validate(&self) -> Result<(), ConfigError> {
        if self.centring && self.check != CollisionCheck::Full {
            return Err(ConfigError::CentringNeedsFullCheck { check: self.check });
        }
        if self.verify_rejected > 0 && self.verify_top == 0 {
            return Err(ConfigError::RejectedWithoutDepthTest {
                count: self.verify_rejected,
            });
        }
        if self.verify_floor > 0.0 && self.verify_top == 0 {
            return Err(ConfigError::FloorWithoutDepthTest {
                floor: self.verify_floor,
            });
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

impl ModelPolicy {
    /// Exploration: an action drawn from the network's maps (after suppression, before any
    /// check) with probability ∝ score^(1/`temperature`), executed as drawn, so that the model
    /// also learns where its own unchecked choices fail (docs/learning.md, "Trials").
    pub(crate) fn explore(
        &self,
        view: &Observation,
        memory: &Suppression,
        temperature: f32,
        rng: &mut impl rand::Rng,
    ) -> Decision {
        let start = Instant::now();
        let mut maps = self.score(view);
        memory.apply(&mut maps);
        let choice = maps.sample(temperature, rng);
        Decision {
            grasp: Ok(choice.grasp),
            choice: Some(choice),
            vis: picture(view, &maps, &choice),
            network_seconds: start.elapsed().as_secs_f64(),
            verified: None,
        }
    }

    /// The network's 8 rotated maps of the view. The frame's depth goes through the 16-bit
    /// millimetre image that `label` stores, as in training, so the height plane gets the same
    /// rounding.
    fn score(&self, view: &Observation) -> AffordanceMaps {
        let kind = self.model.input();
        let depth = (kind == InputKind::Rgbd).then(|| view.frame.to_depth_image_mm());
        let input = NetInput::new(kind, view.rgb.clone(), depth.as_ref());
        self.model
            .score(&input)
            .expect("the policy builds the input its model was trained on")
    }

    /// The collision check: zeroes the grasps that would collide. Returns the maps as they
    /// were before it when verification's second pass may look at them.
    fn collision_check(
        &self,
        view: &Observation,
        heights: &HeightMap,
        gripper: &GripperVolume,
        maps: &mut AffordanceMaps,
    ) -> Option<AffordanceMaps> {
        let ModelPolicyConfig {
            check,
            verify_top,
            verify_rejected,
            ..
        } = self.config;
        let second_pass = verify_top > 0 && verify_rejected > 0 && check != CollisionCheck::Off;
        let unchecked = second_pass.then(|| maps.clone());
        if check != CollisionCheck::Off {
            let allowed =
                allowed_actions(view.camera, view.frame, heights, &PICK_TOTE, gripper, check);
            maps.restrict(&allowed);
        }
        unchecked
    }

    /// Verification: the best of the `verify_top` allowed candidates that passes the depth
    /// image test, else of the `verify_rejected` best before the collision check (`unchecked`);
    /// `None` when nothing passes.
    ///
    /// The network ranks, verification vetoes: in clutter its peak often sits on a box's edge
    /// or corner, where the pads squeeze the box out, or across a side wider than the jaw
    /// leaves room for. When none of the allowed best passes, it looks at the best that the
    /// collision check zeroed: in clutter, a grasp that passes there works more often than the
    /// allowed argmax that failed. When nothing passes (or nothing above the floor), the argmax
    /// is still tried (BENCHMARKS.md#verification).
    fn verify(
        &self,
        view: &Observation,
        heights: &HeightMap,
        maps: &AffordanceMaps,
        unchecked: Option<&AffordanceMaps>,
    ) -> Option<Choice> {
        let ModelPolicyConfig {
            verify_top,
            verify_floor,
            verify_rejected,
            verify_strips,
            verify_square,
            verify_margin,
            ..
        } = self.config;
        // Squeezed faces near square come first: a box squeezed 22.5° off its faces slips out
        // of a cardboard grip (friction 0.3 holds up to about 17°), and the planner's 10 mm
        // across a pad allows 24°.
        let planner_slant = CheckConfig::default().max_slant;
        let mut slants = vec![planner_slant];
        if verify_square > 0.0 && verify_square < planner_slant {
            slants.insert(0, verify_square);
        }
        // Each pass ranks the same maps: rank them once, the second pass's only if asked.
        let ranked = maps.ranked(verify_top);
        let ranked_unchecked = std::cell::OnceCell::new();
        slants.into_iter().find_map(|max_slant| {
            let config = CheckConfig {
                strips: verify_strips,
                max_slant,
                squeeze_margin: verify_margin,
                ..CheckConfig::default()
            };
            let verifier = Verifier::new(view.camera, view.frame, heights, config);
            let passes = |g: PixelGrasp| verifier.assess(g).is_ok();
            first_verified(ranked.clone(), verify_floor, passes).or_else(|| {
                let unchecked = unchecked?;
                let second = ranked_unchecked.get_or_init(|| unchecked.ranked(verify_rejected));
                first_verified(second.clone(), verify_floor, passes)
            })
        })
    }

    /// Centring: the chosen grasp moved to the middle of its surface. A grasp that fits only at
    /// a corner is still executed: refusing it and taking the next best did worse
    /// (BENCHMARKS.md#centring).
    fn centre(
        view: &Observation,
        heights: &HeightMap,
        gripper: &GripperVolume,
        maps: &AffordanceMaps,
        choice: Choice,
    ) -> Choice {
        let site = GraspSite {
            camera: view.camera,
            frame: view.frame,
            heights,
            tote: &PICK_TOTE,
            gripper,
        };
        let refined = site.refine(choice.grasp, |g| maps.score_at(g));
        match refined.filter(|&g| g != choice.grasp) {
            Some(grasp) => maps.choice_of(grasp),
            None => choice,
        }
    }
}

impl Policy for ModelPolicy {
    /// Score → suppression → collision check → argmax → verification → centring.
    fn decide(&self, view: &Observation, memory: &Suppression) -> Decision {
        let start = Instant::now();
        let mut maps = self.score(view);
        // One back-projection of the frame serves the collision check, verification and
        // centring.
        let heights = HeightMap::new(view.camera, view.frame);
        let gripper = GripperVolume::from(&GRIPPER);
        // Suppression only lowers and clips to [0, 1], so it gives the same maps before the
        // collision check's zeroing as after; applied first, the second pass's copy shares it.
        memory.apply(&mut maps);
        let unchecked = self.collision_check(view, &heights, &gripper, &mut maps);
        let mut choice = maps.choose();
        let mut verified = None;
        if self.config.verify_top > 0 {
            let passed = self.verify(view, &heights, &maps, unchecked.as_ref());
            verified = Some(passed.is_some());
            choice = passed.unwrap_or(choice);
        }
        if self.config.centring {
            choice = Self::centre(view, &heights, &gripper, &maps, choice);
        }
        let network_seconds = start.elapsed().as_secs_f64();
        Decision {
            grasp: Ok(choice.grasp),
            choice: Some(choice),
            vis: picture(view, &maps, &choice),
            network_seconds,
            verified,
        }
    }
}

/// The decision's picture: the maps as the policy ranked them, over the camera's image, with
/// the gripper to that camera's scale (none for a camera that does not see the tote floor).
fn picture(view: &Observation, maps: &AffordanceMaps, choice: &Choice) -> Option<image::RgbImage> {
    let jaw = JawPx::at_floor(view.camera)?;
    Some(affordance_picture(view.rgb, maps, choice, jaw))
}

/// The first of `ranked` (best first) that `passes`, among those scoring at least `floor` times
/// the best. Alone in the bin, an object the test finds too wide for the jaw (a 75 mm can,
/// with the test's 6 mm to spare on each side) leaves only its edges to pass, where the network
/// scores a few per cent of its peak and the pads close on air; the floor keeps the peak instead
/// (BENCHMARKS.md#verification).
fn first_verified(
    ranked: Vec<Choice>,
    floor: f32,
    passes: impl Fn(PixelGrasp) -> bool,
) -> Option<Choice> {
    let least = ranked.first()?.score * floor;
    ranked
        .into_iter()
        .take_while(|c| c.score >= least)
        .find(|c| passes(c.grasp))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn candidate(u: u32, score: f32) -> Choice {
        let grasp = PixelGrasp {
            u,
            v: 64,
            angle_deg: 0.0,
        };
        Choice {
            bin: 0,
            rotated: [u, 64],
            grasp,
            score,
        }
    }

    #[test]
    fn the_floor_keeps_candidates_the_network_barely_scores_from_replacing_the_peak() {
        let ranked = vec![candidate(10, 0.4), candidate(20, 0.3), candidate(30, 0.02)];
        let only_far_edge = |g: PixelGrasp| g.u == 30;
        // Without a floor any passing candidate replaces the peak, however low its score.
        let chosen = first_verified(ranked.clone(), 0.0, only_far_edge).unwrap();
        assert_eq!(chosen.grasp.u, 30);
        // With one, a candidate under a quarter of the peak does not: the argmax stands.
        assert!(first_verified(ranked.clone(), 0.25, only_far_edge).is_none());
        // The floor narrows the list but keeps its order: the best passing one above it wins.
        let both = |g: PixelGrasp| g.u != 10;
        assert_eq!(
            first_verified(ranked.clone(), 0.25, both).unwrap().grasp.u,
            20
        );
        assert_eq!(first_verified(ranked, 1.0, both), None);
        assert_eq!(first_verified(Vec::new(), 0.25, |_| true), None);
    }

    #[test]
    fn a_floor_or_a_second_pass_without_the_depth_test_is_refused() {
        let validated = |verify_top, verify_floor, verify_rejected| {
            let config = ModelPolicyConfig {
                verify_top,
                verify_floor,
                verify_rejected,
                ..ModelPolicyConfig::default()
            };
            config.validate()
        };
        assert_eq!(
            validated(0, 0.25, 0),
            Err(ConfigError::FloorWithoutDepthTest { floor: 0.25 })
        );
        assert_eq!(
            validated(0, 0.0, 50),
            Err(ConfigError::RejectedWithoutDepthTest { count: 50 })
        );
        assert_eq!(validated(200, 0.25, 200), Ok(()));
        assert_eq!(validated(0, 0.0, 0), Ok(()));
    }
}
