//! Analytic ray intersections with the renderer's primitive shapes, in the shape's local frame.
//!
//! Every function takes a ray `origin + t · dir` (the direction need not be unit length;
//! `t` is measured in multiples of it) and an accepted interval `[tmin, tmax]`, and returns
//! the smallest `t` in that interval where the ray crosses the surface, together with the
//! unit outward normal there. A ray starting inside a solid therefore reports its exit point.
//! Cylinders and capsules use parry's convention: the axis is local Y, centred on the origin.
use rapier3d::math::Vector as Vec3;

/// Tolerance on barycentric coordinates so rays through a shared mesh edge cannot slip
/// between the two triangles through rounding.
const BARY_EPS: f32 = 1e-6;

/// A ray–surface intersection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Hit {
    /// Ray parameter of the hit, in multiples of the ray direction.
    pub(crate) t: f32,
    /// Unit outward surface normal (for triangles: the face normal turned towards the ray
    /// origin, since triangle winding is not trusted).
    pub(crate) normal: Vec3,
}

/// Expresses a world-space ray in the local frame of a shape placed at `pose`
/// (local-to-world). Rigid transforms preserve the ray parameter `t`.
#[cfg(test)]
pub(crate) fn ray_to_local(pose: &rapier3d::math::Pose, origin: Vec3, dir: Vec3) -> (Vec3, Vec3) {
    let to_local = pose.rotation.inverse();
    (to_local * (origin - pose.translation), to_local * dir)
}

/// Collects candidate hits and keeps the nearest one inside `[tmin, tmax]`.
struct Nearest {
    tmin: f32,
    tmax: f32,
    best: Option<Hit>,
}

impl Nearest {
    fn new(tmin: f32, tmax: f32) -> Self {
        Self {
            tmin,
            tmax,
            best: None,
        }
    }

    fn accepts(&self, t: f32) -> bool {
        t >= self.tmin && t <= self.tmax && self.best.is_none_or(|b| t < b.t)
    }

    /// The normal is computed lazily because most candidates are rejected.
    fn offer(&mut self, t: f32, normal: impl FnOnce() -> Vec3) {
        if self.accepts(t) {
            self.best = Some(Hit {
                t,
                normal: normal(),
            });
        }
    }
}

/// Ray against the axis-aligned box `[-half, half]` (slab test).
pub(crate) fn ray_cuboid(origin: Vec3, dir: Vec3, half: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
    let mut t_enter = f32::NEG_INFINITY;
    let mut enter_axis = 0;
    let mut t_exit = f32::INFINITY;
    let mut exit_axis = 0;
    for i in 0..3 {
        // A (near-)parallel ray never crosses this slab's planes: it is either always
        // between them or never. Tiny components would otherwise give inf·0 = NaN.
        if dir[i].abs() < 1e-20 {
            if origin[i].abs() > half[i] {
                return None;
            }
            continue;
        }
        let inv = 1.0 / dir[i];
        let a = (-half[i] - origin[i]) * inv;
        let b = (half[i] - origin[i]) * inv;
        let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
        if lo > t_enter {
            t_enter = lo;
            enter_axis = i;
        }
        if hi < t_exit {
            t_exit = hi;
            exit_axis = i;
        }
    }
    if t_enter > t_exit {
        return None;
    }
    let mut nearest = Nearest::new(tmin, tmax);
    nearest.offer(t_enter, || {
        axis_normal(enter_axis, -dir[enter_axis].signum())
    });
    if nearest.best.is_none() {
        nearest.offer(t_exit, || axis_normal(exit_axis, dir[exit_axis].signum()));
    }
    nearest.best
}

fn axis_normal(axis: usize, sign: f32) -> Vec3 {
    let mut n = Vec3::ZERO;
    n[axis] = sign;
    n
}

/// Ray against the sphere of `radius` centred on the origin.
pub(crate) fn ray_sphere(
    origin: Vec3,
    dir: Vec3,
    radius: f32,
    tmin: f32,
    tmax: f32,
) -> Option<Hit> {
    let mut nearest = Nearest::new(tmin, tmax);
    sphere_roots(origin, dir, radius, |t| {
        let p = origin + dir * t;
        nearest.offer(t, || p.normalize_or(Vec3::Z));
    });
    nearest.best
}

/// Calls `visit` with both roots of `|origin + t·dir| = radius`, if real.
///
/// Solving around the ray's closest approach (instead of the textbook `b² − 4ac`) avoids
/// the cancellation that costs precision when the ray starts far from a small sphere.
fn sphere_roots(origin: Vec3, dir: Vec3, radius: f32, mut visit: impl FnMut(f32)) {
    let a = dir.length_squared();
    if a == 0.0 {
        return;
    }
    let t_closest = -origin.dot(dir) / a;
    let miss2 = (origin + dir * t_closest).length_squared();
    let h2 = radius * radius - miss2;
    if h2 < 0.0 {
        return;
    }
    let half_chord = (h2 / a).sqrt();
    visit(t_closest - half_chord);
    visit(t_closest + half_chord);
}

/// Calls `visit` with both roots of `x² + z² = radius²` along the ray (infinite cylinder
/// around local Y), if real; same closest-approach formulation as [`sphere_roots`].
fn side_roots(origin: Vec3, dir: Vec3, radius: f32, mut visit: impl FnMut(f32)) {
    let a = dir.x * dir.x + dir.z * dir.z;
    // Parallel to the axis: the side is never crossed (the caps handle such rays).
    if a < 1e-24 {
        return;
    }
    let t_closest = -(origin.x * dir.x + origin.z * dir.z) / a;
    let px = origin.x + dir.x * t_closest;
    let pz = origin.z + dir.z * t_closest;
    let h2 = radius * radius - (px * px + pz * pz);
    if h2 < 0.0 {
        return;
    }
    let half_chord = (h2 / a).sqrt();
    visit(t_closest - half_chord);
    visit(t_closest + half_chord);
}

fn radial_normal(p: Vec3) -> Vec3 {
    Vec3::new(p.x, 0.0, p.z).normalize_or(Vec3::X)
}

/// Offers the ray's crossings of the round side (radius `radius` about local Y) within
/// `|y| <= half`: the part that cylinders and capsules share.
fn side_hits(mut nearest: Nearest, origin: Vec3, dir: Vec3, radius: f32, half: f32) -> Nearest {
    side_roots(origin, dir, radius, |t| {
        let p = origin + dir * t;
        if p.y.abs() <= half {
            nearest.offer(t, || radial_normal(p));
        }
    });
    nearest
}

/// Ray against the finite capped cylinder with axis local Y, `|y| <= half_height`.
pub(crate) fn ray_cylinder(
    origin: Vec3,
    dir: Vec3,
    radius: f32,
    half_height: f32,
    tmin: f32,
    tmax: f32,
) -> Option<Hit> {
    let mut nearest = side_hits(Nearest::new(tmin, tmax), origin, dir, radius, half_height);
    if dir.y != 0.0 {
        for sign in [-1.0f32, 1.0] {
            let t = (sign * half_height - origin.y) / dir.y;
            if nearest.accepts(t) {
                let p = origin + dir * t;
                if p.x * p.x + p.z * p.z <= radius * radius {
                    nearest.offer(t, || Vec3::new(0.0, sign, 0.0));
                }
            }
        }
    }
    nearest.best
}

/// Ray against the capsule around the local-Y segment from `-half_height` to `+half_height`.
pub(crate) fn ray_capsule(
    origin: Vec3,
    dir: Vec3,
    radius: f32,
    half_height: f32,
    tmin: f32,
    tmax: f32,
) -> Option<Hit> {
    let mut nearest = side_hits(Nearest::new(tmin, tmax), origin, dir, radius, half_height);
    // Each end sphere only contributes the part of its surface beyond its end of the
    // segment; the rest lies inside the capsule.
    for sign in [-1.0f32, 1.0] {
        let centre = Vec3::new(0.0, sign * half_height, 0.0);
        let local = origin - centre;
        sphere_roots(local, dir, radius, |t| {
            let p = local + dir * t;
            if p.y * sign >= 0.0 {
                nearest.offer(t, || p.normalize_or(Vec3::new(0.0, sign, 0.0)));
            }
        });
    }
    nearest.best
}

/// Ray against the triangle `(a, b, c)` (Möller–Trumbore), hit from either side.
pub(crate) fn ray_triangle(
    origin: Vec3,
    dir: Vec3,
    [a, b, c]: [Vec3; 3],
    tmin: f32,
    tmax: f32,
) -> Option<Hit> {
    let e1 = b - a;
    let e2 = c - a;
    let p = dir.cross(e2);
    let det = e1.dot(p);
    // Either sign of det is accepted: both faces are hit.
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - a;
    let u = s.dot(p) * inv;
    if !(-BARY_EPS..=1.0 + BARY_EPS).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < -BARY_EPS || u + v > 1.0 + BARY_EPS {
        return None;
    }
    let t = e2.dot(q) * inv;
    if !(t >= tmin && t <= tmax) {
        return None;
    }
    let n = e1.cross(e2).normalize_or(Vec3::Z);
    let normal = if n.dot(dir) > 0.0 { -n } else { n };
    Some(Hit { t, normal })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use rapier3d::math::{Pose, Rotation as Quat};

    /// Exact signed distance functions, an independent description of each surface.
    #[derive(Clone, Copy, Debug)]
    enum Solid {
        Cuboid(Vec3),
        Sphere(f32),
        Cylinder(f32, f32),
        Capsule(f32, f32),
    }

    impl Solid {
        fn sdf(self, p: Vec3) -> f32 {
            match self {
                Solid::Cuboid(h) => {
                    let q = p.abs() - h;
                    q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
                }
                Solid::Sphere(r) => p.length() - r,
                Solid::Cylinder(r, hh) => {
                    let dr = (p.x * p.x + p.z * p.z).sqrt() - r;
                    let dy = p.y.abs() - hh;
                    let outside = (dr.max(0.0).powi(2) + dy.max(0.0).powi(2)).sqrt();
                    outside + dr.max(dy).min(0.0)
                }
                Solid::Capsule(r, hh) => {
                    let y = p.y.clamp(-hh, hh);
                    (p - Vec3::new(0.0, y, 0.0)).length() - r
                }
            }
        }

        fn bounding_radius(self) -> f32 {
            match self {
                Solid::Cuboid(h) => h.length(),
                Solid::Sphere(r) => r,
                Solid::Cylinder(r, hh) => (r * r + hh * hh).sqrt(),
                Solid::Capsule(r, hh) => r + hh,
            }
        }

        fn cast(self, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
            match self {
                Solid::Cuboid(h) => ray_cuboid(o, d, h, tmin, tmax),
                Solid::Sphere(r) => ray_sphere(o, d, r, tmin, tmax),
                Solid::Cylinder(r, hh) => ray_cylinder(o, d, r, hh, tmin, tmax),
                Solid::Capsule(r, hh) => ray_capsule(o, d, r, hh, tmin, tmax),
            }
        }
    }

    /// First parameter where sphere tracing (which never overshoots an exact SDF)
    /// reaches the surface, if it does before `t_end`.
    fn sphere_trace(solid: Solid, o: Vec3, d: Vec3, t_end: f32) -> Option<f32> {
        let len = d.length();
        let mut t = 0.0f32;
        for _ in 0..100_000 {
            let dist = solid.sdf(o + d * t);
            if dist < 2e-6 {
                return Some(t);
            }
            t += dist / len;
            if t > t_end {
                return None;
            }
        }
        None
    }

    fn random_unit(rng: &mut ChaCha8Rng) -> Vec3 {
        loop {
            let v = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }

    /// Checks hits and misses of many random rays (mostly aimed near the solid, with
    /// non-unit directions) against the solid's SDF.
    fn check_against_sdf(solid: Solid, seed: u64, rays: usize) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let br = solid.bounding_radius();
        let (mut hits, mut misses) = (0, 0);
        for _ in 0..rays {
            let o = random_unit(&mut rng) * rng.random_range(br * 1.5..br * 4.0);
            let aim = random_unit(&mut rng) * rng.random_range(0.0..br * 1.2);
            let d = (aim - o) * rng.random_range(0.3..3.0);
            let len = d.length();
            match solid.cast(o, d, 0.0, 100.0) {
                Some(hit) => {
                    hits += 1;
                    let p = o + d * hit.t;
                    assert!(solid.sdf(p).abs() < 1e-4, "{solid:?}: hit off surface {p}");
                    // Nothing was crossed before: sphere tracing reaches the same point.
                    let traced = sphere_trace(solid, o, d, hit.t + 1.0)
                        .expect("sphere tracing should also hit");
                    assert!(
                        (traced - hit.t).abs() * len < 1e-4,
                        "{solid:?}: analytic {} vs traced {traced} (o {o}, d {d})",
                        hit.t
                    );
                    let before = p - d / len * 1e-3;
                    assert!(
                        solid.sdf(before) > 0.0,
                        "{solid:?}: point before hit is inside"
                    );
                    // For a convex solid, stepping along a valid outward normal moves away
                    // from the surface by exactly the step.
                    assert!((hit.normal.length() - 1.0).abs() < 1e-5);
                    let out = solid.sdf(p + hit.normal * 1e-3);
                    assert!(
                        (out - 1e-3).abs() < 1e-4,
                        "{solid:?}: bad normal {} at {p}",
                        hit.normal
                    );
                }
                None => {
                    misses += 1;
                    // A miss must not pass through the solid: sample densely over the
                    // part of the ray inside the bounding sphere.
                    let steps = 4000;
                    let t_far = (o.length() + br) / len;
                    for k in 0..=steps {
                        let t = t_far * k as f32 / steps as f32;
                        let s = solid.sdf(o + d * t);
                        assert!(
                            s > -1e-4,
                            "{solid:?}: missed ray goes inside at t={t} (o {o}, d {d})"
                        );
                    }
                }
            }
        }
        assert!(
            hits > rays / 5 && misses > rays / 20,
            "{solid:?}: {hits} hits, {misses} misses"
        );
    }

    /// Rays starting inside the solid report the exit point, and stay inside until then.
    fn check_exits(solid: Solid, seed: u64, rays: usize) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let br = solid.bounding_radius();
        let mut tested = 0;
        while tested < rays {
            let o = random_unit(&mut rng) * rng.random_range(0.0..br);
            if solid.sdf(o) > -1e-3 {
                continue;
            }
            tested += 1;
            let d = random_unit(&mut rng) * rng.random_range(0.3..3.0);
            let hit = solid
                .cast(o, d, 0.0, 100.0)
                .expect("a ray from inside must exit");
            let p = o + d * hit.t;
            assert!(solid.sdf(p).abs() < 1e-4, "{solid:?}: exit off surface {p}");
            for k in 0..200 {
                let t = hit.t * k as f32 / 200.0 - 1e-4 / d.length();
                assert!(
                    solid.sdf(o + d * t.max(0.0)) < 1e-4,
                    "{solid:?}: left early"
                );
            }
            assert!((solid.sdf(p + hit.normal * 1e-3) - 1e-3).abs() < 1e-4);
        }
    }

    #[test]
    fn rays_from_inside_exit() {
        check_exits(Solid::Cuboid(Vec3::new(0.05, 0.08, 0.03)), 30, 200);
        check_exits(Solid::Sphere(0.04), 31, 200);
        check_exits(Solid::Cylinder(0.03, 0.06), 32, 200);
        check_exits(Solid::Capsule(0.04, 0.1), 33, 200);
    }

    #[test]
    fn cuboid_matches_sdf() {
        check_against_sdf(Solid::Cuboid(Vec3::new(0.05, 0.08, 0.03)), 10, 400);
    }

    #[test]
    fn sphere_matches_sdf() {
        check_against_sdf(Solid::Sphere(0.04), 11, 400);
    }

    #[test]
    fn cylinder_matches_sdf() {
        check_against_sdf(Solid::Cylinder(0.03, 0.06), 12, 400);
        check_against_sdf(Solid::Cylinder(0.1, 0.01), 13, 300);
    }

    #[test]
    fn capsule_matches_sdf() {
        check_against_sdf(Solid::Capsule(0.04, 0.1), 14, 400);
        check_against_sdf(Solid::Capsule(0.05, 0.0), 15, 200);
    }

    #[test]
    fn cylinder_side_and_caps() {
        let (r, hh) = (0.05, 0.1);
        // From above, straight down the axis: top cap.
        let h = ray_cylinder(Vec3::new(0.01, 1.0, 0.02), -Vec3::Y, r, hh, 0.0, 10.0).unwrap();
        assert!((h.t - 0.9).abs() < 1e-6 && h.normal == Vec3::Y, "{h:?}");
        // From below: bottom cap.
        let h = ray_cylinder(Vec3::new(0.0, -2.0, 0.0), Vec3::Y * 2.0, r, hh, 0.0, 10.0).unwrap();
        assert!((h.t - 0.95).abs() < 1e-6 && h.normal == -Vec3::Y, "{h:?}");
        // From the side: curved surface, radial normal.
        let h = ray_cylinder(Vec3::new(1.0, 0.07, 0.0), -Vec3::X, r, hh, 0.0, 10.0).unwrap();
        assert!((h.t - 0.95).abs() < 1e-6, "{h:?}");
        assert!((h.normal - Vec3::X).length() < 1e-6);
        // From above but just outside the radius: misses; just inside: hits the cap.
        assert!(ray_cylinder(Vec3::new(0.0501, 1.0, 0.0), -Vec3::Y, r, hh, 0.0, 10.0).is_none());
        assert!(ray_cylinder(Vec3::new(0.0499, 1.0, 0.0), -Vec3::Y, r, hh, 0.0, 10.0).is_some());
        // From the side but above the top: misses.
        assert!(ray_cylinder(Vec3::new(1.0, 0.1001, 0.0), -Vec3::X, r, hh, 0.0, 10.0).is_none());
        // Oblique into the top rim region lands on the cap.
        let o = Vec3::new(0.2, 0.3, 0.0);
        let d = Vec3::new(-0.2, -0.2, 0.0);
        let h = ray_cylinder(o, d, r, hh, 0.0, 10.0).unwrap();
        let p = o + d * h.t;
        assert!(
            (p.y - hh).abs() < 1e-6 && p.x <= r && h.normal == Vec3::Y,
            "{p}"
        );
    }

    #[test]
    fn capsule_ends_are_hemispheres() {
        let (r, hh) = (0.05, 0.1);
        let h = ray_capsule(Vec3::new(0.0, 1.0, 0.0), -Vec3::Y, r, hh, 0.0, 10.0).unwrap();
        assert!((h.t - (1.0 - hh - r)).abs() < 1e-6 && (h.normal - Vec3::Y).length() < 1e-6);
        // Off-axis from above: hits the hemisphere below y = hh + r.
        let x = 0.03;
        let h = ray_capsule(Vec3::new(x, 1.0, 0.0), -Vec3::Y, r, hh, 0.0, 10.0).unwrap();
        let y = hh + (r * r - x * x).sqrt();
        assert!((h.t - (1.0 - y)).abs() < 1e-6, "{h:?}");
        // Through the end sphere's lower half region the side surface is hit instead.
        let h = ray_capsule(Vec3::new(1.0, 0.09, 0.0), -Vec3::X, r, hh, 0.0, 10.0).unwrap();
        assert!((h.t - 0.95).abs() < 1e-6 && (h.normal - Vec3::X).length() < 1e-6);
    }

    #[test]
    fn cuboid_faces_and_interval() {
        let half = Vec3::new(0.1, 0.2, 0.3);
        let h = ray_cuboid(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z, half, 0.0, 10.0).unwrap();
        assert_eq!((h.t, h.normal), (0.7, Vec3::Z));
        // Starting inside reports the exit with its outward normal.
        let h = ray_cuboid(Vec3::ZERO, Vec3::X, half, 0.0, 10.0).unwrap();
        assert_eq!((h.t, h.normal), (0.1, Vec3::X));
        // tmin beyond the entry also yields the exit; tmax before the entry yields nothing.
        let h = ray_cuboid(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z, half, 0.8, 10.0).unwrap();
        assert!((h.t - 1.3).abs() < 1e-6 && h.normal == -Vec3::Z);
        assert!(ray_cuboid(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z, half, 0.0, 0.69).is_none());
        // Axis-parallel ray outside one slab misses.
        assert!(ray_cuboid(Vec3::new(0.2, 0.0, 1.0), -Vec3::Z, half, 0.0, 10.0).is_none());
    }

    #[test]
    fn triangle_both_faces_and_edges() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let above = ray_triangle(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z, tri, 0.0, 10.0).unwrap();
        assert!((above.t - 1.0).abs() < 1e-6 && above.normal == Vec3::Z);
        let below = ray_triangle(Vec3::new(0.2, 0.2, -2.0), Vec3::Z * 2.0, tri, 0.0, 10.0).unwrap();
        assert!((below.t - 1.0).abs() < 1e-6 && below.normal == -Vec3::Z);
        assert!(ray_triangle(Vec3::new(0.6, 0.6, 1.0), -Vec3::Z, tri, 0.0, 10.0).is_none());
        assert!(ray_triangle(Vec3::new(-0.01, 0.2, 1.0), -Vec3::Z, tri, 0.0, 10.0).is_none());
        assert!(ray_triangle(Vec3::new(0.2, 0.2, 1.0), Vec3::X, tri, 0.0, 10.0).is_none());
        assert!(ray_triangle(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z, tri, 0.0, 0.5).is_none());
        // Random rays through a two-triangle quad never fall through the shared diagonal.
        let quad = [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ];
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..20_000 {
            let s = rng.random_range(-0.9..0.9f32);
            let target = Vec3::new(s, s + rng.random_range(-1e-5..1e-5), 0.0);
            let o = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                1.3,
            );
            let d = target - o;
            let a = ray_triangle(o, d, [quad[0], quad[1], quad[2]], 0.0, 10.0);
            let b = ray_triangle(o, d, [quad[0], quad[2], quad[3]], 0.0, 10.0);
            assert!(
                a.is_some() || b.is_some(),
                "ray through {target} fell through the diagonal"
            );
        }
    }

    #[test]
    fn posed_shapes_in_several_orientations() {
        let mut rng = ChaCha8Rng::seed_from_u64(6);
        for _ in 0..60 {
            let pose = Pose::from_parts(
                Vec3::new(
                    rng.random_range(-0.5..0.5),
                    rng.random_range(-0.5..0.5),
                    rng.random_range(0.0..0.5),
                ),
                Quat::from_axis_angle(
                    random_unit(&mut rng),
                    rng.random_range(0.0..std::f32::consts::TAU),
                ),
            );
            let solid = Solid::Cylinder(0.04, 0.07);
            for _ in 0..50 {
                let o = pose.translation + random_unit(&mut rng) * 0.5;
                let d = pose.translation + random_unit(&mut rng) * 0.06 - o;
                let (lo, ld) = ray_to_local(&pose, o, d);
                let Some(hit) = solid.cast(lo, ld, 0.0, 10.0) else {
                    continue;
                };
                let world_p = o + d * hit.t;
                let local_p = pose.inverse_transform_point(world_p);
                assert!(
                    solid.sdf(local_p).abs() < 1e-4,
                    "world hit off the posed cylinder"
                );
                let n_world = pose.rotation * hit.normal;
                assert!(solid.sdf(pose.inverse_transform_point(world_p + n_world * 1e-3)) > 0.9e-3);
            }
        }
    }
}
