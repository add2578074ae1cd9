//! The baselines beside the model: a random pixel of bin 1's floor, and the oracle planner on
//! ground truth.

use std::collections::BTreeMap;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rapier3d::math::Vector;

use super::affordance::Suppression;
use super::oracle::{self, OracleConfig, OracleError};
use super::{Decision, Observation, Policy};
use crate::grasp::tote::PICK_TOTE;
use crate::grasp::{normalize_angle, PixelGrasp};
use crate::vision::camera::Camera;
use crate::vision::render::Frame;

/// A uniformly random pixel of bin 1's floor and a uniformly random angle.
pub(crate) struct RandomPolicy;

impl Policy for RandomPolicy {
    fn decide(&self, view: &Observation, _memory: &Suppression) -> Decision {
        Decision::grasp_only(Ok(random_grasp(view.camera, view.attempt_seed)))
    }
}

/// A uniformly random point of bin 1's floor, seen through the camera, and a uniform angle.
pub(crate) fn random_grasp(camera: &Camera, seed: u64) -> PixelGrasp {
    // A separate stream from the drop, so the same seed does not correlate the two.
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(1);
    let tote = PICK_TOTE;
    let size = camera.width as f32;
    loop {
        let point = Vector::new(
            tote.center[0] + rng.random_range(-tote.inner_half[0]..=tote.inner_half[0]),
            tote.center[1] + rng.random_range(-tote.inner_half[1]..=tote.inner_half[1]),
            tote.floor_top,
        );
        let angle_deg = normalize_angle(rng.random_range(0.0..180.0));
        if let Some([u, v, _]) = camera.project(point) {
            if (0.0..size).contains(&u) && (0.0..size).contains(&v) {
                return PixelGrasp {
                    u: u as u32,
                    v: v as u32,
                    angle_deg,
                };
            }
        }
    }
}

/// The planner, on the topmost object of bin 1 it can grasp, from the mask and depth.
pub(crate) struct OraclePolicy;

impl Policy for OraclePolicy {
    fn decide(&self, view: &Observation, _memory: &Suppression) -> Decision {
        let mut grasp = Err(OracleError::NothingInBin);
        for id in topmost_first(view.frame, view.in_bin) {
            grasp = oracle::plan(view.camera, view.frame, id, &OracleConfig::default())
                .map(|plan| plan.grasp);
            if grasp.is_ok() {
                break;
            }
        }
        Decision::grasp_only(grasp)
    }
}

/// Visible object ids, nearest to the camera first (ties by id).
fn topmost_first(frame: &Frame, ids: &[u16]) -> Vec<u16> {
    let mut nearest: BTreeMap<u16, f32> = BTreeMap::new();
    for v in 0..frame.height {
        for u in 0..frame.width {
            let id = frame.id_at(u, v);
            if ids.contains(&id) {
                let depth = frame.depth_at(u, v);
                let entry = nearest.entry(id).or_insert(f32::INFINITY);
                *entry = entry.min(depth);
            }
        }
    }
    let mut order: Vec<(u16, f32)> = nearest.into_iter().collect();
    order.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
    order.into_iter().map(|(id, _)| id).collect()
}
