//! Oracle grasp planner: chooses a pixel grasp from the camera's ground-truth mask and depth, so it works for any shape.
//!
//! For each visible pixel of the object and each of 16 angles it checks, on the 2.5-D height map
//! seen by the camera, that the object fits between the open pads and that both pads have free
//! space down to the TCP height; among the feasible grasps it prefers clearance near the centre.

use rapier3d::math::Vector;

use crate::camera::Camera;
use crate::grasp::{world_grasp, PixelGrasp};
use crate::render::Frame;

/// Geometry of the jaw the planner plans for (defaults: Robotiq 2F-85 size, SPEC §2).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct OracleConfig {
    /// Distance between the open pads' inner faces (m).
    pub opening: f32,
    /// Pad width across the closing line (m).
    pub pad_width: f32,
    /// Pad thickness along the closing line (m).
    pub pad_thickness: f32,
    /// Safety margin around the pads and inside the opening (m).
    pub margin: f32,
    /// Number of angles tried over 180°.
    pub angles: u32,
    /// Sampling step along and across the closing line (m).
    pub step: f32,
}

impl Default for OracleConfig {
    fn default() -> Self {
        Self {
            opening: 0.085,
            pad_width: 0.022,
            pad_thickness: 0.010,
            margin: 0.004,
            angles: 16,
            step: 0.002,
        }
    }
}

/// A planned grasp with its quality terms.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct OraclePlan {
    /// The grasp to click.
    pub grasp: PixelGrasp,
    /// Smallest height of free space under the pads' footprints (m), capped at 5 cm.
    pub clearance: f32,
    /// Distance from the grasp centre to the object's visible centroid (m).
    pub off_center: f32,
    /// Object width along the closing line at pad height (m).
    pub width: f32,
}

/// Why no grasp was found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OracleError {
    /// The object is not in the image.
    #[error("object id {id} is not visible in the image")]
    NotVisible { id: u16 },
    /// No candidate passed the width and clearance checks.
    #[error("ungraspable in this pose: none of {candidates} candidate grasps fits the open jaw with free space for both pads")]
    Ungraspable { candidates: usize },
}

/// Plans a grasp on the object whose mask id is `id`.
pub fn plan(
    camera: &Camera,
    frame: &Frame,
    id: u16,
    config: &OracleConfig,
) -> Result<OraclePlan, OracleError> {
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
    let height_map = HeightMap { camera, frame };

    let mut best: Option<(f32, OraclePlan)> = None;
    let mut candidates = 0;
    for &(u, v) in &pixels {
        for k in 0..config.angles {
            candidates += 1;
            let angle_deg = k as f32 * 180.0 / config.angles as f32;
            let grasp = PixelGrasp { u, v, angle_deg };
            let Some(plan) = evaluate(&height_map, grasp, centroid, config) else {
                continue;
            };
            // Clearance matters up to a few centimetres; beyond that, being central wins.
            let score = plan.clearance.min(0.03) - plan.off_center;
            if best.as_ref().is_none_or(|(s, _)| score > *s) {
                best = Some((score, plan));
            }
        }
    }
    best.map(|(_, plan)| plan)
        .ok_or(OracleError::Ungraspable { candidates })
}

/// Surface heights seen by the camera, looked up along the camera ray through a world point.
struct HeightMap<'a> {
    camera: &'a Camera,
    frame: &'a Frame,
}

impl HeightMap<'_> {
    /// Height of the visible surface on the ray through `p`; +∞ outside the image (unknown = blocked).
    fn height(&self, p: Vector) -> f32 {
        let Some([u, v, _]) = self.camera.project(p) else {
            return f32::INFINITY;
        };
        if u < 0.0 || v < 0.0 || u >= self.frame.width as f32 || v >= self.frame.height as f32 {
            return f32::INFINITY;
        }
        let (u, v) = (u as u32, v as u32);
        self.camera.pixel_to_world(u, v, self.frame.depth_at(u, v)).z
    }
}

fn evaluate(
    map: &HeightMap,
    grasp: PixelGrasp,
    centroid: Vector,
    config: &OracleConfig,
) -> Option<OraclePlan> {
    let target = world_grasp(map.camera, map.frame, grasp);
    let tcp = target.tcp;
    let along = target.closing;
    let across = Vector::new(-along.y, along.x, 0.0);
    // Probe at mid-pad height: that is where the pads meet the object.
    let probe_z = tcp.z + 0.015;
    let half_open = config.opening / 2.0;
    let step = config.step;
    let point = |s: f32, w: f32| {
        let p = tcp + along * s + across * w;
        Vector::new(p.x, p.y, probe_z)
    };
    // Object extent along the closing line at pad height, within the opening.
    let limit = half_open - config.margin;
    let mut lo = 0.0f32;
    let mut hi = 0.0f32;
    let mut s = -half_open;
    while s <= half_open {
        let occupied = [-config.pad_width / 2.0, 0.0, config.pad_width / 2.0]
            .iter()
            .any(|&w| map.height(point(s, w)) > tcp.z + 0.003);
        if occupied {
            if s.abs() > limit {
                return None;
            }
            lo = lo.min(s);
            hi = hi.max(s);
        }
        s += step;
    }
    // Both pads need free space down to the TCP height.
    let mut clearance = 0.05f32;
    for side in [-1.0f32, 1.0] {
        let mut s = half_open;
        while s <= half_open + config.pad_thickness + config.margin {
            let mut w = -config.pad_width / 2.0 - config.margin;
            while w <= config.pad_width / 2.0 + config.margin {
                let free = tcp.z - map.height(point(side * s, w));
                if free < 0.0 {
                    return None;
                }
                clearance = clearance.min(free);
                w += step;
            }
            s += step;
        }
    }
    let off_center = Vector::new(tcp.x - centroid.x, tcp.y - centroid.y, 0.0).length()
        + (lo + hi).abs() / 2.0;
    Some(OraclePlan {
        grasp,
        clearance,
        off_center,
        width: hi - lo,
    })
}
