//! The baselines beside the model: a random pixel of bin 1's floor, and the oracle planner on
//! ground truth.

use std::collections::{BTreeMap, BTreeSet};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rapier3d::math::Vector;

use super::oracle;
use super::suppression::Suppression;
use super::verify::CheckConfig;
use super::{Decision, NoGrasp, Observation, Policy};
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

/// The planner, on the topmost object of bin 1 it can grasp, from the mask and depth. With
/// suppression on, objects under fewer remembered grasps come first.
pub(crate) struct OraclePolicy;

impl Policy for OraclePolicy {
    fn decide(&self, view: &Observation, memory: &Suppression) -> Decision {
        let mut grasp = Err(NoGrasp::NothingInBin);
        for id in least_tried_first(view.frame, topmost_first(view.frame, view.in_bin), memory) {
            grasp = oracle::plan(view.camera, view.frame, id, &CheckConfig::default())
                .map(|plan| plan.grasp)
                .map_err(NoGrasp::from);
            if grasp.is_ok() {
                break;
            }
        }
        Decision::grasp_only(grasp)
    }
}

/// How far from a remembered grasp's centre (pixels, each way) an object counts as tried: a
/// grasp that closes on air often nudges the object it missed off its centre pixel. 2 px (about
/// 2 cm) moved more than 0 or 4 (the measurement diary, `git show 2c24231:docs/history.md`; the
/// oracle with this memory today: BENCHMARKS.md#oracle-yardstick-in-clutter).
const TRIED_REACH_PX: u32 = 2;

/// `ids` reordered by how many remembered grasps land on or next to each in `frame`, fewest
/// first, keeping their order otherwise. The planner is deterministic: without this it plans
/// the same failing grasp on the same object to the end of an episode.
fn least_tried_first(frame: &Frame, mut ids: Vec<u16>, memory: &Suppression) -> Vec<u16> {
    let mut tried: BTreeMap<u16, usize> = BTreeMap::new();
    for past in memory.past() {
        let near = |c: u32, size: u32| {
            c.saturating_sub(TRIED_REACH_PX)..=(c + TRIED_REACH_PX).min(size - 1)
        };
        let touched: BTreeSet<u16> = near(past.v, frame.height)
            .flat_map(|v| near(past.u, frame.width).map(move |u| frame.id_at(u, v)))
            .collect();
        for id in touched {
            *tried.entry(id).or_default() += 1;
        }
    }
    ids.sort_by_key(|id| tried.get(id).copied().unwrap_or(0));
    ids
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::policy::suppression::SuppressionConfig;

    /// A frame whose mask holds three objects in columns 10–20, 60–70 and 100–110.
    fn three_objects() -> Frame {
        let mask = (0..128u32)
            .flat_map(|_| 0..128u32)
            .map(|u| match u {
                10..=20 => 1,
                60..=70 => 2,
                100..=110 => 3,
                _ => 0,
            })
            .collect();
        Frame {
            width: 128,
            height: 128,
            rgb: vec![0; 3 * 128 * 128],
            depth: vec![0.6; 128 * 128],
            mask,
        }
    }

    fn failed_at(memory: &mut Suppression, u: u32) {
        let grasp = PixelGrasp {
            u,
            v: 64,
            angle_deg: 0.0,
        };
        memory.record(grasp, false);
    }

    #[test]
    fn the_oracle_tries_the_objects_under_fewer_failed_grasps_first() {
        let frame = three_objects();
        let order = |memory: &Suppression| least_tried_first(&frame, vec![1, 2, 3], memory);
        let mut memory = Suppression::new(SuppressionConfig {
            remember: 8,
            ..SuppressionConfig::default()
        });
        assert_eq!(order(&memory), [1, 2, 3], "nothing tried: the given order");
        failed_at(&mut memory, 15);
        assert_eq!(order(&memory), [2, 3, 1]);
        // Two pixels past an object's edge still count against it; three do not.
        failed_at(&mut memory, 72);
        failed_at(&mut memory, 97);
        assert_eq!(order(&memory), [3, 1, 2]);
        failed_at(&mut memory, 63);
        assert_eq!(order(&memory), [3, 1, 2]);
        failed_at(&mut memory, 105);
        failed_at(&mut memory, 105);
        assert_eq!(order(&memory), [1, 2, 3]);
        // With suppression off nothing is remembered, so the order never changes.
        let mut off = Suppression::new(SuppressionConfig::default());
        failed_at(&mut off, 15);
        assert_eq!(order(&off), [1, 2, 3]);
    }
}
