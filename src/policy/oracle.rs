//! Oracle grasp planner: chooses a pixel grasp from the camera's ground-truth mask and depth, so it works for any shape.
//!
//! For each visible pixel of the object and each of 16 angles it checks, on the 2.5-D height map
//! seen by the camera, that the object fits between the open pads and that both pads have free
//! space down to the TCP height; among the feasible grasps it prefers clearance near the centre.

use rapier3d::math::Vector;

use super::heights::HeightMap;
use super::verify::{
    check_grasp, Assessment, CheckConfig, Cloud, Rejection, ASYMMETRY_WEIGHT, CLEARANCE_THAT_COUNTS,
};
use crate::grasp::PixelGrasp;
use crate::named::Named;
use crate::vision::camera::Camera;
use crate::vision::render::Frame;

/// Why no grasp was found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OracleError {
    /// The object is not in the image.
    #[error("object id {id} is not visible in the image")]
    NotVisible { id: u16 },
    /// No candidate passed the width and clearance checks.
    #[error(
        "ungraspable in this pose: none of {candidates} candidate grasps works ({})",
        tally(.rejected)
    )]
    Ungraspable {
        /// Candidates tried.
        candidates: usize,
        /// How many were rejected for each reason, in [`Rejection`] order; zero counts left out.
        rejected: Vec<(Rejection, usize)>,
    },
}

fn tally(rejected: &[(Rejection, usize)]) -> String {
    rejected
        .iter()
        .map(|(r, n)| format!("{n} {}", r.help()))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Plans a grasp on the object whose mask id is `id`.
pub fn plan(
    camera: &Camera,
    frame: &Frame,
    id: u16,
    config: &CheckConfig,
) -> Result<Assessment, OracleError> {
    let mut pixels = Vec::new();
    for v in 0..frame.height {
        for u in 0..frame.width {
            if frame.id_at(u, v) == id {
                pixels.push((u, v));
            }
        }
    }
    if pixels.is_empty() {
        return Err(OracleError::NotVisible { id });
    }
    let world_of = |(u, v): (u32, u32)| camera.pixel_to_world(u, v, frame.depth_at(u, v));
    let centroid = pixels.iter().map(|&p| world_of(p)).sum::<Vector>() / pixels.len() as f32;
    let cloud = Cloud::new(&HeightMap::new(camera, frame));

    let mut best: Option<(f32, Assessment)> = None;
    let mut candidates = 0;
    let mut rejected = [0usize; Rejection::COUNT];
    for &(u, v) in &pixels {
        for k in 0..config.angles {
            candidates += 1;
            let angle_deg = k as f32 * 180.0 / config.angles as f32;
            let grasp = PixelGrasp { u, v, angle_deg };
            let plan = match check_grasp(&cloud, camera, frame, grasp, centroid, config) {
                Ok(plan) => plan,
                Err(reject) => {
                    rejected[reject as usize] += 1;
                    continue;
                }
            };
            // Clearance matters up to a couple of centimetres; beyond that a centred
            // squeeze near the centre of mass wins.
            let score = plan.clearance.min(CLEARANCE_THAT_COUNTS)
                - ASYMMETRY_WEIGHT * plan.asymmetry
                - plan.off_center
                - plan.slant;
            if best.as_ref().is_none_or(|(s, _)| score > *s) {
                best = Some((score, plan));
            }
        }
    }
    best.map(|(_, plan)| plan)
        .ok_or_else(|| OracleError::Ungraspable {
            candidates,
            rejected: <Rejection as Named>::ALL
                .iter()
                .map(|&r| (r, rejected[r as usize]))
                .filter(|&(_, n)| n > 0)
                .collect(),
        })
}
