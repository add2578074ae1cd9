//! Arranging objects where a scene file lists them (docs/scenes.md): placed at rest, lifted
//! out of the floor, checked for overlaps, then settled.

use rapier3d::math::Pose;
use rapier3d::parry::shape::Shape;
use rapier3d::prelude::*;

use super::Workcell;
use crate::assets::objects::ObjectModel;
use crate::grasp::tote::PICK_TOTE;

/// Longest wait for an arranged scene to come to rest (s).
const ARRANGE_SETTLE_SECONDS: f32 = 4.0;
/// How far into the floor an object may reach and stay where it is listed (m): a resting
/// object's contact depth, which lifting would turn into a visible shift of a saved scene.
const FLOOR_TOLERANCE: f32 = 0.001;

/// Two listed objects that overlap.
#[derive(Debug, Clone, PartialEq)]
pub struct Overlap {
    /// The first object's index in the list.
    pub first: usize,
    /// The second's.
    pub second: usize,
    /// How deep they overlap (m).
    pub depth: f32,
}

impl Workcell {
    /// Places `objects` at their poses, at rest, lifting any that reaches more than a millimetre
    /// into bin 1's floor until it rests on it (a hand-written file's rounding, or a model
    /// framed otherwise than the file's author had it). The scene is not
    /// settled: [`Workcell::deepest_overlap`] can judge the layout as listed first.
    pub fn place_at_rest(&mut self, objects: &[(ObjectModel, Pose)]) -> anyhow::Result<()> {
        for (model, pose) in objects {
            let index = self.add_object(model, *pose)?;
            let lowest = self.object_bounds(index).mins.z;
            if lowest < PICK_TOTE.floor_top - FLOOR_TOLERANCE {
                let body = &mut self.world.bodies[self.objects[index].body];
                let mut lifted = *body.position();
                lifted.translation.z += PICK_TOTE.floor_top - lowest;
                body.set_position(lifted, true);
            }
        }
        Ok(())
    }

    /// Lets placed objects come to rest with the parked arm out of the way.
    pub fn settle_arrangement(&mut self) {
        self.set_robot_collisions(false);
        self.enter("arrange");
        self.settle(ARRANGE_SETTLE_SECONDS);
        self.set_robot_collisions(true);
        self.enter("idle");
    }

    /// The deepest overlap between two objects at their poses now, part by part (parry's exact
    /// query on each pair of convex parts); `None` when no two touch.
    pub fn deepest_overlap(&self) -> Option<Overlap> {
        let mut deepest: Option<Overlap> = None;
        for first in 0..self.objects.len() {
            for second in first + 1..self.objects.len() {
                let (a, b) = (self.object_bounds(first), self.object_bounds(second));
                if !a.intersects(&b) {
                    continue;
                }
                let depth = self.overlap_depth(first, second);
                if depth > 0.0 && deepest.as_ref().is_none_or(|d| depth > d.depth) {
                    deepest = Some(Overlap {
                        first,
                        second,
                        depth,
                    });
                }
            }
        }
        deepest
    }

    /// The world pose of an object's collider and its shape.
    fn object_shape(&self, index: usize) -> (Pose, &dyn Shape) {
        let object = &self.objects[index];
        let body = &self.world.bodies[object.body];
        let collider = &self.world.colliders[object.collider];
        let local = collider
            .position_wrt_parent()
            .copied()
            .unwrap_or(Pose::IDENTITY);
        (*body.position() * local, collider.shape())
    }

    fn object_bounds(&self, index: usize) -> rapier3d::parry::bounding_volume::Aabb {
        let (pose, shape) = self.object_shape(index);
        shape.compute_aabb(&pose)
    }

    fn overlap_depth(&self, first: usize, second: usize) -> f32 {
        let parts = |index: usize| -> Vec<(Pose, SharedShape)> {
            let (pose, shape) = self.object_shape(index);
            match shape.as_compound() {
                Some(compound) => compound
                    .shapes()
                    .iter()
                    .map(|(part_pose, part)| (pose * *part_pose, part.clone()))
                    .collect(),
                None => Vec::new(),
            }
        };
        let mut deepest = 0.0f32;
        for (pose_a, part_a) in parts(first) {
            for (pose_b, part_b) in parts(second) {
                let depth = rapier3d::parry::query::contact(
                    &pose_a,
                    part_a.as_ref(),
                    &pose_b,
                    part_b.as_ref(),
                    0.0,
                )
                .ok()
                .flatten()
                .map_or(0.0, |c| (-c.dist).max(0.0));
                deepest = deepest.max(depth);
            }
        }
        deepest
    }
}
