//! Which grasps collide before they close: the open gripper entering a tote wall (known box) or landing on a surface the depth image shows.
//!
//! The network never saw a wall or a neighbour up close (labels come from single objects
//! dropped near the bin's middle), so in clutter it happily scores grasps whose fingers would
//! come down on a wall or on another object, and the arm's protective stop ends them. Deployed
//! grasping systems check candidate grasps against the tote model and the depth image before
//! executing; this module builds that mask from the camera's depth and the tote's known box
//! only: no object identities, no ground-truth masks.

use rapier3d::math::Vector;

use super::heights::HeightMap;

use crate::grasp::gripper::GripperGeometry;
use crate::grasp::rotate::rotate_point;
use crate::grasp::tote::Tote;
use crate::grasp::world::{world_grasp, WorldGrasp};
use crate::grasp::{bin_angle, PixelGrasp, BINS};
use crate::named::named_enum;
use crate::vision::camera::Camera;
use crate::vision::render::Frame;

/// The gripper's volume below tool0, as boxes around the TCP.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub(crate) struct GripperVolume {
    /// Distance between the open pads' inner faces (m).
    pub(crate) opening: f32,
    /// Finger thickness along the closing line (m).
    pub(crate) finger_thickness: f32,
    /// Finger width across the closing line (m).
    pub(crate) finger_width: f32,
    /// Height of the palm's lower face above the TCP (m).
    pub(crate) palm_height: f32,
    /// Palm half extent along the closing line (m).
    pub(crate) palm_half_along: f32,
    /// Palm half extent across the closing line (m).
    pub(crate) palm_half_across: f32,
    /// Clearance kept from the walls (m).
    pub(crate) margin: f32,
}

/// Clearance the collision check keeps from the tote's walls (m).
pub(crate) const WALL_MARGIN: f32 = 0.005;

impl From<&GripperGeometry> for GripperVolume {
    fn from(g: &GripperGeometry) -> Self {
        Self {
            opening: g.max_opening,
            finger_thickness: g.pad_thickness,
            finger_width: g.pad_width,
            palm_height: g.palm_height(),
            palm_half_along: g.palm_half_along,
            palm_half_across: g.palm_half_across,
            margin: WALL_MARGIN,
        }
    }
}

/// True when the open gripper, lowered to this grasp, stays clear of the tote's walls: every
/// box of it either lies inside the inner floor area or starts above the wall tops.
pub(crate) fn clears_walls(grasp: &WorldGrasp, tote: &Tote, gripper: &GripperVolume) -> bool {
    let along = Vector::new(grasp.closing.x, grasp.closing.y, 0.0).normalize_or_zero();
    let across = Vector::new(-along.y, along.x, 0.0);
    let finger_offset = gripper.opening / 2.0 + gripper.finger_thickness / 2.0;
    // (centre offset along the closing line, half along, half across, bottom above the TCP)
    let boxes = [
        (
            -finger_offset,
            gripper.finger_thickness / 2.0,
            gripper.finger_width / 2.0,
            0.0,
        ),
        (
            finger_offset,
            gripper.finger_thickness / 2.0,
            gripper.finger_width / 2.0,
            0.0,
        ),
        (
            0.0,
            gripper.palm_half_along,
            gripper.palm_half_across,
            gripper.palm_height,
        ),
    ];
    boxes
        .iter()
        .all(|&(offset, half_along, half_across, bottom)| {
            if grasp.tcp.z + bottom > tote.wall_top + gripper.margin {
                return true;
            }
            let centre = grasp.tcp + along * offset;
            [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)]
                .iter()
                .all(|&(sa, sc): &(f32, f32)| {
                    let corner = centre + along * (sa * half_along) + across * (sc * half_across);
                    (corner.x - tote.center[0]).abs() <= tote.inner_half[0] - gripper.margin
                        && (corner.y - tote.center[1]).abs() <= tote.inner_half[1] - gripper.margin
                })
        })
}

named_enum! {
    /// How strictly candidate grasps are checked before the argmax.
    pub enum CollisionCheck {
        /// Walls; the fingers and palm against the surfaces in the depth image; and the grasp
        /// centre on something, not on bare floor.
        Full = "full", "walls, the surfaces in the depth image, and no grasp on bare floor",
        /// Only the tote's walls.
        Walls = "walls", "only the tote's walls",
        /// None: the reference's plain argmax.
        Off = "off", "none: the reference's plain argmax",
    }
}

/// How far above the TCP a seen surface under a finger may be (m): the depth image's noise-free
/// but 8 mm pixels blur edges by about this much.
pub(crate) const LANDING_TOLERANCE: f32 = 0.005;

/// A grasp centre whose surface is lower than this above the tote floor is on bare floor, where
/// the pads can only close on the edge of whatever lies beside it (m).
pub(crate) const ON_OBJECT_HEIGHT: f32 = 0.005;

/// True when, lowered to the grasp, neither finger nor the palm would come down on a surface
/// the camera sees: under each finger's footprint nothing rises above the TCP (plus
/// [`LANDING_TOLERANCE`]), under the palm nothing above its lower face.
pub(crate) fn lands_clear(
    grasp: &WorldGrasp,
    heights: &HeightMap,
    camera: &Camera,
    gripper: &GripperVolume,
) -> bool {
    let along = Vector::new(grasp.closing.x, grasp.closing.y, 0.0).normalize_or_zero();
    let across = Vector::new(-along.y, along.x, 0.0);
    let finger_offset = gripper.opening / 2.0 + gripper.finger_thickness / 2.0;
    let blocked = |point: Vector, limit: f32| {
        heights
            .under(camera, point)
            .is_some_and(|h| h > limit + LANDING_TOLERANCE)
    };
    for side in [-1.0f32, 1.0] {
        for i in [-1.0f32, 0.0, 1.0] {
            for j in [-1.0f32, 0.0, 1.0] {
                let point = grasp.tcp
                    + along * (side * finger_offset + i * gripper.finger_thickness / 2.0)
                    + across * (j * gripper.finger_width / 2.0);
                if blocked(point, grasp.tcp.z) {
                    return false;
                }
            }
        }
    }
    let palm_bottom = grasp.tcp.z + gripper.palm_height;
    for i in [-1.0f32, -0.5, 0.0, 0.5, 1.0] {
        for j in [-1.0f32, 0.0, 1.0] {
            let point = grasp.tcp
                + along * (i * gripper.palm_half_along)
                + across * (j * gripper.palm_half_across);
            if blocked(point, palm_bottom) {
                return false;
            }
        }
    }
    true
}

/// For each bin and rotated pixel, whether the grasp it stands for is allowed: its original
/// pixel lies in the image (not in the black fill of the rotation) and it passes `check`
/// (for `Full`: the walls, [`lands_clear`], and a centre above [`ON_OBJECT_HEIGHT`]).
/// Same layout as [`crate::model::maps::AffordanceMaps`].
pub(crate) fn allowed_actions(
    camera: &Camera,
    frame: &Frame,
    heights: &HeightMap,
    tote: &Tote,
    gripper: &GripperVolume,
    check: CollisionCheck,
) -> Vec<bool> {
    let full = check == CollisionCheck::Full;
    let size = frame.width;
    debug_assert_eq!(frame.width, frame.height);
    let mut allowed = Vec::with_capacity(BINS * (size * size) as usize);
    for bin in 0..BINS {
        for v in 0..size {
            for u in 0..size {
                let [x, y] = rotate_point([u as f32 + 0.5, v as f32 + 0.5], bin_angle(bin), size);
                let inside = (0.0..size as f32).contains(&x) && (0.0..size as f32).contains(&y);
                allowed.push(
                    inside && {
                        let grasp = PixelGrasp {
                            u: x as u32,
                            v: y as u32,
                            angle_deg: bin_angle(bin),
                        };
                        grasp_allowed(
                            camera,
                            frame,
                            full.then_some(heights),
                            tote,
                            gripper,
                            check,
                            grasp,
                        )
                    },
                );
            }
        }
    }
    allowed
}

/// Whether one grasp passes `check`; `heights` is needed (and only used) for `Full`.
fn grasp_allowed(
    camera: &Camera,
    frame: &Frame,
    heights: Option<&HeightMap>,
    tote: &Tote,
    gripper: &GripperVolume,
    check: CollisionCheck,
    grasp: PixelGrasp,
) -> bool {
    if check == CollisionCheck::Off {
        return true;
    }
    let world = world_grasp(camera, frame, grasp);
    let on_floor =
        heights.is_some_and(|h| h.at(grasp.u, grasp.v) < tote.floor_top + ON_OBJECT_HEIGHT);
    !on_floor
        && clears_walls(&world, tote, gripper)
        && heights.is_none_or(|h| lands_clear(&world, h, camera, gripper))
}

/// The longest surface, measured across the closing line, on which a grasp is centred (m):
/// a box's long side (the YCB boxes and cans are at most 104 mm) and a pixel of blur at each end. A longer one is a long part (a handle, a bottle), where the
/// network's spot along it is kept.
pub(crate) const CENTRING_SPAN: f32 = 0.13;

/// Step of the walk along the surface when centring (m): a quarter of a pixel on the floor.
const CENTRING_STEP: f32 = 0.002;

/// What the depth-based grasp checks look at: the camera, its frame and the heights it shows,
/// the pick tote and the open gripper.
#[derive(Clone, Copy)]
pub(crate) struct GraspSite<'a> {
    /// The top-down camera.
    pub(crate) camera: &'a Camera,
    /// Its frame.
    pub(crate) frame: &'a Frame,
    /// The frame's heights ([`HeightMap::new`]).
    pub(crate) heights: &'a HeightMap,
    /// The pick tote.
    pub(crate) tote: &'a Tote,
    /// The open gripper's volume.
    pub(crate) gripper: &'a GripperVolume,
}

impl GraspSite<'_> {
    /// Whether the grasp passes the `Full` collision check.
    pub(crate) fn allows(&self, grasp: PixelGrasp) -> bool {
        grasp_allowed(
            self.camera,
            self.frame,
            Some(self.heights),
            self.tote,
            self.gripper,
            CollisionCheck::Full,
            grasp,
        )
    }

    /// Moves a chosen grasp to the middle of the surface the pads would close on, judged from the
    /// depth image alone; `score` gives the network's (suppressed, collision-checked) score of a
    /// grasp, 0 where it is not allowed. `None` when the surface's middle cannot be grasped.
    ///
    /// The network places its peak on the right object but often near a box's end or corner: the
    /// 22 mm pads then catch a corner, and the squeeze spins a light box out of the jaw. So:
    /// 1. From the grasp centre, the surface that rises above the TCP is followed both ways along
    ///    the closing line (a run up to the open jaw) and across it (up to [`CENTRING_SPAN`]);
    ///    the centre moves to the middle of each run that fits ([`GraspSite::centred`]). If
    ///    that grasp passes the `Full` collision check, it is the one. With nothing above the
    ///    TCP at the centre, the grasp is kept as it is.
    /// 2. Otherwise the jaw, at this angle, does not fit across the middle (a box seen along its
    ///    diagonal or long side): of the 8 angles at that middle, each centred again, the allowed
    ///    one the network scores highest is taken.
    /// 3. If none is allowed, the grasp only fits at a corner or an end: `None`.
    pub(crate) fn refine(
        &self,
        grasp: PixelGrasp,
        score: impl Fn(PixelGrasp) -> f32,
    ) -> Option<PixelGrasp> {
        let Some(middle) = self.centred(grasp) else {
            return Some(grasp);
        };
        if self.allows(middle) {
            return Some(middle);
        }
        (0..BINS)
            .map(|bin| PixelGrasp {
                angle_deg: bin_angle(bin),
                ..middle
            })
            .map(|g| self.centred(g).unwrap_or(g))
            .filter(|&g| self.allows(g))
            .map(|g| (score(g), g))
            .filter(|&(s, _)| s > 0.0)
            .fold(None, |best: Option<(f32, PixelGrasp)>, (s, g)| match best {
                Some((b, _)) if b >= s => best,
                _ => Some((s, g)),
            })
            .map(|(_, g)| g)
    }

    /// The grasp, at its angle, moved to the middle of the surface above its TCP along and across
    /// the closing line, where each run fits (see [`GraspSite::refine`]); `None` when nothing rises above
    /// the TCP at its centre or the middle falls outside the image.
    pub(crate) fn centred(&self, grasp: PixelGrasp) -> Option<PixelGrasp> {
        let Self {
            camera,
            frame,
            heights,
            tote,
            gripper,
        } = *self;
        let world = world_grasp(camera, frame, grasp);
        let grip_level = (world.tcp.z + LANDING_TOLERANCE).max(tote.floor_top + ON_OBJECT_HEIGHT);
        let solid = |p: Vector| heights.under(camera, p).is_some_and(|h| h > grip_level);
        if !solid(world.tcp) {
            return None;
        }
        let along = Vector::new(world.closing.x, world.closing.y, 0.0).normalize_or_zero();
        let across = Vector::new(-along.y, along.x, 0.0);
        // Distance to the surface's edge in `direction`, or None when it runs past `limit`.
        let edge = |direction: Vector, limit: f32| {
            let steps = (limit / CENTRING_STEP).ceil() as u32;
            (1..=steps)
                .map(|i| i as f32 * CENTRING_STEP)
                .find(|&s| !solid(world.tcp + direction * s))
        };
        // The offset to the middle of the run through the centre, if the whole run is within `span`.
        let middle =
            |direction: Vector, span: f32| match (edge(-direction, span), edge(direction, span)) {
                (Some(minus), Some(plus)) if minus + plus <= span => (plus - minus) / 2.0,
                _ => 0.0,
            };
        let shift = along * middle(along, gripper.opening) + across * middle(across, CENTRING_SPAN);
        // Projected at the height of the surface seen at the grasp, so that an unmoved grasp maps
        // back to its own pixel.
        let target = world.tcp + shift;
        let surface = Vector::new(target.x, target.y, heights.at(grasp.u, grasp.v));
        let [u, v, _] = camera.project(surface)?;
        let size = frame.width as f32;
        ((0.0..size).contains(&u) && (0.0..size).contains(&v)).then_some(PixelGrasp {
            u: u as u32,
            v: v as u32,
            angle_deg: grasp.angle_deg,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasp::gripper::GRIPPER;
    use crate::grasp::tote::PICK_TOTE;
    use crate::policy::synthetic::{block_frame, floor_frame};

    fn grasp(x: f32, y: f32, z: f32, closing: Vector) -> WorldGrasp {
        WorldGrasp {
            tcp: Vector::new(x, y, z),
            closing,
        }
    }

    #[test]
    fn the_gripper_clears_walls_in_the_middle_and_above_them_but_not_beside_them() {
        let gripper = GripperVolume::from(&GRIPPER);
        let t = PICK_TOTE;
        assert!(clears_walls(
            &grasp(0.5, 0.0, 0.03, Vector::X),
            &t,
            &gripper
        ));
        // 3 cm from the +x wall: closing along x puts a finger into it, and closing along y
        // the palm's 3.5 cm half width across does not fit either.
        let near = 0.8 - 0.03;
        assert!(!clears_walls(
            &grasp(near, 0.0, 0.03, Vector::X),
            &t,
            &gripper
        ));
        assert!(!clears_walls(
            &grasp(near, 0.0, 0.03, Vector::Y),
            &t,
            &gripper
        ));
        // 6 cm away, closing along the wall: fingers 1.1 cm and palm 3.5 cm across fit.
        let off = 0.8 - 0.06;
        assert!(clears_walls(
            &grasp(off, 0.0, 0.03, Vector::Y),
            &t,
            &gripper
        ));
        assert!(!clears_walls(
            &grasp(off, 0.0, 0.03, Vector::X),
            &t,
            &gripper
        ));
        // On a tall object the fingers end above the wall tops.
        assert!(clears_walls(
            &grasp(near, 0.0, 0.25, Vector::X),
            &t,
            &gripper
        ));
    }

    #[test]
    fn full_checks_allow_a_free_standing_block_and_nothing_on_bare_floor() {
        let camera = Camera::top_down();
        let gripper = GripperVolume::from(&GRIPPER);
        let allowed = |frame: &Frame| {
            allowed_actions(
                &camera,
                frame,
                &HeightMap::new(&camera, frame),
                &PICK_TOTE,
                &gripper,
                CollisionCheck::Full,
            )
        };
        assert!(!allowed(&floor_frame(&camera, None)).iter().any(|&a| a));
        // A 3 × 3 px (about 26 mm) block fits between the pads at every angle.
        let block = allowed(&floor_frame(&camera, Some(1)));
        let plane = 128 * 128;
        for bin in 0..BINS {
            let [x, y] = rotate_point([64.5, 64.5], -bin_angle(bin), 128);
            assert!(
                block[bin * plane + y as usize * 128 + x as usize],
                "bin {bin}"
            );
        }
        // A 21 px (18 cm) block is wider than the jaw: its centre is never a grasp.
        let wide = allowed(&floor_frame(&camera, Some(10)));
        assert!((0..BINS).all(|bin| !wide[bin * plane + 64 * 128 + 64]));
    }

    #[test]
    fn pixels_rotated_in_from_outside_the_image_are_never_allowed() {
        let camera = Camera::top_down();
        let frame = floor_frame(&camera, None);
        let allowed = allowed_actions(
            &camera,
            &frame,
            &HeightMap::new(&camera, &frame),
            &PICK_TOTE,
            &GripperVolume::from(&GRIPPER),
            CollisionCheck::Walls,
        );
        let plane = 128 * 128;
        // Bin 2 (45°): the rotated image's corner comes from outside the original.
        assert!(!allowed[2 * plane]);
        assert!(allowed.iter().any(|&a| a));
        assert!(allowed[..plane].iter().filter(|&&a| a).count() > plane / 4);
    }

    /// The refined grasp, with a network that likes every allowed grasp equally.
    fn refined(frame: &Frame, grasp: PixelGrasp) -> PixelGrasp {
        let camera = Camera::top_down();
        let heights = HeightMap::new(&camera, frame);
        let gripper = GripperVolume::from(&GRIPPER);
        let tote = PICK_TOTE;
        let site = GraspSite {
            camera: &camera,
            frame,
            heights: &heights,
            tote: &tote,
            gripper: &gripper,
        };
        site.refine(grasp, |_| 0.5).expect("graspable")
    }

    #[test]
    fn a_grasp_near_a_box_end_moves_to_the_middle_of_the_box() {
        let camera = Camera::top_down();
        // A 9 × 11 px box (about 75 × 90 mm at its top): grasps across its short side, at its
        // end (5 px off across the closing line) and 2 px off along it.
        let frame = block_frame(&camera, Some([4, 5]));
        for (u, v, angle_deg) in [(64, 68, 0.0), (64, 60, 0.0), (66, 69, 0.0), (62, 60, 0.0)] {
            let g = refined(&frame, PixelGrasp { u, v, angle_deg });
            assert_eq!(g.angle_deg, angle_deg);
            assert!(
                g.u.abs_diff(64) <= 1 && g.v.abs_diff(64) <= 1,
                "({u}, {v}) went to ({}, {})",
                g.u,
                g.v
            );
        }
        // At 90° the jaw closes along the rows, so the columns are centred across it.
        let g = refined(
            &frame,
            PixelGrasp {
                u: 61,
                v: 64,
                angle_deg: 90.0,
            },
        );
        assert!(g.u.abs_diff(64) <= 1 && g.v.abs_diff(64) <= 1, "{g:?}");
    }

    #[test]
    fn a_grasp_across_a_box_diagonal_turns_to_the_box_sides() {
        // A 5 cm tall box standing at 45° to the image axes (|du| + |dv| ≤ 5 px): across the
        // image axes it is 11 px (about 92 mm) wide, wider than the jaw; across its sides about
        // 65 mm. A grasp at 0° near its top corner fits only there, where the pads would catch
        // the corner; refined, it closes across the sides at the middle.
        let camera = Camera::top_down();
        let mut frame = floor_frame(&camera, None);
        let eye = camera.eye();
        for v in 0..128u32 {
            for u in 0..128u32 {
                if u.abs_diff(64) + v.abs_diff(64) <= 5 {
                    let far = camera.pixel_to_world(u, v, 1.0);
                    frame.depth[(v * 128 + u) as usize] = (eye.z - 0.07) / (eye.z - far.z);
                }
            }
        }
        let heights = HeightMap::new(&camera, &frame);
        let gripper = GripperVolume::from(&GRIPPER);
        let corner = PixelGrasp {
            u: 64,
            v: 60,
            angle_deg: 0.0,
        };
        // Of the angles that fit at the middle, the one the network likes best.
        let likes_135 = |g: PixelGrasp| if g.angle_deg == 135.0 { 0.9 } else { 0.1 };
        let tote = PICK_TOTE;
        let site = GraspSite {
            camera: &camera,
            frame: &frame,
            heights: &heights,
            tote: &tote,
            gripper: &gripper,
        };
        let g = site
            .refine(corner, likes_135)
            .expect("the box fits across its sides");
        assert_eq!(g.angle_deg, 135.0);
        assert!(g.u.abs_diff(64) <= 1 && g.v.abs_diff(64) <= 1, "{g:?}");
        // Across the diagonals (0° and 90°) it never fits at the middle.
        let g = refined(&frame, corner);
        assert!(g.angle_deg != 0.0 && g.angle_deg != 90.0, "{g:?}");
        assert!(g.u.abs_diff(64) <= 1 && g.v.abs_diff(64) <= 1, "{g:?}");
        // If the network scores none of the fitting angles, the corner grasp is refused.
        let refused = site.refine(corner, |_| 0.0);
        assert_eq!(refused, None);
    }

    #[test]
    fn a_long_part_keeps_the_spot_along_it_and_bare_floor_is_left_alone() {
        let camera = Camera::top_down();
        // A 3 × 41 px bar (about 2.5 × 35 cm): closing across it, the grasp is near one end and
        // stays there; only the small offset along the closing line is removed.
        let frame = block_frame(&camera, Some([1, 20]));
        let g = refined(
            &frame,
            PixelGrasp {
                u: 65,
                v: 50,
                angle_deg: 0.0,
            },
        );
        assert_eq!((g.u, g.v), (64, 50));
        // Nothing under the centre: nothing to centre on.
        let floor = floor_frame(&camera, None);
        let at = PixelGrasp {
            u: 30,
            v: 40,
            angle_deg: 45.0,
        };
        assert_eq!(refined(&floor, at), at);
    }
}
