//! Collider shapes for the objects' URDF geometry: primitives as rapier shapes, round ones as
//! faceted hulls.

use anyhow::Context;
use rapier3d::math::Vector;
use rapier3d::prelude::*;

use crate::assets::urdf::CollisionShape;

/// Facets around a round collision shape. Rapier has no rolling resistance, so exactly round
/// cans and balls rolled on for seconds; faceted hulls (like the convex decompositions of real
/// object meshes) come to rest.
const ROUND_FACETS: usize = 24;

/// The rapier collider shape of a URDF collision shape, round ones faceted.
pub(crate) fn shared_shape(shape: &CollisionShape) -> anyhow::Result<SharedShape> {
    let hull = |points: Vec<Vector>| {
        SharedShape::convex_hull(&points)
            .context("a collision mesh piece is degenerate (flat or fewer than 4 points)")
    };
    match shape {
        CollisionShape::Cuboid { half_extents: h } => Ok(SharedShape::cuboid(h.x, h.y, h.z)),
        CollisionShape::Sphere { radius } => hull(sphere_points(*radius, 0.0)),
        CollisionShape::Cylinder {
            radius,
            half_height,
        } => hull(
            [-*half_height, *half_height]
                .iter()
                .flat_map(|&y| ring(*radius, y))
                .collect(),
        ),
        CollisionShape::Capsule {
            radius,
            half_height,
        } => hull(sphere_points(*radius, *half_height)),
        CollisionShape::ConvexHull { points } => hull(points.clone()),
    }
}

/// Points on a circle of radius `r` in the plane y = `y`.
fn ring(r: f32, y: f32) -> impl Iterator<Item = Vector> {
    (0..ROUND_FACETS).map(move |i| {
        let a = i as f32 * std::f32::consts::TAU / ROUND_FACETS as f32;
        Vector::new(r * a.cos(), y, r * a.sin())
    })
}

/// Points on a sphere of radius `r`, split at the equator and pulled apart by ±`half` along y
/// (a capsule; a sphere when `half` is 0).
fn sphere_points(r: f32, half: f32) -> Vec<Vector> {
    let bands = ROUND_FACETS / 4;
    let mut points = vec![
        Vector::new(0.0, r + half, 0.0),
        Vector::new(0.0, -r - half, 0.0),
    ];
    for b in 1..bands {
        let polar = b as f32 * std::f32::consts::FRAC_PI_2 / bands as f32;
        let (ring_r, ring_y) = (r * polar.sin(), r * polar.cos());
        points.extend(ring(ring_r, half + ring_y));
        points.extend(ring(ring_r, -half - ring_y));
    }
    points.extend(ring(r, half));
    points.extend(ring(r, -half));
    points
}
