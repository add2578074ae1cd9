//! From an image grasp (pixel, angle) to a world grasp: TCP position and closing direction (docs/grasping.md).

use rapier3d::math::Vector;

use super::tote::FLOOR_TOP;
use super::{normalize_angle, PixelGrasp};
use crate::vision::camera::Camera;
use crate::vision::render::Frame;

/// How far above the tote floor the TCP stays at the lowest (m).
pub const FLOOR_CLEARANCE: f32 = 0.002;
/// Lowest TCP height (m): [`FLOOR_CLEARANCE`] above the tote floor (0.022).
pub const MIN_TCP_HEIGHT: f32 = FLOOR_TOP + FLOOR_CLEARANCE;
/// How far below the clicked surface the TCP goes (m).
pub const DEPTH_BELOW_SURFACE: f32 = 0.05;

/// A grasp in world terms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldGrasp {
    /// Target TCP position.
    pub tcp: Vector,
    /// Unit horizontal direction along which the fingers close (either sign).
    pub closing: Vector,
}

/// A push in world terms: the closed hand lowered at `start` and driven in a straight line to
/// `end`, both TCP positions at the same height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldPush {
    /// Where the TCP goes down.
    pub start: Vector,
    /// Where the stroke ends.
    pub end: Vector,
}

impl WorldPush {
    /// Unit horizontal direction of the stroke.
    pub fn direction(&self) -> Vector {
        let d = self.end - self.start;
        Vector::new(d.x, d.y, 0.0).normalize()
    }
}

/// World direction of the image line at `angle_deg` through the camera's image plane, flattened
/// onto the horizontal: image x runs along the camera's right axis, image y along its down axis.
pub fn closing_direction(camera: &Camera, angle_deg: f32) -> Vector {
    let theta = angle_deg.to_radians();
    let right = camera.pose.rotation * Vector::X;
    let down = camera.pose.rotation * Vector::Y;
    let d = right * theta.cos() + down * theta.sin();
    Vector::new(d.x, d.y, 0.0).normalize()
}

/// The image angle (degrees, [0, 180)) whose closing line runs along the horizontal world
/// direction `direction`: the inverse of [`closing_direction`].
pub fn image_angle(camera: &Camera, direction: Vector) -> f32 {
    let right = camera.pose.rotation * Vector::X;
    let down = camera.pose.rotation * Vector::Y;
    normalize_angle(direction.dot(down).atan2(direction.dot(right)).to_degrees())
}

/// The world grasp for a pixel grasp, using the frame's depth at that pixel.
pub fn world_grasp(camera: &Camera, frame: &Frame, grasp: PixelGrasp) -> WorldGrasp {
    let depth = frame.depth_at(grasp.u, grasp.v);
    let surface = camera.pixel_to_world(grasp.u, grasp.v, depth);
    WorldGrasp {
        tcp: Vector::new(
            surface.x,
            surface.y,
            (surface.z - DEPTH_BELOW_SURFACE).max(MIN_TCP_HEIGHT),
        ),
        closing: closing_direction(camera, grasp.angle_deg),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_axes_map_to_world_axes_of_the_top_down_camera() {
        let camera = Camera::top_down();
        // θ = 0 closes along image x = world +y; θ = 90 along image y = world +x.
        assert!((closing_direction(&camera, 0.0) - Vector::Y).length() < 1e-5);
        assert!((closing_direction(&camera, 90.0) - Vector::X).length() < 1e-5);
        // Clockwise in the image (x towards y) is from world +y towards +x.
        let d = closing_direction(&camera, 30.0);
        let expected = Vector::new(30f32.to_radians().sin(), 30f32.to_radians().cos(), 0.0);
        assert!((d - expected).length() < 1e-5, "{d:?}");
    }

    #[test]
    fn image_angle_inverts_closing_direction() {
        let camera = Camera::top_down();
        for k in 0..36 {
            let angle = k as f32 * 5.0;
            let back = image_angle(&camera, closing_direction(&camera, angle));
            assert!((back - angle).abs() < 1e-3, "{angle} -> {back}");
        }
    }
}
