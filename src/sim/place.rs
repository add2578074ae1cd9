//! Placing in bin 2 (docs/grasping.md, "Placing"): a second top-down camera over bin 2, the
//! heights it sees, the lowest free spot for the held object, a release just above what lies
//! there, and a wait until the object rests.

use rapier3d::glamx::{Mat3, Vec2};
use rapier3d::math::{Pose, Rotation, Vector};

use super::guard::Guard;
use super::kinematics::{Joints, Ur5, PLACE_JOINTS};
use super::pick::{to_isometry, PickOutcome, PickReason, AFTER_ATTEMPT_SETTLE, OPEN_WAIT};
use super::{Workcell, PHYSICS_HZ, ROBOT_BASE};
use crate::grasp::gripper::GRIPPER;
use crate::grasp::tote::PLACE_TOTE;
use crate::vision::camera::Camera;
use crate::vision::render::Frame;

/// Side of a cell of the height grid over bin 2's floor (m).
const CELL: f32 = 0.01;
/// Spacing of the candidate spots for the TCP over bin 2 (m).
const SPOT_STEP: f32 = 0.02;
/// Room left around the held object's footprint: what lies this close counts as under it (m).
const FOOTPRINT_MARGIN: f32 = 0.01;
/// Least gap between the walls and the held object's footprint or the open hand (m).
const WALL_GAP: f32 = 0.015;
/// Height of the held object's lowest point above the highest surface under it at the release
/// (m): low enough that nothing bounces off, high enough that the estimate's error (a cell of
/// the grid, the object's tilt in the jaw) does not press it into the pile.
const RELEASE_CLEARANCE: f32 = 0.02;
/// Spots whose release heights lie within this of the lowest count as equally low; the first of
/// them in the fixed order wins (m). It absorbs the depth image's rounding on a flat floor.
const LEVEL_TOLERANCE: f32 = 0.005;
/// Longest wait after the release for the placed object to come to rest (s).
const PLACED_SETTLE: f32 = 2.0;

/// The highest surface the bin-2 camera sees over each cell of bin 2's floor.
///
/// Each pixel's surface point counts, and so does every point of its ray beyond that surface
/// down to the floor, at the ray's height there: whatever lies hidden behind a surface is lower
/// than the ray that passed over it, so the grid never reads a hidden spot as lower than it can
/// be.
pub(crate) struct HeightGrid {
    /// World (x, y) of the grid's corner, bin 2's inner floor corner.
    origin: [f32; 2],
    /// Cells along x and y.
    cells: [usize; 2],
    /// Heights (m), row-major in y.
    heights: Vec<f32>,
}

impl HeightGrid {
    /// The grid from a frame of the bin-2 camera.
    pub(crate) fn from_frame(camera: &Camera, frame: &Frame) -> Self {
        let tote = PLACE_TOTE;
        let origin = [
            tote.center[0] - tote.inner_half[0],
            tote.center[1] - tote.inner_half[1],
        ];
        let cells = [
            (2.0 * tote.inner_half[0] / CELL).round() as usize,
            (2.0 * tote.inner_half[1] / CELL).round() as usize,
        ];
        let mut grid = Self {
            origin,
            cells,
            heights: vec![tote.floor_top; cells[0] * cells[1]],
        };
        for v in 0..frame.height {
            for u in 0..frame.width {
                let depth = frame.depth_at(u, v);
                if depth >= camera.far {
                    continue;
                }
                let eye = camera.pixel_to_world(u, v, 0.0);
                let surface = camera.pixel_to_world(u, v, depth);
                grid.raise(surface, surface.z);
                // Beyond the surface the ray runs on, lower, until it meets the floor.
                let ray = surface - eye;
                if ray.z >= 0.0 {
                    continue;
                }
                let to_floor = (surface.z - tote.floor_top).max(0.0) / -ray.z;
                let run = ray.truncate().length() * to_floor;
                let samples = (run / (CELL / 2.0)).ceil() as usize;
                for k in 1..=samples {
                    let point = surface + ray * (to_floor * k as f32 / samples as f32);
                    grid.raise(point, point.z);
                }
            }
        }
        grid
    }

    fn cell(&self, x: f32, y: f32) -> Option<usize> {
        let i = ((x - self.origin[0]) / CELL).floor();
        let j = ((y - self.origin[1]) / CELL).floor();
        let inside =
            i >= 0.0 && j >= 0.0 && (i as usize) < self.cells[0] && (j as usize) < self.cells[1];
        inside.then(|| j as usize * self.cells[0] + i as usize)
    }

    fn raise(&mut self, at: Vector, height: f32) {
        if let Some(c) = self.cell(at.x, at.y) {
            self.heights[c] = self.heights[c].max(height);
        }
    }

    /// The highest surface over the rectangle `[low, high]` (world x, y), cells it touches.
    pub(crate) fn highest(&self, low: [f32; 2], high: [f32; 2]) -> f32 {
        let index = |value: f32, axis: usize| {
            (((value - self.origin[axis]) / CELL).floor().max(0.0) as usize)
                .min(self.cells[axis] - 1)
        };
        let (i0, i1) = (index(low[0], 0), index(high[0], 0));
        let (j0, j1) = (index(low[1], 1), index(high[1], 1));
        let mut highest = f32::NEG_INFINITY;
        for j in j0..=j1 {
            for i in i0..=i1 {
                highest = highest.max(self.heights[j * self.cells[0] + i]);
            }
        }
        highest
    }
}

/// Where and how low to release the held object.
pub(crate) struct PlacePlan {
    /// Joints over the spot, at the carrying height.
    above: Joints,
    /// Tool0 at the release.
    release: Pose,
    /// The TCP's spot (x, y) and release height, for the log.
    tcp: Vector,
}

impl Workcell {
    /// The frame of the camera over bin 2.
    pub(crate) fn capture_place_bin(&self) -> Frame {
        crate::vision::render::render(&self.place_camera, &self.drawables())
    }

    /// The lowest free spot of bin 2 for the held object, as the bin-2 camera sees it; `None`
    /// when no spot is both free of the walls and within the arm's reach.
    ///
    /// The object keeps its hold in the jaw and the hand turns with the arm's base, half a turn
    /// from home, so its footprint over bin 2 is the one it has at home turned by π about the
    /// TCP. Every spot on a [`SPOT_STEP`] grid that keeps the footprint and the open hand
    /// [`WALL_GAP`] inside the walls gets a release height: the object's lowest point
    /// [`RELEASE_CLEARANCE`] above the highest surface under the footprint (with
    /// [`FOOTPRINT_MARGIN`] around it), and the pads as far above the highest surface under the
    /// hand. The lowest release wins; among releases within [`LEVEL_TOLERANCE`] of it, the spot
    /// nearest bin 2's centre (then the lower x, then the lower y), so that placements fill the
    /// floor outwards from the middle and the pile never grows under one point.
    pub(crate) fn plan_place(&self, held: usize) -> Option<PlacePlan> {
        let grid = HeightGrid::from_frame(&self.place_camera, &self.capture_place_bin());
        let tool0 = self.tool0_pose();
        let tcp = tool0.transform_point(Vector::new(0.0, 0.0, GRIPPER.tcp_offset));
        let turn = Rotation::from_rotation_z(std::f32::consts::PI);
        let rotation = turn * tool0.rotation;
        let aabb = self.world.colliders[self.objects[held].collider].compute_aabb();
        // Half a turn about the TCP flips the footprint's offset and keeps its extents.
        let offset = -(aabb.center() - tcp).truncate();
        let half = aabb.half_extents().truncate();
        let hang = (tcp.z - aabb.mins.z).max(0.0);
        let hand_local = Vector::new(
            GRIPPER.palm_half_across.max(GRIPPER.pad_width / 2.0),
            GRIPPER
                .palm_half_along
                .max(GRIPPER.max_opening / 2.0 + GRIPPER.pad_thickness),
            0.0,
        );
        let axes = Mat3::from_quat(rotation);
        let hand = (axes.x_axis.abs() * hand_local.x + axes.y_axis.abs() * hand_local.y).truncate();

        let tote = PLACE_TOTE;
        let centre = Vec2::new(tote.center[0], tote.center[1]);
        let inner = Vec2::new(tote.inner_half[0], tote.inner_half[1]);
        let free = |middle: Vec2, half: Vec2| {
            let reach = (middle - centre).abs() + half;
            reach.x <= inner.x - WALL_GAP && reach.y <= inner.y - WALL_GAP
        };
        let steps = |axis: usize| (inner[axis] / SPOT_STEP).floor() as i32;
        let mut spots = Vec::new();
        for i in -steps(0)..=steps(0) {
            for j in -steps(1)..=steps(1) {
                let spot = centre + Vec2::new(i as f32, j as f32) * SPOT_STEP;
                let object = spot + offset;
                if !free(object, half) || !free(spot, hand) {
                    continue;
                }
                let around = half + FOOTPRINT_MARGIN;
                let under_object = grid.highest((object - around).into(), (object + around).into());
                let under_hand = grid.highest((spot - hand).into(), (spot + hand).into());
                let release =
                    (under_object + RELEASE_CLEARANCE + hang).max(under_hand + RELEASE_CLEARANCE);
                spots.push((spot, release));
            }
        }
        let lowest = spots.iter().map(|s| s.1).fold(f32::INFINITY, f32::min);
        spots.retain(|s| s.1 <= lowest + LEVEL_TOLERANCE);
        spots.sort_by(|a, b| {
            let key = |s: &(Vec2, f32)| ((s.0 - centre).length(), s.0.x, s.0.y);
            key(a)
                .partial_cmp(&key(b))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        let ur5 = Ur5::new(to_isometry(&Pose::from_translation(ROBOT_BASE)));
        let tool0_at = |spot: Vec2, z: f32| {
            Pose::from_parts(
                Vector::new(spot.x, spot.y, z + GRIPPER.tcp_offset),
                rotation,
            )
        };
        spots.into_iter().find_map(|(spot, release_z)| {
            let above = ur5
                .inverse(&to_isometry(&tool0_at(spot, tcp.z)), &PLACE_JOINTS)
                .ok()?;
            let release = tool0_at(spot, release_z.min(tcp.z));
            ur5.inverse(&to_isometry(&release), &above).ok()?;
            Some(PlacePlan {
                above,
                release,
                tcp: Vector::new(spot.x, spot.y, release_z),
            })
        })
    }

    /// Carries the held object to bin 2, lowers it over the lowest free spot, releases it, waits
    /// until it rests, and comes back: a success, wherever the object comes to rest (`placed`
    /// reports where). A collision on the way stops the arm, and the object is released where
    /// it is.
    pub(super) fn place(&mut self, held: usize, lift_at_home: f32) -> PickOutcome {
        let ur5 = Ur5::new(to_isometry(&Pose::from_translation(ROBOT_BASE)));
        let carry = Guard { objects: false };
        let carry_height = self.tool0_pose().translation.z;
        self.enter("carry to bin 2");
        let plan = self.plan_place(held);
        match &plan {
            Some(plan) => {
                tracing::debug!(tcp = ?plan.tcp, "placing");
                if self.move_joints(plan.above, carry).is_ok() {
                    self.enter("lower");
                    let _ = self.move_line(&ur5, plan.release, carry);
                }
            }
            None => {
                tracing::debug!("no free spot within reach: releasing from the place pose");
                let _ = self.move_joints(PLACE_JOINTS, carry);
            }
        }
        let at_release = self.object_centre(held);
        self.enter("release");
        self.gripper.open(&mut self.world);
        self.wait_for_fingers(OPEN_WAIT);
        self.wait_until_still(held, PLACED_SETTLE);
        // A pad can end up across a slot narrower than the pad is wide, overlapping both walls,
        // as one did in the clamp's slot between its sliding jaw and screw handle when the clamp
        // turned in the jaw on the way. No rigid pad gets there, and the solver cannot push it
        // out sideways, so the open hand would lift the object back out. The hand rises
        // through it instead, and the object drops the release clearance.
        let hung = self.touches_a_pad(held);
        if hung {
            tracing::debug!("the released object hangs on a pad: the hand rises through it");
            self.gripper.set_collisions(&mut self.world, false);
        }
        self.enter("return");
        let mut up = self.tool0_pose();
        up.translation.z = up.translation.z.max(carry_height);
        let _ = self.move_line_unchecked(&ur5, up);
        if hung {
            self.gripper.set_collisions(&mut self.world, true);
        }
        self.recover_home();
        self.enter("settle");
        self.settle(AFTER_ATTEMPT_SETTLE);
        let placed = self.locate(held);
        // Where the object was at the release tells a drop on the way (on the floor already)
        // from one that left bin 2 after the release.
        tracing::debug!(object = %self.objects[held].model.name, ?at_release, rests = ?self.object_centre(held), location = ?placed, "placed");
        PickOutcome {
            success: true,
            reason: PickReason::Success,
            detail: format!(
                "carried {} home {:.2} m above where it lay",
                self.objects[held].model.name, lift_at_home
            ),
            object: Some(self.objects[held].model.name.clone()),
            placed: Some(placed),
            released_at: Some(at_release.to_array()),
            sim_seconds: 0.0,
        }
    }

    /// Whether object `index` touches either pad.
    fn touches_a_pad(&self, index: usize) -> bool {
        let collider = self.objects[index].collider;
        self.gripper
            .pads
            .iter()
            .any(|&pad| super::in_contact(&self.world, pad, collider, 0.002))
    }

    /// Holds the arm until object `index` has been still for a settled spell, or `max_seconds`
    /// pass.
    fn wait_until_still(&mut self, index: usize, max_seconds: f32) {
        let body = self.objects[index].body;
        let mut calm = 0;
        for _ in 0..(max_seconds * PHYSICS_HZ) as u32 {
            self.hold_arm();
            self.step();
            calm = if self.is_still(body) { calm + 1 } else { 0 };
            if calm >= super::stepping::SETTLED_STEPS {
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasp::tote::FLOOR_TOP;
    use crate::vision::render::{render, Drawable, Shape};

    #[test]
    fn the_grid_reads_a_box_in_bin_2_and_what_it_hides_no_lower_than_the_rays_over_it() {
        // A 100 mm cube on bin 2's floor, 200 mm off the camera's axis along y.
        let camera = Camera::place_top_down();
        let cube = Drawable {
            shape: Shape::Cuboid {
                half_extents: Vector::splat(0.05),
            },
            pose: Pose::from_translation(Vector::new(-0.5, 0.2, FLOOR_TOP + 0.05)),
            color: [0.5; 3],
            id: 1,
        };
        let grid = HeightGrid::from_frame(&camera, &render(&camera, &[cube]));
        let top = grid.highest([-0.52, 0.18], [-0.48, 0.22]);
        assert!((top - (FLOOR_TOP + 0.1)).abs() < 0.002, "top {top}");
        let floor = grid.highest([-0.6, -0.3], [-0.55, -0.25]);
        assert!((floor - FLOOR_TOP).abs() < 0.002, "floor {floor}");
        // Behind the cube, away from the camera, the floor is hidden: it reads as high as the
        // rays that pass over it there, never as bare floor.
        let hidden = grid.highest([-0.51, 0.26], [-0.49, 0.27]);
        assert!(hidden > FLOOR_TOP + 0.05, "hidden {hidden}");
        // Beside it, towards the camera, the floor is seen.
        let seen = grid.highest([-0.51, 0.12], [-0.49, 0.13]);
        assert!((seen - FLOOR_TOP).abs() < 0.002, "seen {seen}");
    }
}
