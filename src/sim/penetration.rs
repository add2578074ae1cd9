//! How deep a body is inside one of the scenery's fixed boxes: parry's exact query, part by part,
//! bounded by the depth along the box's own axes; and the hook that drops the narrow phase's
//! contacts with a box (of the scenery or of the hand) that claim more depth than that bound
//! allows.

use rapier3d::math::{Pose, Vector};
use rapier3d::parry::shape::Shape;
use rapier3d::prelude::*;

/// How deep collider `b` overlaps the fixed box `a` (m), at their poses now; 0 when apart, or
/// when none of the narrow phase's contact points reads deeper than `screen` (m; −∞ takes any
/// point).
pub(crate) fn penetration(
    world: &PhysicsWorld,
    a: ColliderHandle,
    b: ColliderHandle,
    screen: f32,
) -> f32 {
    // The narrow phase's points come from before the step's solve and, with a compound against
    // a thin box, can be tens of millimetres off (an 86 mm reading for a pear 11 mm into the
    // floor), so they only screen, and the depth is measured afresh.
    let near = world.contact_pair(a, b).is_some_and(|pair| {
        pair.manifolds()
            .iter()
            .flat_map(|m| m.points.iter())
            .any(|p| -p.dist > screen)
    });
    if !near {
        return 0.0;
    }
    let (a, b) = (&world.colliders[a], &world.colliders[b]);
    let depth = |pose: &Pose, part: &dyn Shape| {
        let exact = rapier3d::parry::query::contact(a.position(), a.shape(), pose, part, 0.0)
            .ok()
            .flatten()
            .map_or(0.0, |contact| (-contact.dist).max(0.0));
        // The exact query's penetration step misfires now and then on a flat face lying on a
        // box: the scissors read 26 mm deep for one step while at rest, every vertex on the
        // floor. Pushing a part out along one of the box's axes always separates them, so the
        // least such push bounds the true depth from above and caps the misfire.
        match box_axes_depth(a, pose, part) {
            Some(bound) => exact.min(bound),
            None => exact,
        }
    };
    match b.shape().as_compound() {
        Some(compound) => compound
            .shapes()
            .iter()
            .map(|(part_pose, part)| depth(&(*b.position() * *part_pose), part.as_ref()))
            .fold(0.0, f32::max),
        None => depth(b.position(), b.shape()),
    }
}

/// Solver contacts with a box no deeper than this (m) are never second-guessed, so the bound
/// below is only computed for the rare deep ones.
const MISFIRE_SCREEN: f32 = 0.002;
/// How far past the box-axes bound a contact's depth may read before it counts as a misfire (m).
/// The bound is never less than the true depth; the margin absorbs the clipped points of a
/// manifold whose normal is a little off the box's face.
const MISFIRE_MARGIN: f32 = 0.002;

/// Drops, for one step, a manifold between a box (of the scenery, or of the hand: palm, finger
/// links and pads) and a dynamic body's part whose solver contacts read deeper than any push
/// along the box's axes needs to separate them. Parry's penetration step misfires now and then
/// on a flat face against a box: it gave a convex part of the scissors, lying at rest in bin 2, a
/// floor contact with a slanted normal at 33.7 mm depth, and the solver tipped them 9 mm into
/// the floor in one step (BENCHMARKS.md#physics-soak). Between a pad and a held pear it read
/// 18-21 mm with the normal turned by 65 degrees, and the impulse spun the pear out of the jaw on
/// the way to bin 2 (docs/grasping.md, "Placing"). The part's other contacts, and the next
/// step's fresh ones, carry it as before.
pub(super) struct DropMisfiredContacts;

impl PhysicsHooks for DropMisfiredContacts {
    fn modify_solver_contacts(&self, context: &mut ContactModificationContext) {
        let ModifiableContacts::Rigid(contacts) = &mut context.contacts else {
            return;
        };
        let deepest = contacts
            .solver_contacts
            .iter()
            .map(|c| -c.dist)
            .fold(0.0, f32::max);
        if deepest <= MISFIRE_SCREEN {
            return;
        }
        let (c1, c2) = (
            &context.colliders[context.collider1],
            &context.colliders[context.collider2],
        );
        // Only a dynamic body is pushed by the solver; the kinematic arm's contacts are read by
        // the guards from the manifold points, which this leaves alone. A pad is dynamic and a
        // box: against a held object either side may be the box.
        let dynamic = |c: &Collider| {
            c.parent()
                .is_some_and(|p| context.bodies[p].body_type() == RigidBodyType::Dynamic)
        };
        let (m1, m2) = (contacts.manifold.subshape1, contacts.manifold.subshape2);
        let misfired = if is_box(c1) && dynamic(c2) {
            exceeds_box_axes_depth(c1, c2, m2, deepest)
        } else if is_box(c2) && dynamic(c1) {
            exceeds_box_axes_depth(c2, c1, m1, deepest)
        } else {
            false
        };
        if misfired {
            tracing::debug!(
                depth_mm = deepest * 1e3,
                normal = ?contacts.normal,
                "dropped a misfired contact with a box"
            );
            contacts.solver_contacts.clear();
        }
    }
}

/// A box of the scenery or of the hand; an object is a compound, never one.
fn is_box(collider: &Collider) -> bool {
    collider.shape().as_cuboid().is_some()
}

/// True when `depth` (m), read by the narrow phase between the box `boxed` and part `subshape`
/// of `other` (the whole shape when it is not a compound), is deeper than the box-axes bound
/// allows.
fn exceeds_box_axes_depth(boxed: &Collider, other: &Collider, subshape: u32, depth: f32) -> bool {
    let (pose, part) = match other.shape().as_compound() {
        Some(compound) => match compound.shapes().get(subshape as usize) {
            Some((part_pose, part)) => (*other.position() * *part_pose, part.as_ref()),
            None => return false,
        },
        None => (*other.position(), other.shape()),
    };
    box_axes_depth(boxed, &pose, part).is_some_and(|bound| depth > bound + MISFIRE_MARGIN)
}

/// The least push along one of box `a`'s axes that takes `part` (at `pose`) out of it (m), or
/// `None` when `a` is not a box or the part has no vertices to push (a ball, say).
fn box_axes_depth(a: &Collider, pose: &Pose, part: &dyn Shape) -> Option<f32> {
    let half = a.shape().as_cuboid()?.half_extents;
    let corners;
    let points: &[Vector] = if let Some(poly) = part.as_convex_polyhedron() {
        poly.points()
    } else {
        let h = part.as_cuboid()?.half_extents;
        corners = [-1.0f32, 1.0].map(|x| {
            [-1.0f32, 1.0].map(|y| [-1.0f32, 1.0].map(|z| Vector::new(x * h.x, y * h.y, z * h.z)))
        });
        corners.as_flattened().as_flattened()
    };
    let mut low = Vector::splat(f32::INFINITY);
    let mut high = Vector::splat(f32::NEG_INFINITY);
    for &p in points {
        let local = a
            .position()
            .inverse_transform_point(pose.transform_point(p));
        low = low.min(local);
        high = high.max(local);
    }
    // Along each axis, the push out through the nearer face; any axis the part clears is 0.
    let push = (high + half).min(half - low).max(Vector::ZERO);
    Some(push.min_element())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rapier3d::math::Rotation;
    use rapier3d::parry::shape::{Ball, Cuboid};

    #[test]
    fn the_box_axes_bound_reads_a_cube_s_depth_in_a_floor() {
        let floor = ColliderBuilder::cuboid(1.0, 1.0, 0.1).build();
        let cube = Cuboid::new(Vector::splat(0.05));
        let at = |z: f32, tilt: f32| {
            Pose::from_parts(Vector::new(0.2, -0.3, z), Rotation::from_rotation_x(tilt))
        };
        let diagonal = 0.05 * std::f32::consts::SQRT_2;
        for (pose, expected) in [
            (at(0.15 - 0.003, 0.0), 0.003),
            // On an edge, 45° over: the edge is what goes in.
            (
                at(0.1 + diagonal - 0.004, std::f32::consts::FRAC_PI_4),
                0.004,
            ),
            (at(0.15 + 0.01, 0.0), 0.0),
        ] {
            let bound = box_axes_depth(&floor, &pose, &cube).unwrap();
            assert!(
                (bound - expected).abs() < 1e-5,
                "{bound} against {expected}"
            );
            let exact =
                rapier3d::parry::query::contact(floor.position(), floor.shape(), &pose, &cube, 0.0)
                    .unwrap()
                    .map_or(0.0, |c| (-c.dist).max(0.0));
            assert!(
                (exact - expected).abs() < 1e-4,
                "exact {exact} against {expected}"
            );
        }
        // A part without vertices has no bound; the exact query alone measures it.
        assert!(box_axes_depth(&floor, &at(0.1, 0.0), &Ball::new(0.05)).is_none());
    }

    #[test]
    fn a_contact_deeper_than_the_box_axes_allow_is_a_misfire() {
        let floor = ColliderBuilder::cuboid(1.0, 1.0, 0.1).build();
        // A compound of two cubes side by side, resting 3 mm into the floor (top at z 0.1).
        let cube = |x: f32| {
            (
                Pose::from_translation(Vector::new(x, 0.0, 0.0)),
                SharedShape::cuboid(0.02, 0.02, 0.02),
            )
        };
        let body = ColliderBuilder::compound(vec![cube(-0.03), cube(0.03)])
            .translation(Vector::new(0.0, 0.0, 0.1 + 0.02 - 0.003))
            .build();
        // The scissors' misfire: 33.7 mm against a part lying 3 mm deep.
        assert!(exceeds_box_axes_depth(&floor, &body, 1, 0.0337));
        // The true depth, and a clipped point a little past it, stand.
        assert!(!exceeds_box_axes_depth(&floor, &body, 0, 0.003));
        assert!(!exceeds_box_axes_depth(&floor, &body, 1, 0.0045));
        // Sunk for real, 12 mm deep, a 12 mm contact stands too.
        let sunk = ColliderBuilder::cuboid(0.02, 0.02, 0.02)
            .translation(Vector::new(0.0, 0.0, 0.1 + 0.02 - 0.012))
            .build();
        assert!(!exceeds_box_axes_depth(&floor, &sunk, 0, 0.012));
        assert!(exceeds_box_axes_depth(&floor, &sunk, 0, 0.03));
        // A part index the compound lacks is left alone rather than guessed at.
        assert!(!exceeds_box_axes_depth(&floor, &body, 7, 0.05));
        // The hook screens boxes, of the scenery or the hand; an object is a compound.
        assert!(is_box(&floor));
        assert!(!is_box(&body));
    }
}
