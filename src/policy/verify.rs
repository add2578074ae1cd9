//! Verification (`eval --verify-top/--verify-floor/--verify-rejected`): the test of one
//! grasp on the depth image alone, which the oracle planner runs on every candidate and the
//! model policy runs on the network's best candidates before it executes one.
//!
//! On the 2.5-D height map the camera sees, a grasp passes when what lies between the open pads
//! fits the opening with a margin, both pads have free, visible space down to the TCP height,
//! the palm clears everything, and the pads squeeze a face square enough to hold. A grasp that
//! passes comes with its quality terms (clearance, off-centre squeeze, slant), which the planner
//! ranks by.

use rapier3d::math::Vector;

use super::heights::HeightMap;
use crate::grasp::gripper::GRIPPER;
use crate::grasp::world::{world_grasp, WorldGrasp};
use crate::grasp::PixelGrasp;
use crate::named::{named_enum, Named};
use crate::vision::camera::Camera;
use crate::vision::render::Frame;

/// Geometry of the jaw the planner plans for (defaults: the workcell's gripper) and how finely it searches.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CheckConfig {
    /// Distance between the open pads' inner faces (m).
    pub(crate) opening: f32,
    /// Pad width across the closing line (m).
    pub(crate) pad_width: f32,
    /// Pad thickness along the closing line (m).
    pub(crate) pad_thickness: f32,
    /// Pad height along the tool axis (m).
    pub(crate) pad_height: f32,
    /// Height of the palm's lower face above the TCP (m).
    pub(crate) palm_height: f32,
    /// Palm half extents along and across the closing line (m).
    pub(crate) palm_half_along: f32,
    /// Palm half extent across the closing line (m).
    pub(crate) palm_half_across: f32,
    /// Safety margin around the pads and the palm (m).
    pub(crate) margin: f32,
    /// Room kept inside the opening between what is squeezed and each open pad (m).
    pub(crate) squeeze_margin: f32,
    /// Largest shift of the squeezed outline across a pad's width (m); more is a slanted face.
    pub(crate) max_slant: f32,
    /// How many of a pad's three strips across its width (the outer quarters and the middle
    /// half) the squeezed part must reach: fewer lets the pads pivot the object out.
    pub(crate) strips: usize,
    /// Number of angles tried over 180°.
    pub(crate) angles: u32,
    /// Sampling step along and across the closing line (m).
    pub(crate) step: f32,
}

/// Clearance the planner keeps around the pads and inside the opening (m).
pub(crate) const PLANNING_MARGIN: f32 = 0.006;
/// Largest shift of the squeezed outline across a pad before a face counts as slanted (m).
pub(crate) const MAX_SLANT: f32 = 0.010;
/// The planner's (and labeller's) strips rule: two of three, so that a grasp near an object's
/// end still counts; the planner also knows the object's centroid and ranks by nearness to it.
pub(crate) const PLANNER_STRIPS: usize = 2;
/// Free space under the pads beyond this no longer raises a plan's score (m).
pub(crate) const CLEARANCE_THAT_COUNTS: f32 = 0.02;
/// Weight of an off-centre squeeze in a plan's score, against clearance and the distance to
/// the object's centroid (weight 1): a squeeze off the middle pushes the object sideways.
pub(crate) const ASYMMETRY_WEIGHT: f32 = 2.0;
/// Clearance reported for pads with nothing at all beneath them (m).
const CLEARANCE_CAP: f32 = 0.05;
/// How far above the TCP a surface between the pads must rise to be squeezed (m).
const SQUEEZE_LEVEL: f32 = 0.003;
/// How much nearer the camera a surface must be to hide a point behind it (m).
const OCCLUSION_TOLERANCE: f32 = 0.002;
/// Angles the planner tries over the half turn.
pub(crate) const PLANNED_ANGLES: u32 = 16;
/// Sampling step of the planner's point-cloud queries (m).
pub(crate) const SAMPLING_STEP: f32 = 0.002;

impl CheckConfig {
    /// The default planner on `angles` evenly spaced angles (8: the 22.5° steps a person
    /// turns the gripper in, which the scripted clicker and the browser test plan in).
    pub fn with_angles(angles: u32) -> Self {
        CheckConfig {
            angles,
            ..CheckConfig::default()
        }
    }
}

impl Default for CheckConfig {
    fn default() -> Self {
        Self {
            opening: GRIPPER.max_opening,
            pad_width: GRIPPER.pad_width,
            pad_thickness: GRIPPER.pad_thickness,
            pad_height: GRIPPER.pad_height,
            palm_height: GRIPPER.palm_height(),
            palm_half_along: GRIPPER.palm_half_along,
            palm_half_across: GRIPPER.palm_half_across,
            margin: PLANNING_MARGIN,
            squeeze_margin: PLANNING_MARGIN,
            max_slant: MAX_SLANT,
            strips: PLANNER_STRIPS,
            angles: PLANNED_ANGLES,
            step: SAMPLING_STEP,
        }
    }
}

/// A planned grasp with its quality terms.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Assessment {
    /// The grasp to click.
    pub grasp: PixelGrasp,
    /// Smallest height of free space under the pads' footprints (m), capped at 5 cm.
    pub(crate) clearance: f32,
    /// Distance from the grasp centre to the object's visible centroid (m).
    pub(crate) off_center: f32,
    /// How far the squeezed span's middle is from the grasp centre (m): the pads would
    /// push the object sideways by this much.
    pub(crate) asymmetry: f32,
    /// Object width along the closing line at pad height (m).
    pub width: f32,
    /// How much the squeezed outline shifts across a pad's width (m): 0 for faces square to the jaw.
    pub(crate) slant: f32,
}

/// Checks grasps the way the planner does, from the depth image alone: no mask, so the grasp
/// centre stands in for the object's centroid.
pub struct Verifier<'a> {
    camera: &'a Camera,
    frame: &'a Frame,
    cloud: Cloud,
    config: CheckConfig,
}

impl<'a> Verifier<'a> {
    /// Buckets the frame's height map once for many checks.
    pub fn new(
        camera: &'a Camera,
        frame: &'a Frame,
        heights: &HeightMap,
        config: CheckConfig,
    ) -> Self {
        Self {
            camera,
            frame,
            cloud: Cloud::new(heights),
            config,
        }
    }

    /// The planner's verdict on one grasp: its quality terms, or why it would be rejected.
    pub fn assess(&self, grasp: PixelGrasp) -> Result<Assessment, Rejection> {
        let centre = world_grasp(self.camera, self.frame, grasp).tcp;
        check_grasp(
            &self.cloud,
            self.camera,
            self.frame,
            grasp,
            centre,
            &self.config,
        )
    }
}

named_enum! {
    /// Why verification (and the planner) rejects a candidate grasp.
    pub enum Rejection {
        /// What lies between the pads at pad height does not fit the open jaw with the margin.
        TooWide = "too_wide", "wider than the opening",
        /// Something is in a pad's footprint above the TCP.
        PadBlocked = "pad_blocked", "no room for a pad",
        /// The camera cannot see down to the TCP in a pad's footprint.
        PadHidden = "pad_hidden", "a pad's footprint hidden from the camera",
        /// Something rises into the palm's volume.
        Palm = "palm", "palm would hit something",
        /// The jaw would close on air.
        NothingBetweenPads = "nothing_between_pads", "nothing between the pads",
        /// The squeezed part reaches fewer of a pad's strips than asked.
        Edge = "edge", "pads would only catch an edge",
        /// The squeezed outline shifts too much across a pad.
        Slanted = "slanted", "faces slanted to the jaw",
    }
}

impl Rejection {
    /// How many reasons there are.
    pub(crate) const COUNT: usize = <Self as Named>::ALL.len();
}

/// The camera's depth as a world point cloud, bucketed on a horizontal grid for box queries.
pub(crate) struct Cloud {
    min: [f32; 2],
    cell: f32,
    cols: usize,
    rows: usize,
    buckets: Vec<Vec<Vector>>,
}

impl Cloud {
    /// Buckets the surface points of a frame's height map.
    pub(crate) fn new(heights: &HeightMap) -> Self {
        Self::from_points(heights.surface_points().collect())
    }

    fn from_points(points: Vec<Vector>) -> Self {
        let (lo, hi) = points
            .iter()
            .fold(([f32::MAX; 2], [f32::MIN; 2]), |(lo, hi), p| {
                (
                    [lo[0].min(p.x), lo[1].min(p.y)],
                    [hi[0].max(p.x), hi[1].max(p.y)],
                )
            });
        let cell = 0.01;
        let cols = (((hi[0] - lo[0]) / cell) as usize + 1).max(1);
        let rows = (((hi[1] - lo[1]) / cell) as usize + 1).max(1);
        let mut cloud = Self {
            min: lo,
            cell,
            cols,
            rows,
            buckets: vec![Vec::new(); cols * rows],
        };
        for p in points {
            let (i, j) = cloud.cell_of(p.x, p.y);
            cloud.buckets[j * cols + i].push(p);
        }
        cloud
    }

    fn cell_of(&self, x: f32, y: f32) -> (usize, usize) {
        let i = ((x - self.min[0]) / self.cell).clamp(0.0, (self.cols - 1) as f32) as usize;
        let j = ((y - self.min[1]) / self.cell).clamp(0.0, (self.rows - 1) as f32) as usize;
        (i, j)
    }

    /// Points within `radius` (horizontally) of `center`.
    fn near(&self, center: Vector, radius: f32) -> impl Iterator<Item = Vector> + '_ {
        let (i0, j0) = self.cell_of(center.x - radius, center.y - radius);
        let (i1, j1) = self.cell_of(center.x + radius, center.y + radius);
        (j0..=j1).flat_map(move |j| {
            (i0..=i1).flat_map(move |i| self.buckets[j * self.cols + i].iter().copied())
        })
    }
}

/// Fraction of the pad height at which the pad footprint must be in view.
const OCCLUSION_PROBE: f32 = 1.0;

/// True when the camera sees a surface in front of `p` (or `p` is outside the image).
fn occluded(camera: &Camera, frame: &Frame, p: Vector) -> bool {
    let Some([u, v, depth]) = camera.project(p) else {
        return true;
    };
    if u < 0.0 || v < 0.0 || u >= frame.width as f32 || v >= frame.height as f32 {
        return true;
    }
    frame.depth_at(u as u32, v as u32) < depth - OCCLUSION_TOLERANCE
}

/// What the camera cannot see can still be in the way: a rounded side bulges out under the
/// edge it shows. So both pads' footprints must be in plain view at mid-pad height.
fn pads_in_view(camera: &Camera, frame: &Frame, target: &WorldGrasp, config: &CheckConfig) -> bool {
    let (tcp, along) = (target.tcp, target.closing);
    let across = Vector::new(-along.y, along.x, 0.0);
    let half_open = config.opening / 2.0;
    let pad_outer = half_open + config.pad_thickness + config.margin;
    let pad_half_width = config.pad_width / 2.0 + config.margin;
    let mid_pad = tcp.z + config.pad_height * OCCLUSION_PROBE;
    for side in [-1.0f32, 1.0] {
        let mut s = half_open;
        while s <= pad_outer {
            let mut w = -pad_half_width;
            while w <= pad_half_width {
                let p = tcp + along * (side * s) + across * w;
                if occluded(camera, frame, Vector::new(p.x, p.y, mid_pad)) {
                    return false;
                }
                w += config.step * 2.0;
            }
            s += config.step * 2.0;
        }
    }
    true
}

/// The planner's test of one grasp: its quality terms, or the first check it fails.
pub(crate) fn check_grasp(
    cloud: &Cloud,
    camera: &Camera,
    frame: &Frame,
    grasp: PixelGrasp,
    centroid: Vector,
    config: &CheckConfig,
) -> Result<Assessment, Rejection> {
    let target = world_grasp(camera, frame, grasp);
    let tcp = target.tcp;
    let jaw = Jaw::of(target.closing, config);
    let mut squeezed = Squeezed::new();
    for p in cloud.near(tcp, jaw.reach) {
        squeezed.add(&jaw, p, tcp, config)?;
    }
    let Squeezed {
        lo,
        hi,
        covered,
        clearance,
        ..
    } = squeezed;
    if lo > hi {
        return Err(Rejection::NothingBetweenPads);
    }
    // A grasp whose pads only catch the object's edge lets it pivot out.
    if covered.iter().filter(|&&c| c).count() < config.strips {
        return Err(Rejection::Edge);
    }
    if !pads_in_view(camera, frame, &target, config) {
        return Err(Rejection::PadHidden);
    }
    let slant = squeezed.slant(config);
    if slant > config.max_slant {
        return Err(Rejection::Slanted);
    }
    Ok(Assessment {
        grasp,
        clearance,
        slant,
        off_center: Vector::new(tcp.x - centroid.x, tcp.y - centroid.y, 0.0).length(),
        asymmetry: (lo + hi).abs() / 2.0,
        width: hi - lo,
    })
}

/// The open jaw of one grasp in the plane: its closing axis, the axis across it, and the
/// extents that [`Squeezed::add`] sorts the points by.
struct Jaw {
    along: Vector,
    across: Vector,
    half_open: f32,
    /// How far apart the squeezed part may reach, each side of the centre.
    limit: f32,
    pad_outer: f32,
    pad_half_width: f32,
    palm_half: [f32; 2],
    /// The radius around the tool centre point that holds every point the checks look at.
    reach: f32,
}

impl Jaw {
    fn of(along: Vector, config: &CheckConfig) -> Self {
        let half_open = config.opening / 2.0;
        let pad_outer = half_open + config.pad_thickness + config.margin;
        let pad_half_width = config.pad_width / 2.0 + config.margin;
        let palm_half = [
            config.palm_half_along + config.margin,
            config.palm_half_across + config.margin,
        ];
        Self {
            along,
            across: Vector::new(-along.y, along.x, 0.0),
            half_open,
            limit: half_open - config.squeeze_margin,
            pad_outer,
            pad_half_width,
            palm_half,
            reach: pad_outer.max(palm_half[0]) + pad_half_width.max(palm_half[1]),
        }
    }
}

/// What the points near a grasp say so far: the extent of the squeezed part along the jaw
/// (overall and per half of the pads' width), which strips of the pads it covers, and the
/// clearance under the pads.
struct Squeezed {
    lo: f32,
    hi: f32,
    covered: [bool; 3],
    side_lo: [f32; 2],
    side_hi: [f32; 2],
    clearance: f32,
}

impl Squeezed {
    fn new() -> Self {
        Self {
            lo: f32::MAX,
            hi: f32::MIN,
            covered: [false; 3],
            side_lo: [f32::MAX; 2],
            side_hi: [f32::MIN; 2],
            clearance: CLEARANCE_CAP,
        }
    }

    /// Adds the point `p` of the cloud near the tool centre point `tcp`, or the check it
    /// fails.
    fn add(
        &mut self,
        jaw: &Jaw,
        p: Vector,
        tcp: Vector,
        config: &CheckConfig,
    ) -> Result<(), Rejection> {
        let d = p - tcp;
        let s = d.dot(jaw.along);
        let signed_w = d.dot(jaw.across);
        let w = signed_w.abs();
        if s.abs() <= jaw.palm_half[0]
            && w <= jaw.palm_half[1]
            && p.z >= tcp.z + config.palm_height - config.margin
        {
            return Err(Rejection::Palm);
        }
        if w > jaw.pad_half_width || s.abs() > jaw.pad_outer {
            return Ok(());
        }
        // The margin beside a pad's inner corner belongs to the pad: the corner comes down
        // there, and a flank rising into it stopped the arm at 204 N on a mesh mustard bottle.
        let beside_inner_corner = s.abs() > jaw.limit && w > config.pad_width / 2.0;
        if s.abs() >= jaw.half_open || beside_inner_corner {
            // Under a pad: the surface must be below the pad's lower edge.
            if p.z >= tcp.z {
                return Err(Rejection::PadBlocked);
            }
            self.clearance = self.clearance.min(tcp.z - p.z);
        } else if w <= config.pad_width / 2.0 && p.z > tcp.z + SQUEEZE_LEVEL {
            // Between the pads at pad height: part of what will be squeezed.
            if s.abs() > jaw.limit {
                return Err(Rejection::TooWide);
            }
            self.lo = self.lo.min(s);
            self.hi = self.hi.max(s);
            let half = usize::from(signed_w > 0.0);
            self.side_lo[half] = self.side_lo[half].min(s);
            self.side_hi[half] = self.side_hi[half].max(s);
            // Which halves of the pads' width the squeezed part covers.
            if signed_w < -config.pad_width / 4.0 {
                self.covered[0] = true;
            } else if signed_w > config.pad_width / 4.0 {
                self.covered[1] = true;
            } else {
                self.covered[2] = true;
            }
        }
        Ok(())
    }

    /// Where the squeezed outline differs between the two halves of a pad, the surface is
    /// slanted to the jaw and a squeeze pushes the object out sideways.
    fn slant(&self, config: &CheckConfig) -> f32 {
        let (lo, hi) = (self.side_lo, self.side_hi);
        if lo[0] <= hi[0] && lo[1] <= hi[1] {
            (lo[0] - lo[1]).abs().max((hi[0] - hi[1]).abs())
        } else {
            config.pad_width
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::policy::synthetic::{block_frame, floor_frame};

    /// A grasp across the middle of a 26 mm block, the cloud the camera sees, and the checks
    /// under `config` with more surface points, each (along, across, above) the TCP.
    fn with_extra_points(
        extra: &[[f32; 3]],
        config: &CheckConfig,
    ) -> Result<Assessment, Rejection> {
        let camera = Camera::top_down();
        let frame = floor_frame(&camera, Some(1));
        let grasp = PixelGrasp {
            u: 64,
            v: 64,
            angle_deg: 0.0,
        };
        let target = world_grasp(&camera, &frame, grasp);
        let normal = Vector::new(-target.closing.y, target.closing.x, 0.0);
        let mut points: Vec<Vector> = HeightMap::new(&camera, &frame).surface_points().collect();
        points.extend(extra.iter().map(|&[along, across, above]| {
            target.tcp + target.closing * along + normal * across + Vector::Z * above
        }));
        check_grasp(
            &Cloud::from_points(points),
            &camera,
            &frame,
            grasp,
            target.tcp,
            config,
        )
    }

    /// The default checks with one more surface point at (`along`, `across`) from the TCP,
    /// `above` its height.
    fn with_extra_point(along: f32, across: f32, above: f32) -> Result<Assessment, Rejection> {
        with_extra_points(&[[along, across, above]], &CheckConfig::default())
    }

    #[test]
    fn a_surface_beside_a_pads_inner_corner_blocks_the_pad() {
        let config = CheckConfig::default();
        let half_open = config.opening / 2.0;
        let inside_margin = half_open - config.margin / 2.0;
        let beside_pad = config.pad_width / 2.0 + config.margin / 2.0;
        assert!(with_extra_point(0.0, 0.0, -0.005).is_ok());
        assert_eq!(
            with_extra_point(inside_margin, beside_pad, 0.01),
            Err(Rejection::PadBlocked)
        );
        assert_eq!(
            with_extra_point(-inside_margin, -beside_pad, 0.01),
            Err(Rejection::PadBlocked)
        );
        // Below the pads' lower edge the same spot is free.
        assert!(with_extra_point(inside_margin, beside_pad, -0.002).is_ok());
        // In front of the pad's face it is part of what is squeezed, and too wide.
        assert_eq!(
            with_extra_point(inside_margin, 0.0, 0.01),
            Err(Rejection::TooWide)
        );
        // Beyond the margin beside the pad nothing is touched.
        let clear_of_pad = config.pad_width / 2.0 + config.margin * 1.5;
        assert!(with_extra_point(inside_margin, clear_of_pad, 0.01).is_ok());
    }

    #[test]
    fn the_squeeze_margin_decides_whether_a_face_close_to_an_open_pad_fits() {
        let half_open = GRIPPER.max_opening / 2.0;
        // A face 4 mm inside the open pad on one side, square across its whole width.
        let face: Vec<[f32; 3]> = (-5..=5)
            .map(|k| [half_open - 0.004, k as f32 * 0.002, 0.01])
            .collect();
        let check = |squeeze_margin: f32| {
            let config = CheckConfig {
                squeeze_margin,
                ..CheckConfig::default()
            };
            with_extra_points(&face, &config)
        };
        assert_eq!(check(PLANNING_MARGIN), Err(Rejection::TooWide));
        let passed = check(0.003).expect("4 mm of room is more than 3");
        assert!(passed.width > half_open - 0.004, "{passed:?}");
    }

    #[test]
    fn a_grasp_on_a_blocks_last_row_catches_two_strips_and_fails_when_three_are_asked() {
        let camera = Camera::top_down();
        // 3 columns along the closing line (it fits the jaw), 7 rows across it.
        let frame = block_frame(&camera, Some([1, 3]));
        let heights = HeightMap::new(&camera, &frame);
        let check = |row: u32, strips: usize| {
            let config = CheckConfig {
                strips,
                ..CheckConfig::default()
            };
            let grasp = PixelGrasp {
                u: 64,
                v: row,
                angle_deg: 0.0,
            };
            Verifier::new(&camera, &frame, &heights, config).assess(grasp)
        };
        assert!(check(64, 3).is_ok(), "{:?}", check(64, 3));
        // On the last row the block lies on one side of the closing line only: the middle
        // strip and one outer quarter.
        assert!(check(67, 2).is_ok(), "{:?}", check(67, 2));
        assert_eq!(check(67, 3), Err(Rejection::Edge));
    }
}
