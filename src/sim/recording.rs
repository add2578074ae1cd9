//! Filming the workcell for `--record`: snapshots of the scene taken every few physics steps,
//! rendered from the oblique view on another thread so that the physics never waits for them.

use std::sync::mpsc::Sender;
use std::sync::Arc;

use image::RgbImage;

use crate::vision::camera::Camera;
use crate::vision::render::{render_rgb_over, Backdrop, Drawable, Shape};
use rapier3d::math::Vector;

/// The oblique view of the whole workcell that recordings show.
pub fn oblique_camera() -> Camera {
    Camera::look_at(
        Vector::new(1.35, -1.25, 1.25),
        Vector::new(0.0, 0.0, 0.25),
        Vector::Z,
        45.0,
        320,
        240,
    )
}

/// The scene at one instant: the scenery, shared between snapshots of the same workcell so
/// that it is rendered once, and everything that moves.
pub(crate) struct Snapshot {
    pub(crate) scenery: Arc<[Drawable]>,
    pub(crate) moving: Vec<Drawable>,
}

/// What a recording receives, in order.
pub(crate) enum Footage {
    /// A frame's scene.
    Scene(Snapshot),
    /// The picture shown beside the oblique view in the frames that follow (eval's episode
    /// video shows the camera view with its grasp).
    Inset(RgbImage),
}

/// Where a recording workcell sends its snapshots.
pub(crate) type FootageSender = Sender<Footage>;

/// Renders snapshots from the oblique view, reusing the scenery's pixels while the scenery
/// stays the same.
pub(crate) struct ObliqueFilm {
    camera: Camera,
    backdrop: Option<(Arc<[Drawable]>, Backdrop)>,
    /// The last frame, and the moving drawables it shows: a scene at rest is not drawn again.
    last: Option<(Vec<Drawable>, RgbImage)>,
}

impl ObliqueFilm {
    pub(crate) fn new() -> Self {
        Self {
            camera: oblique_camera(),
            backdrop: None,
            last: None,
        }
    }

    /// The height of its frames (px).
    pub(crate) fn height(&self) -> u32 {
        self.camera.height
    }

    /// The oblique view of `snapshot`: the pixels [`crate::vision::render::render`] gives for
    /// the scenery followed by the moving drawables.
    pub(crate) fn frame(&mut self, snapshot: &Snapshot) -> RgbImage {
        let stale = !self
            .backdrop
            .as_ref()
            .is_some_and(|(scenery, _)| Arc::ptr_eq(scenery, &snapshot.scenery));
        if stale {
            self.backdrop = None;
            self.last = None;
        }
        if let Some((moving, frame)) = &self.last {
            let same = moving.len() == snapshot.moving.len()
                && moving
                    .iter()
                    .zip(&snapshot.moving)
                    .all(|(a, b)| identical(a, b));
            if same {
                return frame.clone();
            }
        }
        let (_, backdrop) = self.backdrop.get_or_insert_with(|| {
            let backdrop = Backdrop::new(&self.camera, &snapshot.scenery);
            (snapshot.scenery.clone(), backdrop)
        });
        let frame = render_rgb_over(&self.camera, backdrop, &snapshot.moving);
        self.last = Some((snapshot.moving.clone(), frame.clone()));
        frame
    }
}

/// Whether two drawables are bit for bit the same, so that rendering is sure to draw them
/// alike (a mesh: the same one, not merely equal vertices, which would take longer to compare
/// than to draw).
fn identical(a: &Drawable, b: &Drawable) -> bool {
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<u32>>();
    let same_shape = match (&a.shape, &b.shape) {
        (Shape::Mesh(m), Shape::Mesh(n)) => Arc::ptr_eq(m, n),
        (Shape::Cuboid { half_extents: h }, Shape::Cuboid { half_extents: k }) => {
            bits(&h.to_array()) == bits(&k.to_array())
        }
        (Shape::Sphere { radius: r }, Shape::Sphere { radius: s }) => r.to_bits() == s.to_bits(),
        (
            Shape::Cylinder {
                radius: r,
                half_height: h,
            },
            Shape::Cylinder {
                radius: s,
                half_height: k,
            },
        )
        | (
            Shape::Capsule {
                radius: r,
                half_height: h,
            },
            Shape::Capsule {
                radius: s,
                half_height: k,
            },
        ) => bits(&[*r, *h]) == bits(&[*s, *k]),
        _ => false,
    };
    same_shape
        && a.id == b.id
        && bits(&a.color) == bits(&b.color)
        && bits(&a.pose.translation.to_array()) == bits(&b.pose.translation.to_array())
        && bits(&a.pose.rotation.to_array()) == bits(&b.pose.rotation.to_array())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{Workcell, WorkcellConfig};
    use crate::vision::render::render;

    #[test]
    fn a_film_frame_is_the_full_render_of_the_scene() {
        let library = crate::assets::objects::ObjectLibrary::bundled();
        let models = library.load_all(&["YcbMustardBottle".into(), "YcbHammer".into()]);
        let mut cell = Workcell::new(&WorkcellConfig::default()).unwrap();
        cell.drop_objects(&models.unwrap(), 3).unwrap();
        let mut film = ObliqueFilm::new();
        for _ in 0..2 {
            // The second frame draws over the backdrop the first one made.
            let full = render(&oblique_camera(), &cell.drawables()).to_rgb_image();
            assert!(film.frame(&cell.snapshot()) == full);
            cell.hold_arm();
            for _ in 0..24 {
                cell.step();
            }
        }
        // A new workcell's scenery is a new backdrop, with the same pixels.
        let other = Workcell::new(&WorkcellConfig::default()).unwrap();
        let full = render(&oblique_camera(), &other.drawables()).to_rgb_image();
        assert!(film.frame(&other.snapshot()) == full);
    }
}
