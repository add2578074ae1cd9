//! How deep a body is inside one of the scenery's fixed boxes: parry's exact query, part by part,
//! bounded by the depth along the box's own axes.

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
}
