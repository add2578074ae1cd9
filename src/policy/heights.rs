//! The depth image back-projected once per frame: the world point behind every pixel. The
//! collision check, verification and centring all read this one map of a frame.

use rapier3d::math::Vector;

use crate::vision::camera::Camera;
use crate::vision::render::Frame;

/// The world point, and so the surface height, seen at each pixel of a frame.
pub struct HeightMap {
    size: u32,
    points: Vec<Vector>,
    /// Whether the pixel's ray hit something before the camera's far plane.
    hit: Vec<bool>,
}

impl HeightMap {
    /// Back-projects the frame's depth.
    pub fn new(camera: &Camera, frame: &Frame) -> Self {
        let mut points = Vec::with_capacity((frame.width * frame.height) as usize);
        let mut hit = Vec::with_capacity(points.capacity());
        for v in 0..frame.height {
            for u in 0..frame.width {
                let depth = frame.depth_at(u, v);
                points.push(camera.pixel_to_world(u, v, depth));
                hit.push(depth < camera.far);
            }
        }
        Self {
            size: frame.width,
            points,
            hit,
        }
    }

    /// The surface height seen at pixel (`u`, `v`).
    pub(crate) fn at(&self, u: u32, v: u32) -> f32 {
        self.points[(v * self.size + u) as usize].z
    }

    /// Side length of the square image (px).
    pub(crate) fn size(&self) -> u32 {
        self.size
    }

    /// Every pixel, row by row.
    pub(crate) fn pixels(&self) -> impl Iterator<Item = (u32, u32)> {
        let size = self.size;
        (0..size).flat_map(move |v| (0..size).map(move |u| (u, v)))
    }

    /// The world point seen at pixel (`u`, `v`).
    pub(crate) fn point(&self, u: u32, v: u32) -> Vector {
        self.points[(v * self.size + u) as usize]
    }

    /// The surface height seen where `p` projects; `None` outside the image.
    pub(crate) fn under(&self, camera: &Camera, p: Vector) -> Option<f32> {
        let [u, v, _] = camera.project(p)?;
        let inside = |c: f32| (0.0..self.size as f32).contains(&c);
        (inside(u) && inside(v)).then(|| self.at(u as u32, v as u32))
    }

    /// The points of every pixel whose ray hit a surface, row by row.
    pub(crate) fn surface_points(&self) -> impl Iterator<Item = Vector> + '_ {
        self.points
            .iter()
            .zip(&self.hit)
            .filter(|(_, &hit)| hit)
            .map(|(&p, _)| p)
    }
}
