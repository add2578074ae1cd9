//! Pinhole camera model shared by the renderer and the grasp-map code.
//!
//! Conventions: image `u` is the column (to the right), `v` the row (downwards); pixel
//! `(u, v)` covers `[u, u+1) × [v, v+1)`, so its centre is `(u + 0.5, v + 0.5)`. The camera
//! frame has x = image right, y = image down, z = forward along the optical axis, and
//! "depth" always means the distance along that axis (not the length of the ray).
use rapier3d::math::{Pose, Rotation as Quat, Vector as Vec3};

/// Height of the top-down camera's eye above the table (metres), as the reference sets it.
// The reference's value, deliberately not 1/√2 (0.7071068): depth maps must match it exactly.
#[allow(clippy::approx_constant)]
pub(crate) const TOP_DOWN_EYE_HEIGHT: f32 = 0.70711;

/// An ideal pinhole camera (no distortion) with intrinsics in pixels and a rigid pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length along `u`, in pixels.
    pub(crate) fx: f32,
    /// Focal length along `v`, in pixels.
    pub(crate) fy: f32,
    /// Principal point, column coordinate (continuous pixel units).
    pub(crate) cx: f32,
    /// Principal point, row coordinate (continuous pixel units).
    pub(crate) cy: f32,
    /// Near clipping depth in metres; surfaces closer than this are not seen.
    pub(crate) near: f32,
    /// Far depth in metres; reported as the depth wherever nothing is hit.
    pub(crate) far: f32,
    /// Camera-to-world pose: camera x = image right, y = image down, z = optical axis.
    pub(crate) pose: Pose,
}

impl Camera {
    /// The workcell's fixed top-down camera: 128 × 128 pixels, 80° vertical field of view,
    /// eye at (0.5, 0, 0.70711) looking straight down at (0.5, 0, 0) with up = (−1, 0, 0).
    ///
    /// Image columns therefore run along world +y and rows along world +x.
    pub fn top_down() -> Self {
        Self::straight_down_over(0.5, -1.0)
    }

    /// The camera over bin 2: the bin-1 camera mirrored through the robot's base, 128 × 128
    /// pixels, 80° vertical field of view, eye at (−0.5, 0, 0.70711) looking straight down at
    /// (−0.5, 0, 0) with up = (1, 0, 0). The workcell reads from it where to place.
    pub fn place_top_down() -> Self {
        Self::straight_down_over(-0.5, 1.0)
    }

    /// The workcell's camera model over world x = `x`: 128 × 128, 80°, looking straight down
    /// from [`TOP_DOWN_EYE_HEIGHT`] with up along x by `up_x`.
    fn straight_down_over(x: f32, up_x: f32) -> Self {
        Self::look_at(
            Vec3::new(x, 0.0, TOP_DOWN_EYE_HEIGHT),
            Vec3::new(x, 0.0, 0.0),
            Vec3::new(up_x, 0.0, 0.0),
            80.0,
            128,
            128,
        )
    }

    /// A camera at `eye` looking at `target`, with `up` pointing towards the top of the image.
    ///
    /// Square pixels, principal point at the image centre, `near` = 0.01 m, `far` = 10 m
    /// (both public fields, adjust as needed). If `up` is parallel to the viewing direction
    /// an arbitrary perpendicular up vector is used instead.
    pub(crate) fn look_at(
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        vertical_fov_deg: f32,
        width: u32,
        height: u32,
    ) -> Self {
        let forward = (target - eye).normalize();
        let mut right = forward.cross(up);
        if right.length_squared() < 1e-12 {
            right = forward.any_orthonormal_vector();
        }
        let right = right.normalize();
        // Completing the right-handed frame (x, y, z) = (right, down, forward).
        let down = forward.cross(right);
        let rotation = quat_from_basis(right, down, forward);
        // f64 so that the focal length 64 / tan(40°) is as exact as f32 can hold.
        let half_fov = (f64::from(vertical_fov_deg) * 0.5).to_radians();
        let f = (f64::from(height) * 0.5 / half_fov.tan()) as f32;
        Self {
            width,
            height,
            fx: f,
            fy: f,
            cx: width as f32 * 0.5,
            cy: height as f32 * 0.5,
            near: 0.01,
            far: 10.0,
            pose: Pose::from_parts(eye, rotation),
        }
    }

    /// The optical centre in world coordinates.
    #[cfg(test)]
    pub(crate) fn eye(&self) -> Vec3 {
        self.pose.translation
    }

    /// Unit world-space direction of the ray through the continuous image point `(u, v)`.
    ///
    /// Pass `(u + 0.5, v + 0.5)` for the centre of pixel `(u, v)`.
    #[cfg(test)]
    pub(crate) fn ray_direction(&self, u: f32, v: f32) -> Vec3 {
        (self.pose.rotation * self.camera_ray(u, v)).normalize()
    }

    /// Projects a world point to continuous `[u, v, depth]`; `None` if `depth <= near`.
    ///
    /// Points outside the image rectangle are still projected (the caller decides).
    pub fn project(&self, p: Vec3) -> Option<[f32; 3]> {
        let c = self.pose.inverse_transform_point(p);
        if c.z <= self.near || c.z.is_nan() {
            return None;
        }
        Some([
            self.fx * c.x / c.z + self.cx,
            self.fy * c.y / c.z + self.cy,
            c.z,
        ])
    }

    /// World point seen through the centre of pixel `(u, v)` at optical-axis depth `depth`.
    pub(crate) fn pixel_to_world(&self, u: u32, v: u32, depth: f32) -> Vec3 {
        let ray = self.camera_ray(u as f32 + 0.5, v as f32 + 0.5);
        self.pose.transform_point(ray * depth)
    }

    /// Camera-frame ray through `(u, v)` scaled to unit depth, so that a ray parameter
    /// equals optical-axis depth.
    fn camera_ray(&self, u: f32, v: f32) -> Vec3 {
        Vec3::new((u - self.cx) / self.fx, (v - self.cy) / self.fy, 1.0)
    }
}

/// Rotation whose matrix has the orthonormal right-handed columns `x`, `y`, `z`.
///
/// Shepperd's method: branching on the largest diagonal term keeps the square root away
/// from zero, so 180° rotations (like the top-down camera's) come out exact.
fn quat_from_basis(x: Vec3, y: Vec3, z: Vec3) -> Quat {
    let (m00, m01, m02) = (x.x, y.x, z.x);
    let (m10, m11, m12) = (x.y, y.y, z.y);
    let (m20, m21, m22) = (x.z, y.z, z.z);
    let trace = m00 + m11 + m22;
    let q = if trace > 0.0 {
        let s = (trace + 1.0).sqrt() * 2.0;
        Quat::from_xyzw((m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s, 0.25 * s)
    } else if m00 > m11 && m00 > m22 {
        let s = (1.0 + m00 - m11 - m22).sqrt() * 2.0;
        Quat::from_xyzw(0.25 * s, (m01 + m10) / s, (m02 + m20) / s, (m21 - m12) / s)
    } else if m11 > m22 {
        let s = (1.0 + m11 - m00 - m22).sqrt() * 2.0;
        Quat::from_xyzw((m01 + m10) / s, 0.25 * s, (m12 + m21) / s, (m02 - m20) / s)
    } else {
        let s = (1.0 + m22 - m00 - m11).sqrt() * 2.0;
        Quat::from_xyzw((m02 + m20) / s, (m12 + m21) / s, 0.25 * s, (m10 - m01) / s)
    };
    q.normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The reference's eye height, written out independently of the constant under test.
    #[allow(clippy::approx_constant)]
    const REF_EYE_Z: f32 = 0.70711;
    /// 64 / tan(40°), written out so the test does not reuse the camera's own formula.
    const REF_F: f32 = 76.272_23;

    fn spec_world(u: u32, v: u32, d: f32) -> Vec3 {
        Vec3::new(
            0.5 + (v as f32 + 0.5 - 64.0) * d / REF_F,
            (u as f32 + 0.5 - 64.0) * d / REF_F,
            REF_EYE_Z - d,
        )
    }

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).abs().max_element() <= tol
    }

    #[test]
    fn top_down_intrinsics_match_spec() {
        let c = Camera::top_down();
        assert_eq!((c.width, c.height), (128, 128));
        assert!((c.fx - REF_F).abs() < 1e-4, "fx = {}", c.fx);
        assert!((c.fy - REF_F).abs() < 1e-4);
        assert_eq!((c.cx, c.cy), (64.0, 64.0));
        assert_eq!((c.near, c.far), (0.01, 10.0));
        assert!(close(c.eye(), Vec3::new(0.5, 0.0, REF_EYE_Z), 0.0));
    }

    #[test]
    fn top_down_axes_match_spec() {
        let c = Camera::top_down();
        let r = c.pose.rotation;
        assert!(
            close(r * Vec3::X, Vec3::Y, 1e-6),
            "image right should be world +y"
        );
        assert!(
            close(r * Vec3::Y, Vec3::X, 1e-6),
            "image down should be world +x"
        );
        assert!(
            close(r * Vec3::Z, -Vec3::Z, 1e-6),
            "optical axis should be world -z"
        );
    }

    #[test]
    fn pixel_to_world_matches_spec_formula() {
        let c = Camera::top_down();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut cases: Vec<(u32, u32, f32)> = vec![
            (0, 0, 0.7),
            (127, 127, 0.7),
            (64, 64, 0.5),
            (0, 127, 0.01),
            (127, 0, 9.9),
        ];
        for _ in 0..2000 {
            cases.push((
                rng.random_range(0..128),
                rng.random_range(0..128),
                rng.random_range(0.01..2.0),
            ));
        }
        for (u, v, d) in cases {
            let got = c.pixel_to_world(u, v, d);
            let want = spec_world(u, v, d);
            // f32 rounding of a product of terms up to ~1: a few ulps of the magnitude.
            let tol = 2e-6 * (1.0 + d);
            assert!(close(got, want, tol), "({u},{v},{d}): {got} vs {want}");
        }
    }

    #[test]
    fn project_inverts_pixel_to_world() {
        let c = Camera::top_down();
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        for _ in 0..2000 {
            let (u, v) = (rng.random_range(0..128u32), rng.random_range(0..128u32));
            let d = rng.random_range(0.02..3.0f32);
            let [pu, pv, pd] = c.project(c.pixel_to_world(u, v, d)).expect("in front");
            assert!((pu - (u as f32 + 0.5)).abs() < 1e-3, "u {u}: {pu}");
            assert!((pv - (v as f32 + 0.5)).abs() < 1e-3, "v {v}: {pv}");
            assert!((pd - d).abs() < 1e-3, "d {d}: {pd}");
        }
    }

    #[test]
    fn centre_ray_points_straight_down() {
        let c = Camera::top_down();
        let d = c.ray_direction(64.0, 64.0);
        assert!(close(d, Vec3::new(0.0, 0.0, -1.0), 1e-6), "{d}");
        let corner = c.ray_direction(0.0, 0.0);
        assert!((corner.length() - 1.0).abs() < 1e-6);
        // Top-left of the image is towards world -x (image up) and -y (image left).
        assert!(
            corner.x < 0.0 && corner.y < 0.0 && corner.z < 0.0,
            "{corner}"
        );
    }

    #[test]
    fn point_towards_plus_x_plus_y_is_below_and_right_of_centre() {
        let c = Camera::top_down();
        let [u, v, d] = c.project(Vec3::new(0.6, 0.1, 0.0)).unwrap();
        assert!(v > 64.0, "row {v} should be below the centre");
        assert!(u > 64.0, "column {u} should be right of the centre");
        assert!((d - REF_EYE_Z).abs() < 1e-6);
        // Exact values from the reference formula inverted.
        assert!((u - (64.0 + 0.1 * REF_F / REF_EYE_Z)).abs() < 1e-3);
        assert!((v - (64.0 + 0.1 * REF_F / REF_EYE_Z)).abs() < 1e-3);
    }

    #[test]
    fn project_rejects_points_behind_or_at_near_plane() {
        let c = Camera::top_down();
        assert!(c.project(Vec3::new(0.5, 0.0, 1.0)).is_none());
        assert!(c.project(Vec3::new(0.5, 0.0, REF_EYE_Z - 0.005)).is_none());
        assert!(c.project(Vec3::new(0.5, 0.0, REF_EYE_Z - 0.02)).is_some());
        assert!(c.project(Vec3::new(f32::NAN, 0.0, 0.0)).is_none());
    }

    #[test]
    fn look_at_oblique_view() {
        let eye = Vec3::new(1.4, -0.9, 1.1);
        let target = Vec3::new(0.5, 0.0, 0.1);
        let c = Camera::look_at(eye, target, Vec3::Z, 50.0, 320, 240);
        assert_eq!((c.cx, c.cy), (160.0, 120.0));
        let f = 120.0 / 25f32.to_radians().tan();
        assert!((c.fx - f).abs() < 1e-3 && (c.fy - f).abs() < 1e-3);
        // The target lands on the principal point at its Euclidean distance.
        let [u, v, d] = c.project(target).unwrap();
        assert!(
            (u - 160.0).abs() < 1e-3 && (v - 120.0).abs() < 1e-3,
            "{u} {v}"
        );
        assert!((d - (target - eye).length()).abs() < 1e-5);
        // World up appears towards the top of the image; the top row of the image's
        // vertical field of view is at the expected angle.
        let [_, v_up, _] = c.project(target + Vec3::Z * 0.1).unwrap();
        assert!(v_up < 120.0);
        let top = c.ray_direction(160.0, 0.0);
        let axis = (target - eye).normalize();
        assert!((top.dot(axis).acos().to_degrees() - 25.0).abs() < 1e-3);
        // Rotation is proper (right-handed) and orthonormal.
        let r = c.pose.rotation;
        assert!(close((r * Vec3::X).cross(r * Vec3::Y), r * Vec3::Z, 1e-6));
        assert!(
            (r * Vec3::X).z.abs() < 1e-6,
            "image rows stay level with up = z"
        );
    }

    #[test]
    fn look_at_with_degenerate_up_is_still_a_valid_camera() {
        let c = Camera::look_at(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), Vec3::Z, 60.0, 64, 48);
        let d = c.ray_direction(32.0, 24.0);
        assert!(close(d, -Vec3::Z, 1e-6), "{d}");
        assert!(c.pose.rotation.is_normalized());
    }

    #[test]
    fn quat_from_basis_handles_every_branch() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut rotations = vec![
            Quat::IDENTITY,
            Quat::from_rotation_x(std::f32::consts::PI),
            Quat::from_rotation_y(std::f32::consts::PI),
            Quat::from_rotation_z(std::f32::consts::PI),
        ];
        for _ in 0..200 {
            let axis = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
            .normalize_or(Vec3::X);
            rotations.push(Quat::from_axis_angle(
                axis,
                rng.random_range(-std::f32::consts::PI..std::f32::consts::PI),
            ));
        }
        for q in rotations {
            let r = quat_from_basis(q * Vec3::X, q * Vec3::Y, q * Vec3::Z);
            for v in [Vec3::X, Vec3::Y, Vec3::Z, Vec3::new(0.3, -0.7, 0.2)] {
                assert!(close(r * v, q * v, 1e-5), "{q} vs {r}");
            }
        }
    }

    proptest! {
        #[test]
        fn oblique_round_trip(
            ex in -2.0f32..2.0, ey in -2.0f32..2.0, ez in 0.5f32..2.0,
            u in 0u32..200, v in 0u32..150, d in 0.05f32..5.0,
        ) {
            let c = Camera::look_at(Vec3::new(ex, ey, ez), Vec3::new(0.5, 0.0, 0.0), Vec3::Z, 60.0, 200, 150);
            let p = c.pixel_to_world(u, v, d);
            let [pu, pv, pd] = c.project(p).unwrap();
            prop_assert!((pu - (u as f32 + 0.5)).abs() < 1e-3);
            prop_assert!((pv - (v as f32 + 0.5)).abs() < 1e-3);
            prop_assert!((pd - d).abs() < 1e-3 * d.max(1.0));
            // The unit ray through the same pixel centre reaches p.
            let dir = c.ray_direction(u as f32 + 0.5, v as f32 + 0.5);
            let along = (p - c.eye()).dot(dir);
            prop_assert!(((c.eye() + dir * along) - p).length() < 1e-4 * d.max(1.0));
        }
    }
}
