//! Deterministic CPU renderer: RGB, optical-axis depth and an object-id mask per pixel.
//!
//! Rays are cast through pixel centres with the analytic intersections of
//! [`crate::vision::raycast`]. To stay fast without an acceleration structure, each primitive (and
//! each mesh triangle) only casts rays for the pixels inside the image rectangle its
//! bounding box projects to, and a depth buffer keeps the nearest hit. Ray directions are
//! scaled to unit optical-axis depth, so every ray parameter *is* the depth.
use std::sync::Arc;

use rapier3d::math::{Pose, Rotation as Quat, Vector as Vec3};

use crate::vision::camera::Camera;
use crate::vision::raycast::{self, Hit};

/// Background colour where no surface is hit (a light sky blue).
pub(crate) const SKY_RGB: [u8; 3] = [200, 222, 245];

/// Fraction of the albedo that is lit regardless of orientation.
pub(crate) const AMBIENT: f32 = 0.35;

/// Direction towards the single directional light (world frame, not normalised).
pub(crate) const LIGHT_TOWARDS: [f32; 3] = [0.3, -0.2, 1.0];

/// Geometry of a drawable, in its local frame.
#[derive(Debug, Clone)]
pub enum Shape {
    /// Box spanning `[-half_extents, half_extents]`.
    Cuboid {
        /// Half side lengths along local x, y, z.
        half_extents: Vec3,
    },
    /// Sphere centred on the local origin.
    Sphere {
        /// Radius in metres.
        radius: f32,
    },
    /// Capped cylinder around local Y (parry's convention), `|y| <= half_height`.
    Cylinder {
        /// Radius in metres.
        radius: f32,
        /// Half the length along local Y.
        half_height: f32,
    },
    /// Capsule around the local-Y segment from `-half_height` to `+half_height`.
    Capsule {
        /// Radius in metres.
        radius: f32,
        /// Half the length of the inner segment (excluding the end caps).
        half_height: f32,
    },
    /// Triangle mesh in local coordinates; winding is not relied upon.
    Mesh(Arc<TriMesh>),
}

/// An indexed triangle mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct TriMesh {
    /// Vertex positions in the mesh's local frame.
    pub vertices: Vec<Vec3>,
    /// Vertex indices of each triangle; triangles with an out-of-range index are skipped.
    pub triangles: Vec<[u32; 3]>,
}

/// One thing to draw.
#[derive(Debug, Clone)]
pub struct Drawable {
    /// Geometry in the local frame.
    pub shape: Shape,
    /// Local-to-world pose.
    pub pose: Pose,
    /// Albedo, each channel in 0..=1.
    pub color: [f32; 3],
    /// Written to [`Frame::mask`]: 0 for background and static scenery, > 0 for objects.
    pub id: u16,
}

/// A rendered image with per-pixel depth and object ids, all row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub(crate) width: u32,
    /// Height in pixels.
    pub(crate) height: u32,
    /// Interleaved 8-bit RGB, `3 · width · height` bytes.
    pub(crate) rgb: Vec<u8>,
    /// Depth along the optical axis in metres; the camera's `far` where nothing is hit.
    pub(crate) depth: Vec<f32>,
    /// [`Drawable::id`] of the visible surface; 0 where nothing is hit.
    pub mask: Vec<u16>,
}

/// Renders `scene` as seen by `camera`.
///
/// A pure function of its inputs. The nearest hit with depth in `[near, far)` wins; on an
/// exact depth tie the larger `(id, colour)` wins, so the result does not depend on the
/// order of `scene`.
pub fn render(camera: &Camera, scene: &[Drawable]) -> Frame {
    render_impl(camera, scene, true)
}

/// The pixels of a scene's unchanging part (the floor, the totes, the pedestal), rendered once so
/// that each later frame casts rays only for what moves: the floor alone covers nearly every
/// pixel, and recasting it took most of a recorded frame's time.
#[derive(Clone)]
pub(crate) struct Backdrop {
    target: Target,
}

impl Backdrop {
    /// `still` as seen by `camera`.
    pub(crate) fn new(camera: &Camera, still: &[Drawable]) -> Self {
        let view = View::new(camera);
        let mut target = Target::new(camera);
        draw_all(&view, &mut target, still, true);
        Self { target }
    }
}

/// The colours of `moving` rendered over a backdrop made with the same camera: those of
/// [`render`] of the backdrop's drawables followed by `moving`, because drawing continues from
/// the very buffers that rendering the backdrop's drawables first would have left.
pub(crate) fn render_rgb_over(
    camera: &Camera,
    backdrop: &Backdrop,
    moving: &[Drawable],
) -> image::RgbImage {
    let view = View::new(camera);
    let mut target = backdrop.target.clone();
    draw_all(&view, &mut target, moving, true);
    image::RgbImage::from_raw(camera.width, camera.height, target.rgb.into_flattened())
        .expect("rgb buffer length matches the camera's size")
}

/// Casts one world-space ray against a single drawable; `t` is in multiples of `dir` and
/// the normal is in world coordinates.
///
/// Meshes are tested triangle by triangle (no acceleration structure), and their normal
/// faces the ray origin.
#[cfg(test)]
pub(crate) fn cast_ray(
    drawable: &Drawable,
    origin: Vec3,
    dir: Vec3,
    tmin: f32,
    tmax: f32,
) -> Option<Hit> {
    let (o, d) = raycast::ray_to_local(&drawable.pose, origin, dir);
    let hit = match &drawable.shape {
        Shape::Cuboid { half_extents } => raycast::ray_cuboid(o, d, *half_extents, tmin, tmax),
        Shape::Sphere { radius } => raycast::ray_sphere(o, d, *radius, tmin, tmax),
        Shape::Cylinder {
            radius,
            half_height,
        } => raycast::ray_cylinder(o, d, *radius, *half_height, tmin, tmax),
        Shape::Capsule {
            radius,
            half_height,
        } => raycast::ray_capsule(o, d, *radius, *half_height, tmin, tmax),
        Shape::Mesh(mesh) => {
            let mut best: Option<Hit> = None;
            for tri in &mesh.triangles {
                let Some(corners) = triangle_vertices(&mesh.vertices, tri) else {
                    continue;
                };
                let limit = best.map_or(tmax, |b| b.t);
                if let Some(h) = raycast::ray_triangle(o, d, corners, tmin, limit) {
                    if best.is_none_or(|b| h.t < b.t) {
                        best = Some(h);
                    }
                }
            }
            best
        }
    }?;
    Some(Hit {
        t: hit.t,
        normal: drawable.pose.rotation * hit.normal,
    })
}

impl Frame {
    /// Depth in metres at pixel `(u, v)`. Panics if the pixel is outside the image.
    pub(crate) fn depth_at(&self, u: u32, v: u32) -> f32 {
        self.depth[self.index(u, v)]
    }

    /// Drawable id at pixel `(u, v)`. Panics if the pixel is outside the image.
    pub(crate) fn id_at(&self, u: u32, v: u32) -> u16 {
        self.mask[self.index(u, v)]
    }

    /// RGB colour at pixel `(u, v)`. Panics if the pixel is outside the image.
    #[cfg(test)]
    pub(crate) fn rgb_at(&self, u: u32, v: u32) -> [u8; 3] {
        let i = 3 * self.index(u, v);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    fn index(&self, u: u32, v: u32) -> usize {
        assert!(
            u < self.width && v < self.height,
            "pixel ({u}, {v}) outside {}x{} frame",
            self.width,
            self.height
        );
        v as usize * self.width as usize + u as usize
    }

    /// The colour image.
    pub fn to_rgb_image(&self) -> image::RgbImage {
        image::RgbImage::from_raw(self.width, self.height, self.rgb.clone())
            .expect("rgb buffer length matches the frame size")
    }

    /// Depth as 16-bit millimetres: `round(depth · 1000)`, saturating to 0..=65535
    /// (NaN becomes 0).
    pub fn to_depth_image_mm(&self) -> image::ImageBuffer<image::Luma<u16>, Vec<u16>> {
        // `as` from float to integer saturates and maps NaN to 0, which is the contract.
        let mm = self
            .depth
            .iter()
            .map(|d| (d * 1000.0).round() as u16)
            .collect();
        image::ImageBuffer::from_raw(self.width, self.height, mm)
            .expect("depth buffer length matches the frame size")
    }
}

fn triangle_vertices(vertices: &[Vec3], tri: &[u32; 3]) -> Option<[Vec3; 3]> {
    Some([
        *vertices.get(tri[0] as usize)?,
        *vertices.get(tri[1] as usize)?,
        *vertices.get(tri[2] as usize)?,
    ])
}

/// Slack around projected rectangles, in pixels. Far above the rounding error of the
/// projection (~1e-5 px), yet small enough that a sub-pixel mesh triangle usually casts a
/// single ray rather than a 3 × 3 block.
const RECT_MARGIN_PX: f32 = 0.05;

/// Inclusive range of pixels to cast rays for.
#[derive(Debug, Clone, Copy)]
struct PixelRect {
    u0: usize,
    u1: usize,
    v0: usize,
    v1: usize,
}

/// Per-frame constants shared by all drawables.
struct View<'a> {
    camera: &'a Camera,
    world_to_camera: Pose,
    /// Camera-frame ray x (resp. y) component at unit depth for each column (resp. row).
    ray_x: Vec<f32>,
    ray_y: Vec<f32>,
    light_world: Vec3,
    /// `None` when the image has no pixels.
    full: Option<PixelRect>,
}

impl<'a> View<'a> {
    fn new(camera: &'a Camera) -> Self {
        let (w, h) = (camera.width as usize, camera.height as usize);
        let ray_x = (0..w)
            .map(|u| (u as f32 + 0.5 - camera.cx) / camera.fx)
            .collect();
        let ray_y = (0..h)
            .map(|v| (v as f32 + 0.5 - camera.cy) / camera.fy)
            .collect();
        let full = (w > 0 && h > 0).then(|| PixelRect {
            u0: 0,
            u1: w - 1,
            v0: 0,
            v1: h - 1,
        });
        Self {
            camera,
            world_to_camera: camera.pose.inverse(),
            ray_x,
            ray_y,
            light_world: Vec3::from_array(LIGHT_TOWARDS).normalize(),
            full,
        }
    }

    /// Pixels whose centres may see the convex hull of `points` (camera frame), or `None`
    /// if that hull cannot be visible at all.
    fn rect_of(&self, points: impl IntoIterator<Item = Vec3>) -> Option<PixelRect> {
        let cam = self.camera;
        let full = self.full?;
        let (mut umin, mut umax) = (f32::INFINITY, f32::NEG_INFINITY);
        let (mut vmin, mut vmax) = (f32::INFINITY, f32::NEG_INFINITY);
        let (mut any_behind, mut all_behind, mut all_beyond) = (false, true, true);
        for p in points {
            if !p.is_finite() {
                return Some(full);
            }
            all_beyond &= p.z >= cam.far;
            if p.z <= cam.near {
                any_behind = true;
                continue;
            }
            all_behind = false;
            let u = cam.fx * p.x / p.z + cam.cx;
            let v = cam.fy * p.y / p.z + cam.cy;
            umin = umin.min(u);
            umax = umax.max(u);
            vmin = vmin.min(v);
            vmax = vmax.max(v);
        }
        // The hull lies entirely before the near plane or at/after the far depth.
        if all_behind || all_beyond {
            return None;
        }
        // Straddling the near plane, the projection is unbounded.
        if any_behind {
            return Some(full);
        }
        // Pixel u is needed when its centre u + 0.5 lies in [umin, umax].
        let (u0, u1) = pixel_span(umin, umax, cam.width)?;
        let (v0, v1) = pixel_span(vmin, vmax, cam.height)?;
        Some(PixelRect { u0, u1, v0, v1 })
    }
}

fn pixel_span(lo: f32, hi: f32, size: u32) -> Option<(usize, usize)> {
    let first = (lo - 0.5 - RECT_MARGIN_PX).ceil().max(0.0);
    let last = (hi - 0.5 + RECT_MARGIN_PX).floor().min(size as f32 - 1.0);
    // Also false for NaN bounds, which then draw nothing.
    if first <= last {
        Some((first as usize, last as usize))
    } else {
        None
    }
}

/// Depth, id and colour buffers being filled.
#[derive(Clone)]
struct Target {
    width: usize,
    near: f32,
    far: f32,
    depth: Vec<f32>,
    mask: Vec<u16>,
    rgb: Vec<[u8; 3]>,
}

impl Target {
    fn new(camera: &Camera) -> Self {
        let n = camera.width as usize * camera.height as usize;
        Self {
            width: camera.width as usize,
            near: camera.near,
            far: camera.far,
            depth: vec![camera.far; n],
            mask: vec![0; n],
            rgb: vec![SKY_RGB; n],
        }
    }

    /// Depth test; colour is only computed for surviving hits.
    fn offer(&mut self, idx: usize, t: f32, id: u16, rgb: impl FnOnce() -> [u8; 3]) {
        let current = self.depth[idx];
        if !(t < self.far && t <= current) {
            return;
        }
        let rgb = rgb();
        // Exact ties (coplanar faces) are broken on content so drawing order cannot matter.
        if t < current || (id, rgb) > (self.mask[idx], self.rgb[idx]) {
            self.depth[idx] = t;
            self.mask[idx] = id;
            self.rgb[idx] = rgb;
        }
    }

    fn into_frame(self, camera: &Camera) -> Frame {
        Frame {
            width: camera.width,
            height: camera.height,
            rgb: self.rgb.into_flattened(),
            depth: self.depth,
            mask: self.mask,
        }
    }
}

/// Lambert shading with ambient; `cos_light` is the cosine between normal and light.
fn shade(albedo: [f32; 3], cos_light: f32) -> [u8; 3] {
    let k = AMBIENT + (1.0 - AMBIENT) * cos_light.max(0.0);
    albedo.map(|c| ((c * k).clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// `cull = false` casts every pixel for every primitive; it exists so tests can check
/// that culling never changes the image.
fn render_impl(camera: &Camera, scene: &[Drawable], cull: bool) -> Frame {
    let view = View::new(camera);
    let mut target = Target::new(camera);
    draw_all(&view, &mut target, scene, cull);
    target.into_frame(camera)
}

/// Draws `scene` into `target`, in order.
fn draw_all(view: &View, target: &mut Target, scene: &[Drawable], cull: bool) {
    for drawable in scene {
        match &drawable.shape {
            Shape::Cuboid { half_extents } => {
                let h = *half_extents;
                draw_primitive(view, target, drawable, h, cull, |o, d, t0, t1| {
                    raycast::ray_cuboid(o, d, h, t0, t1)
                });
            }
            Shape::Sphere { radius } => {
                let r = *radius;
                draw_primitive(
                    view,
                    target,
                    drawable,
                    Vec3::splat(r),
                    cull,
                    |o, d, t0, t1| raycast::ray_sphere(o, d, r, t0, t1),
                );
            }
            Shape::Cylinder {
                radius,
                half_height,
            } => {
                let (r, hh) = (*radius, *half_height);
                let half = Vec3::new(r, hh, r);
                draw_primitive(view, target, drawable, half, cull, |o, d, t0, t1| {
                    raycast::ray_cylinder(o, d, r, hh, t0, t1)
                });
            }
            Shape::Capsule {
                radius,
                half_height,
            } => {
                let (r, hh) = (*radius, *half_height);
                let half = Vec3::new(r, hh + r, r);
                draw_primitive(view, target, drawable, half, cull, |o, d, t0, t1| {
                    raycast::ray_capsule(o, d, r, hh, t0, t1)
                });
            }
            Shape::Mesh(mesh) => draw_mesh(view, target, drawable, mesh, cull),
        }
    }
}

/// Casts the pixels covered by a primitive's projected local bounding box `[-half, half]`,
/// intersecting in the primitive's local frame.
fn draw_primitive(
    view: &View,
    target: &mut Target,
    drawable: &Drawable,
    half: Vec3,
    cull: bool,
    intersect: impl Fn(Vec3, Vec3, f32, f32) -> Option<Hit>,
) {
    let to_camera = view.world_to_camera * drawable.pose;
    let rect = if cull {
        let corners = (0..8).map(|i| {
            let sign = |bit: u32| if i & bit == 0 { -1.0 } else { 1.0 };
            to_camera.transform_point(half * Vec3::new(sign(1), sign(2), sign(4)))
        });
        view.rect_of(corners)
    } else {
        view.full
    };
    let Some(rect) = rect else {
        return;
    };
    // Camera axes and the light expressed in the local frame: a pixel's local ray is then
    // two multiply-adds away, and shading needs no per-pixel rotation.
    let camera_to_local: Quat = drawable.pose.rotation.inverse() * view.camera.pose.rotation;
    let axis_x = camera_to_local * Vec3::X;
    let axis_y = camera_to_local * Vec3::Y;
    let axis_z = camera_to_local * Vec3::Z;
    let origin = drawable
        .pose
        .inverse_transform_point(view.camera.pose.translation);
    let light = drawable.pose.rotation.inverse() * view.light_world;
    let near = target.near;
    for v in rect.v0..=rect.v1 {
        let row_dir = axis_z + axis_y * view.ray_y[v];
        let row = v * target.width;
        for u in rect.u0..=rect.u1 {
            let dir = row_dir + axis_x * view.ray_x[u];
            let idx = row + u;
            if let Some(hit) = intersect(origin, dir, near, target.depth[idx]) {
                target.offer(idx, hit.t, drawable.id, || {
                    shade(drawable.color, hit.normal.dot(light))
                });
            }
        }
    }
}

/// Casts each triangle over its own projected rectangle, in the camera frame (ray origin 0).
fn draw_mesh(view: &View, target: &mut Target, drawable: &Drawable, mesh: &TriMesh, cull: bool) {
    let to_camera = view.world_to_camera * drawable.pose;
    let verts: Vec<Vec3> = mesh
        .vertices
        .iter()
        .map(|&p| to_camera.transform_point(p))
        .collect();
    if cull && view.rect_of(verts.iter().copied()).is_none() {
        return;
    }
    let light = view.world_to_camera.rotation * view.light_world;
    let near = target.near;
    for tri in &mesh.triangles {
        let Some(corners) = triangle_vertices(&verts, tri) else {
            continue;
        };
        let rect = if cull {
            view.rect_of(corners)
        } else {
            view.full
        };
        let Some(rect) = rect else {
            continue;
        };
        // Flat shading: one colour per triangle, with the normal turned towards the camera
        // (winding is unknown; the visible side of a closed mesh faces the camera).
        // Computed on the first hit only: most triangles of a dense mesh are occluded.
        let mut rgb = None;
        let mut triangle_rgb = || {
            *rgb.get_or_insert_with(|| {
                let mut normal = (corners[1] - corners[0])
                    .cross(corners[2] - corners[0])
                    .normalize_or_zero();
                if normal.dot(corners[0]) > 0.0 {
                    normal = -normal;
                }
                shade(drawable.color, normal.dot(light))
            })
        };
        for v in rect.v0..=rect.v1 {
            let row = v * target.width;
            for u in rect.u0..=rect.u1 {
                let dir = Vec3::new(view.ray_x[u], view.ray_y[v], 1.0);
                let idx = row + u;
                if let Some(hit) =
                    raycast::ray_triangle(Vec3::ZERO, dir, corners, near, target.depth[idx])
                {
                    target.offer(idx, hit.t, drawable.id, &mut triangle_rgb);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[allow(clippy::approx_constant)]
    const EYE_Z: f32 = 0.70711;

    fn cuboid(half: Vec3, pose: Pose, id: u16) -> Drawable {
        Drawable {
            shape: Shape::Cuboid { half_extents: half },
            pose,
            color: [0.8, 0.3, 0.2],
            id,
        }
    }

    fn at(x: f32, y: f32, z: f32) -> Pose {
        Pose::from_translation(Vec3::new(x, y, z))
    }

    /// Convex hull (counter-clockwise in (u, v)) by Andrew's monotone chain.
    fn convex_hull(mut pts: Vec<[f32; 2]>) -> Vec<[f32; 2]> {
        pts.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let cross = |o: [f32; 2], a: [f32; 2], b: [f32; 2]| {
            (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
        };
        let mut hull: Vec<[f32; 2]> = Vec::new();
        for pass in 0..2 {
            let start = hull.len();
            let iter: Box<dyn Iterator<Item = &[f32; 2]>> = if pass == 0 {
                Box::new(pts.iter())
            } else {
                Box::new(pts.iter().rev())
            };
            for &p in iter {
                while hull.len() >= start + 2
                    && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
                {
                    hull.pop();
                }
                hull.push(p);
            }
            hull.pop();
        }
        hull
    }

    /// Signed distance from `p` to the convex polygon: positive inside.
    fn hull_signed_distance(hull: &[[f32; 2]], p: [f32; 2]) -> f32 {
        let mut inside = true;
        let mut min_edge = f32::INFINITY;
        for i in 0..hull.len() {
            let a = hull[i];
            let b = hull[(i + 1) % hull.len()];
            let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
            let (px, py) = (p[0] - a[0], p[1] - a[1]);
            let len2 = ex * ex + ey * ey;
            if ex * py - ey * px < 0.0 {
                inside = false;
            }
            let s = ((px * ex + py * ey) / len2).clamp(0.0, 1.0);
            let (dx, dy) = (px - s * ex, py - s * ey);
            min_edge = min_edge.min((dx * dx + dy * dy).sqrt());
        }
        if inside {
            min_edge
        } else {
            -min_edge
        }
    }

    #[test]
    fn rotated_box_silhouette_is_projected_hull() {
        let cam = Camera::top_down();
        let half = Vec3::new(0.05, 0.08, 0.03);
        let pose = Pose::from_parts(Vec3::new(0.52, -0.03, 0.03), Quat::from_rotation_z(0.3));
        let frame = render(&cam, &[cuboid(half, pose, 7)]);
        let corners: Vec<[f32; 2]> = (0..8)
            .map(|i| {
                let s = |bit: u32| if i & bit == 0 { -1.0 } else { 1.0 };
                let p = pose.transform_point(half * Vec3::new(s(1), s(2), s(4)));
                let [u, v, _] = cam.project(p).unwrap();
                [u, v]
            })
            .collect();
        let hull = convex_hull(corners);
        assert!(hull.len() >= 4);
        let (mut inside, mut deep) = (0, 0);
        for v in 0..cam.height {
            for u in 0..cam.width {
                let sd = hull_signed_distance(&hull, [u as f32 + 0.5, v as f32 + 0.5]);
                let id = frame.id_at(u, v);
                assert!(id == 0 || id == 7);
                if id == 7 {
                    inside += 1;
                    assert!(
                        sd >= -0.5,
                        "mask pixel ({u},{v}) is {sd} px outside the hull"
                    );
                } else {
                    assert_eq!(frame.depth_at(u, v), cam.far);
                    assert_eq!(frame.rgb_at(u, v), SKY_RGB);
                }
                if sd > 0.5 {
                    deep += 1;
                    assert_eq!(
                        id, 7,
                        "pixel ({u},{v}) {sd} px inside the hull is not in the mask"
                    );
                }
            }
        }
        assert!(
            deep > 100 && inside >= deep,
            "{deep} deep, {inside} in mask"
        );
    }

    #[test]
    fn box_top_depth_and_back_projection() {
        let cam = Camera::top_down();
        let (centre, half) = (Vec3::new(0.55, 0.02, 0.05), Vec3::new(0.1, 0.08, 0.05));
        let frame = render(&cam, &[cuboid(half, Pose::from_translation(centre), 3)]);
        let top_z = 0.1;
        let want_depth = EYE_Z - top_z;
        let mut seen = 0;
        for v in 0..cam.height {
            for u in 0..cam.width {
                // Where this pixel's ray meets the plane of the top face (the camera formula).
                let on_plane = cam.pixel_to_world(u, v, want_depth);
                let local = on_plane - centre;
                if local.x.abs() < half.x && local.y.abs() < half.y {
                    seen += 1;
                    assert_eq!(frame.id_at(u, v), 3);
                    let d = frame.depth_at(u, v);
                    assert!((d - want_depth).abs() < 1e-3, "({u},{v}) depth {d}");
                    let p = cam.pixel_to_world(u, v, d);
                    assert!((p.z - top_z).abs() < 2e-3);
                    let l = p - centre;
                    assert!(
                        l.x.abs() < half.x + 2e-3 && l.y.abs() < half.y + 2e-3,
                        "{p}"
                    );
                }
            }
        }
        assert!(seen > 400, "only {seen} pixels see the top face");
        // Straight below the eye, the pixel sees the top face; far outside there is nothing.
        assert!((frame.depth_at(64, 64) - want_depth).abs() < 1e-3);
        assert_eq!((frame.id_at(0, 0), frame.depth_at(0, 0)), (0, cam.far));
    }

    fn stacked_scene() -> Vec<Drawable> {
        let mut big = cuboid(Vec3::new(0.1, 0.1, 0.05), at(0.5, 0.0, 0.05), 1);
        big.color = [0.2, 0.6, 0.2];
        let small = cuboid(Vec3::new(0.03, 0.03, 0.03), at(0.5, 0.0, 0.13), 2);
        let ball = Drawable {
            shape: Shape::Sphere { radius: 0.03 },
            pose: at(0.55, 0.06, 0.13),
            color: [0.1, 0.1, 0.9],
            id: 3,
        };
        let can = Drawable {
            shape: Shape::Cylinder {
                radius: 0.025,
                half_height: 0.04,
            },
            pose: Pose::from_parts(Vec3::new(0.45, -0.06, 0.14), Quat::from_rotation_x(1.2)),
            color: [0.9, 0.9, 0.1],
            id: 4,
        };
        let ground = cuboid(Vec3::new(1.0, 1.0, 0.01), at(0.5, 0.0, -0.01), 0);
        vec![ground, big, small, ball, can]
    }

    #[test]
    fn occlusion_and_order_independence() {
        let cam = Camera::top_down();
        let scene = stacked_scene();
        let frame = render(&cam, &scene);
        assert_eq!(
            frame.id_at(64, 64),
            2,
            "small box on top wins at the centre"
        );
        assert!((frame.depth_at(64, 64) - (EYE_Z - 0.16)).abs() < 1e-4);
        // Over the big box but away from the small one and the others.
        let [u, v, _] = cam.project(Vec3::new(0.58, -0.08, 0.1)).unwrap();
        assert_eq!(frame.id_at(u as u32, v as u32), 1);
        let [u, v, _] = cam.project(Vec3::new(0.55, 0.06, 0.16)).unwrap();
        assert_eq!(frame.id_at(u as u32, v as u32), 3, "sphere top");
        assert!((frame.depth_at(u as u32, v as u32) - (EYE_Z - 0.16)).abs() < 2e-3);
        let [u, v, _] = cam.project(Vec3::new(0.3, -0.45, 0.0)).unwrap();
        assert_eq!(frame.id_at(u as u32, v as u32), 0, "ground");
        assert!((frame.depth_at(u as u32, v as u32) - EYE_Z).abs() < 1e-4);
        for id in 0..=4 {
            assert!(frame.mask.contains(&id), "id {id} not visible");
        }
        let mut reversed = scene.clone();
        reversed.reverse();
        assert!(
            render(&cam, &reversed) == frame,
            "drawing order changed the frame"
        );
        // Any permutation, also with an exactly coplanar duplicate of different id.
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let mut shuffled = scene.clone();
        let mut twin = scene[2].clone();
        twin.id = 9;
        shuffled.push(twin);
        let reference = render(&cam, &shuffled);
        assert_eq!(
            reference.id_at(64, 64),
            9,
            "exact tie goes to the larger id"
        );
        for _ in 0..5 {
            for i in (1..shuffled.len()).rev() {
                shuffled.swap(i, rng.random_range(0..=i));
            }
            assert!(render(&cam, &shuffled) == reference);
        }
    }

    #[test]
    fn rendering_is_deterministic_and_depth_png_rounds() {
        let cam = Camera::top_down();
        let scene = stacked_scene();
        let a = render(&cam, &scene);
        let b = render(&cam, &scene);
        assert!(a == b);
        assert_eq!(a.rgb.len(), 3 * 128 * 128);
        let img = a.to_depth_image_mm();
        assert_eq!(img.dimensions(), (128, 128));
        for v in 0..128 {
            for u in 0..128 {
                let want = (a.depth_at(u, v) * 1000.0).round() as u16;
                assert_eq!(img.get_pixel(u, v).0[0], want);
            }
        }
        let rgb = a.to_rgb_image();
        assert_eq!(rgb.get_pixel(5, 7).0, a.rgb_at(5, 7));
        // Saturation and degenerate values.
        let odd = Frame {
            width: 4,
            height: 1,
            rgb: vec![0; 12],
            depth: vec![70.0, -1.0, f32::NAN, 0.0014],
            mask: vec![0; 4],
        };
        let px: Vec<u16> = odd.to_depth_image_mm().pixels().map(|p| p.0[0]).collect();
        assert_eq!(px, vec![65535, 0, 0, 1]);
    }

    #[test]
    fn save_helpers_write_readable_pngs() {
        let cam = Camera::look_at(
            Vec3::new(1.0, 0.5, 0.8),
            Vec3::new(0.5, 0.0, 0.0),
            Vec3::Z,
            60.0,
            40,
            30,
        );
        let frame = render(&cam, &stacked_scene());
        let dir = std::env::temp_dir().join(format!("render-save-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let rgb_path = dir.join("rgb.png");
        let depth_path = dir.join("depth.png");
        crate::data::atomic::save_image_atomic(&frame.to_rgb_image(), &rgb_path).unwrap();
        crate::data::atomic::save_image_atomic(&frame.to_depth_image_mm(), &depth_path).unwrap();
        let rgb = image::open(&rgb_path).unwrap().into_rgb8();
        let depth = image::open(&depth_path).unwrap().into_luma16();
        let leftovers = std::fs::read_dir(&dir).unwrap().count();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(rgb == frame.to_rgb_image());
        assert!(depth == frame.to_depth_image_mm());
        assert_eq!(leftovers, 2, "temporary files left behind");
    }

    fn random_pose(rng: &mut ChaCha8Rng, spread: f32) -> Pose {
        let axis = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize_or(Vec3::Z);
        Pose::from_parts(
            Vec3::new(
                0.5 + rng.random_range(-spread..spread),
                rng.random_range(-spread..spread),
                rng.random_range(0.0..spread),
            ),
            Quat::from_axis_angle(axis, rng.random_range(0.0..std::f32::consts::TAU)),
        )
    }

    fn random_scene(rng: &mut ChaCha8Rng, n: usize, spread: f32) -> Vec<Drawable> {
        (0..n)
            .map(|i| {
                let s = |rng: &mut ChaCha8Rng| rng.random_range(0.01..0.08f32);
                let shape = match i % 5 {
                    0 => Shape::Cuboid {
                        half_extents: Vec3::new(s(rng), s(rng), s(rng)),
                    },
                    1 => Shape::Sphere { radius: s(rng) },
                    2 => Shape::Cylinder {
                        radius: s(rng),
                        half_height: s(rng),
                    },
                    3 => Shape::Capsule {
                        radius: s(rng),
                        half_height: s(rng),
                    },
                    _ => Shape::Mesh(Arc::new(uv_sphere(s(rng), 6, 8))),
                };
                Drawable {
                    shape,
                    pose: random_pose(rng, spread),
                    color: [rng.random(), rng.random(), rng.random()],
                    id: i as u16 + 1,
                }
            })
            .collect()
    }

    #[test]
    fn culling_never_changes_the_image() {
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let top = Camera::top_down();
        // Oblique and close cameras put shapes partly off-screen, straddling the near
        // plane, behind the eye, or beyond far.
        let oblique = Camera::look_at(
            Vec3::new(0.9, -0.5, 0.35),
            Vec3::new(0.5, 0.0, 0.05),
            Vec3::Z,
            70.0,
            96,
            72,
        );
        let mut close = Camera::look_at(
            Vec3::new(0.5, 0.0, 0.12),
            Vec3::new(0.55, 0.05, 0.0),
            Vec3::Z,
            90.0,
            64,
            64,
        );
        close.near = 0.05;
        close.far = 0.3;
        for cam in [top, oblique, close] {
            for _ in 0..4 {
                let scene = random_scene(&mut rng, 25, 0.4);
                let culled = render(&cam, &scene);
                let brute = render_impl(&cam, &scene, false);
                assert!(culled == brute, "culling changed the image");
                assert!(culled.mask.iter().any(|&m| m != 0));
            }
        }
    }

    #[test]
    fn frame_agrees_with_per_pixel_cast_ray() {
        let mut rng = ChaCha8Rng::seed_from_u64(22);
        let cam = Camera::look_at(
            Vec3::new(0.9, -0.5, 0.6),
            Vec3::new(0.5, 0.0, 0.05),
            Vec3::Z,
            60.0,
            64,
            48,
        );
        let scene = random_scene(&mut rng, 20, 0.25);
        let frame = render(&cam, &scene);
        let mut disagree = 0;
        for v in 0..cam.height {
            for u in 0..cam.width {
                let dir = cam.pose.rotation
                    * Vec3::new(
                        (u as f32 + 0.5 - cam.cx) / cam.fx,
                        (v as f32 + 0.5 - cam.cy) / cam.fy,
                        1.0,
                    );
                let best = scene
                    .iter()
                    .filter_map(|d| {
                        cast_ray(d, cam.eye(), dir, cam.near, cam.far).map(|h| (h.t, d.id))
                    })
                    .min_by(|a, b| a.0.total_cmp(&b.0));
                let (t, id) = best.unwrap_or((cam.far, 0));
                if id != frame.id_at(u, v) {
                    disagree += 1;
                } else {
                    assert!((t - frame.depth_at(u, v)).abs() < 1e-5);
                }
            }
        }
        // Only pixels on a near-exact tie between two surfaces may differ.
        assert!(disagree <= 3, "{disagree} pixels disagree");
    }

    /// Closed box mesh with outward (or, when `flip`, inward) winding.
    fn box_mesh(h: Vec3, flip: bool) -> TriMesh {
        let vertices = (0..8)
            .map(|i| {
                let s = |bit: u32| if i & bit == 0 { -1.0 } else { 1.0 };
                h * Vec3::new(s(1), s(2), s(4))
            })
            .collect();
        let quads = [
            [0, 2, 6, 4],
            [1, 5, 7, 3],
            [0, 4, 5, 1],
            [2, 3, 7, 6],
            [0, 1, 3, 2],
            [4, 6, 7, 5],
        ];
        let mut triangles = Vec::new();
        for q in quads {
            triangles.push([q[0], q[1], q[2]]);
            triangles.push([q[0], q[2], q[3]]);
        }
        if flip {
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }
        TriMesh {
            vertices,
            triangles,
        }
    }

    fn uv_sphere(r: f32, stacks: u32, slices: u32) -> TriMesh {
        let mut vertices = Vec::new();
        for i in 0..=stacks {
            let theta = std::f32::consts::PI * i as f32 / stacks as f32;
            for j in 0..slices {
                let phi = std::f32::consts::TAU * j as f32 / slices as f32;
                vertices.push(
                    r * Vec3::new(
                        theta.sin() * phi.cos(),
                        theta.sin() * phi.sin(),
                        theta.cos(),
                    ),
                );
            }
        }
        let mut triangles = Vec::new();
        for i in 0..stacks {
            for j in 0..slices {
                let a = i * slices + j;
                let b = i * slices + (j + 1) % slices;
                let c = a + slices;
                let d = b + slices;
                triangles.push([a, c, b]);
                triangles.push([b, c, d]);
            }
        }
        TriMesh {
            vertices,
            triangles,
        }
    }

    #[test]
    fn mesh_box_renders_like_the_cuboid() {
        let half = Vec3::new(0.06, 0.04, 0.05);
        let pose = Pose::from_parts(
            Vec3::new(0.47, 0.05, 0.08),
            Quat::from_rotation_z(0.4) * Quat::from_rotation_x(0.3),
        );
        let cams = [
            Camera::top_down(),
            Camera::look_at(
                Vec3::new(0.9, -0.4, 0.5),
                Vec3::new(0.5, 0.0, 0.05),
                Vec3::Z,
                50.0,
                80,
                60,
            ),
        ];
        for cam in cams {
            let analytic = render(&cam, &[cuboid(half, pose, 5)]);
            for flip in [false, true] {
                let mesh = Drawable {
                    shape: Shape::Mesh(Arc::new(box_mesh(half, flip))),
                    pose,
                    color: [0.8, 0.3, 0.2],
                    id: 5,
                };
                let meshed = render(&cam, std::slice::from_ref(&mesh));
                let mut differ = 0;
                for i in 0..meshed.mask.len() {
                    if meshed.mask[i] != analytic.mask[i] {
                        differ += 1;
                        continue;
                    }
                    assert!((meshed.depth[i] - analytic.depth[i]).abs() < 1e-5);
                    for c in 0..3 {
                        let (a, b) = (meshed.rgb[3 * i + c], analytic.rgb[3 * i + c]);
                        assert!(a.abs_diff(b) <= 1, "colour {a} vs {b} (flip {flip})");
                    }
                }
                assert!(differ <= 2, "{differ} silhouette pixels differ");
                assert!(meshed.mask.iter().filter(|&&m| m == 5).count() > 100);
                // The world-space ray query agrees on the centre pixel.
                let dir = cam.ray_direction(cam.cx, cam.cy);
                let a = cast_ray(&mesh, cam.eye(), dir, 0.0, 10.0).map(|h| h.t);
                let b = cast_ray(&cuboid(half, pose, 5), cam.eye(), dir, 0.0, 10.0).map(|h| h.t);
                assert_eq!(a.is_some(), b.is_some());
                if let (Some(a), Some(b)) = (a, b) {
                    assert!((a - b).abs() < 1e-5);
                }
            }
        }
    }

    #[test]
    fn mesh_tolerates_bad_indices_and_near_plane_straddling() {
        let mut mesh = box_mesh(Vec3::splat(0.05), false);
        mesh.triangles.push([0, 1, 99]);
        let cam = Camera::top_down();
        let d = Drawable {
            shape: Shape::Mesh(Arc::new(mesh)),
            pose: at(0.5, 0.0, 0.05),
            color: [1.0; 3],
            id: 1,
        };
        let frame = render(&cam, std::slice::from_ref(&d));
        assert_eq!(frame.id_at(64, 64), 1);
        // A huge floor triangle passing under and behind the camera.
        let floor = TriMesh {
            vertices: vec![
                Vec3::new(-5.0, -5.0, 0.0),
                Vec3::new(5.0, -5.0, 0.0),
                Vec3::new(0.0, 5.0, 0.0),
            ],
            triangles: vec![[0, 1, 2]],
        };
        let cam = Camera::look_at(
            Vec3::new(0.0, -3.0, 0.3),
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::Z,
            60.0,
            32,
            32,
        );
        let d = Drawable {
            shape: Shape::Mesh(Arc::new(floor)),
            pose: Pose::IDENTITY,
            color: [1.0; 3],
            id: 2,
        };
        let frame = render(&cam, std::slice::from_ref(&d));
        assert!(frame == render_impl(&cam, std::slice::from_ref(&d), false));
        assert_eq!(frame.id_at(16, 31), 2);
    }

    #[test]
    fn shading_is_lambert_with_ambient() {
        let cam = Camera::top_down();
        let white = Drawable {
            shape: Shape::Cuboid {
                half_extents: Vec3::splat(0.1),
            },
            pose: at(0.5, 0.0, 0.0),
            color: [1.0, 0.5, 0.0],
            id: 1,
        };
        let frame = render(&cam, &[white]);
        let l = Vec3::from_array(LIGHT_TOWARDS).normalize();
        let k = AMBIENT + (1.0 - AMBIENT) * l.z;
        let want = [(255.0 * k).round() as u8, (127.5 * k).round() as u8, 0];
        assert_eq!(frame.rgb_at(64, 64), want);
        assert_eq!(frame.rgb_at(0, 0), SKY_RGB);
        // A face turned away from the light gets ambient only.
        assert_eq!(shade([1.0, 1.0, 1.0], -0.5), [89, 89, 89]);
        assert_eq!(shade([2.0, 0.0, 1.0], 1.0), [255, 0, 255]);
    }

    #[test]
    fn empty_inputs() {
        let cam = Camera::top_down();
        let frame = render(&cam, &[]);
        assert!(frame.mask.iter().all(|&m| m == 0) && frame.depth.iter().all(|&d| d == cam.far));
        let mut tiny = cam;
        tiny.width = 0;
        let frame = render(&tiny, &stacked_scene());
        assert!(frame.rgb.is_empty() && frame.depth.is_empty());
    }

    /// The workcell-like scene of the speed target: ground, two totes of 5 boxes, an arm of
    /// 10 capsules/cylinders and objects of 1–6 primitives (61 primitives in all).
    fn workcell_scene() -> Vec<Drawable> {
        let mut rng = ChaCha8Rng::seed_from_u64(77);
        let mut scene = vec![cuboid(Vec3::new(1.0, 1.0, 0.01), at(0.5, 0.0, -0.01), 0)];
        for y in [-0.22f32, 0.22] {
            let (hx, hy, hz, wall) = (0.15, 0.12, 0.05, 0.005);
            scene.push(cuboid(Vec3::new(hx, hy, wall), at(0.5, y, wall), 0));
            scene.push(cuboid(Vec3::new(wall, hy, hz), at(0.5 - hx, y, hz), 0));
            scene.push(cuboid(Vec3::new(wall, hy, hz), at(0.5 + hx, y, hz), 0));
            scene.push(cuboid(Vec3::new(hx, wall, hz), at(0.5, y - hy, hz), 0));
            scene.push(cuboid(Vec3::new(hx, wall, hz), at(0.5, y + hy, hz), 0));
        }
        for i in 0..10 {
            let a = i as f32 * 0.35;
            let pose = Pose::from_parts(
                Vec3::new(
                    0.1 + 0.04 * i as f32,
                    0.3 * a.sin() * 0.3,
                    0.45 - 0.02 * i as f32,
                ),
                Quat::from_rotation_x(a) * Quat::from_rotation_z(0.3 * a),
            );
            let shape = if i % 2 == 0 {
                Shape::Capsule {
                    radius: 0.04,
                    half_height: 0.1,
                }
            } else {
                Shape::Cylinder {
                    radius: 0.045,
                    half_height: 0.06,
                }
            };
            scene.push(Drawable {
                shape,
                pose,
                color: [0.7, 0.7, 0.75],
                id: 0,
            });
        }
        let mut id = 1;
        let mut sizes = [1usize, 2, 3, 4, 5, 6, 6, 5, 4, 3, 2, 1, 3, 2, 1].into_iter();
        while scene.len() < 61 {
            let n = sizes.next().unwrap_or(1).min(61 - scene.len());
            let base = random_pose(&mut rng, 0.12);
            let base = Pose::from_parts(
                Vec3::new(
                    base.translation.x,
                    if id % 2 == 0 { 0.22 } else { -0.22 } + base.translation.y * 0.5,
                    0.04,
                ),
                base.rotation,
            );
            for k in 0..n {
                let offset =
                    Pose::from_translation(Vec3::new(0.02 * k as f32, 0.0, 0.01 * k as f32));
                let shape = match k % 4 {
                    0 => Shape::Cuboid {
                        half_extents: Vec3::new(0.03, 0.02, 0.015),
                    },
                    1 => Shape::Sphere { radius: 0.02 },
                    2 => Shape::Cylinder {
                        radius: 0.015,
                        half_height: 0.03,
                    },
                    _ => Shape::Capsule {
                        radius: 0.012,
                        half_height: 0.025,
                    },
                };
                scene.push(Drawable {
                    shape,
                    pose: base * offset,
                    color: [rng.random(), rng.random(), rng.random()],
                    id,
                });
            }
            id += 1;
        }
        scene
    }

    #[test]
    fn workcell_scene_looks_sane() {
        let scene = workcell_scene();
        assert_eq!(scene.len(), 61);
        let frame = render(&Camera::top_down(), &scene);
        let objects = frame.mask.iter().filter(|&&m| m > 0).count();
        assert!(objects > 200, "{objects} object pixels");
        assert!(frame.depth.iter().all(|&d| d > 0.2 && d <= EYE_Z + 1e-4));
    }
}
