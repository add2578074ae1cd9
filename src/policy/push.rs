//! Where to push when no grasp passes the checks: a stroke of the closed hand that slides the
//! object under the network's best grasp away from its neighbours and off the walls, from a
//! start on free floor (docs/evaluation.md, "Pushing").
//!
//! Planned on the frame's height map and colours, as the checks are: no mask, no object
//! identity. Colour tells packed objects of one height apart, which heights alone cannot: VPG's
//! blocks stand side by side, 50 mm tall each.

use rapier3d::math::Vector;

use super::heights::HeightMap;
use crate::grasp::gripper::GRIPPER;
use crate::grasp::tote::{Tote, FLOOR_TOP, PICK_TOTE};
use crate::grasp::world::WorldPush;
use crate::grasp::PixelGrasp;
use crate::vision::render::Frame;

/// Height of the TCP (the fingertips) above the tote floor during the stroke (m): above the
/// floor's friction, below the top of every object but the flattest.
pub(crate) const PUSH_HEIGHT: f32 = 0.015;
/// A surface higher than this above the floor counts as an object (m).
const OCCUPIED_ABOVE_FLOOR: f32 = 0.008;
/// The closed hand needs free floor this far around the start (m): half the pad's width and
/// the finger plates, with room to spare.
const START_CLEARANCE: f32 = 0.03;
/// Nearest and farthest start behind the target (m).
const START_BEHIND: [f32; 2] = [0.03, 0.14];
/// Step of the search for a free start (m).
const START_STEP: f32 = 0.005;
/// How far the stroke moves the object (m): enough to open room for a pad (22 mm) and the open
/// jaw's margin beside it, no more, so that the object lands near where it was and off nothing.
const PUSH_TRAVEL: f32 = 0.06;
/// Least distance the stroke's end passes the target's centre (m), for objects that the height
/// map shows smaller than they are.
const PAST_TARGET_MIN: f32 = 0.02;
/// Neighbours whose surfaces lie this close to the path that the pushed object sweeps (m)
/// would be swept along with it.
const SWEEP_MARGIN: f32 = 0.01;
/// Neighbouring pixels whose colours differ by more than this (sum over R, G, B, of 255 each)
/// belong to different objects.
const SAME_COLOUR_STEP: u32 = 60;
/// Room left between the palm and the walls (m).
const WALL_MARGIN: f32 = 0.01;
/// Neighbours within this distance of the target set the push's direction (m).
const NEIGHBOURHOOD: f32 = 0.12;
/// Within this distance of a wall the push also turns away from it (m).
const WALL_REACH: f32 = 0.08;
/// Neighbouring pixels whose heights differ by less than this belong to one surface (m).
const SAME_SURFACE_STEP: f32 = 0.01;
/// Headings tried, spread over the full turn.
const HEADINGS: usize = 16;

/// The push for the object under `grasp`, or `None` when no heading has free floor behind it.
/// `frame` is the frame the height map was made from; its colours tell objects apart.
///
/// Of the headings that turn away from the neighbours, those whose stroke would sweep a
/// neighbour along with the object come last; the stroke moves the object [`PUSH_TRAVEL`].
pub fn plan_push(heights: &HeightMap, frame: &Frame, grasp: PixelGrasp) -> Option<WorldPush> {
    let rgb = &frame.rgb;
    let tote = PICK_TOTE;
    let target = heights.point(grasp.u, grasp.v);
    let occupied: Vec<Vector> = heights
        .surface_points()
        .filter(|p| p.z > FLOOR_TOP + OCCUPIED_ABOVE_FLOOR && inside(&tote, *p, 0.0))
        .collect();
    let own = own_top(heights, rgb, grasp.u, grasp.v);
    let own_points: Vec<Vector> = heights
        .pixels()
        .filter(|&(u, v)| own[(v * heights.size() + u) as usize])
        .map(|(u, v)| heights.point(u, v))
        .collect();
    let others: Vec<Vector> = heights
        .pixels()
        .filter(|&(u, v)| !own[(v * heights.size() + u) as usize])
        .map(|(u, v)| heights.point(u, v))
        .filter(|p| p.z > FLOOR_TOP + OCCUPIED_ABOVE_FLOOR && inside(&tote, *p, 0.0))
        .collect();
    let preferred = preferred_direction(&tote, target, &others);
    let mut headings: Vec<Vector> = (0..HEADINGS)
        .map(|k| {
            let a = k as f32 * std::f32::consts::TAU / HEADINGS as f32;
            Vector::new(a.cos(), a.sin(), 0.0)
        })
        // Square to the preferred way is still no push towards what it avoids.
        .filter(|d| d.dot(preferred) > -1e-3)
        .collect();
    headings.sort_by(|a, b| {
        let sweeps = |d: &Vector| sweeps_a_neighbour(target, *d, &own_points, &others);
        sweeps(a)
            .cmp(&sweeps(b))
            .then(b.dot(preferred).total_cmp(&a.dot(preferred)))
    });
    let z = FLOOR_TOP + PUSH_HEIGHT;
    let flat = |p: Vector| Vector::new(p.x, p.y, z);
    for d in headings {
        let steps = ((START_BEHIND[1] - START_BEHIND[0]) / START_STEP).round() as usize;
        let start = (0..=steps)
            .map(|k| flat(target - d * (START_BEHIND[0] + k as f32 * START_STEP)))
            .find(|&s| {
                clear_of_walls(&tote, s, d)
                    && occupied
                        .iter()
                        .all(|p| Vector::new(p.x - s.x, p.y - s.y, 0.0).length() > START_CLEARANCE)
            });
        let Some(start) = start else { continue };
        // The hand meets the object at its back edge and moves it from there; as far as that
        // as the walls allow, and a stroke that cannot cross the target is no push.
        let back = extent_along(target, d, &own_points).0;
        let past_target = (back + PUSH_TRAVEL).max(PAST_TARGET_MIN);
        let reach = (0..=((past_target / START_STEP) as usize))
            .rev()
            .map(|k| flat(target + d * (k as f32 * START_STEP)))
            .find(|&e| clear_of_walls(&tote, e, d));
        if let Some(end) = reach {
            return Some(WorldPush { start, end });
        }
    }
    None
}

/// How far the object's surface reaches behind and ahead of `target` along `d` (m; the first
/// is negative).
fn extent_along(target: Vector, d: Vector, own: &[Vector]) -> (f32, f32) {
    own.iter()
        .map(|p| Vector::new(p.x - target.x, p.y - target.y, 0.0).dot(d))
        .fold((0.0f32, 0.0f32), |(lo, hi), a| (lo.min(a), hi.max(a)))
}

/// Whether pushing the object at `target` along `d` by [`PUSH_TRAVEL`] would drive it into
/// another object's surface: one lying ahead of it, within the object's width across `d`.
fn sweeps_a_neighbour(target: Vector, d: Vector, own: &[Vector], others: &[Vector]) -> bool {
    let across = Vector::new(-d.y, d.x, 0.0);
    let offset = |p: &Vector| Vector::new(p.x - target.x, p.y - target.y, 0.0);
    let front = extent_along(target, d, own).1;
    let half_width = own
        .iter()
        .map(|p| offset(p).dot(across).abs())
        .fold(0.0f32, f32::max);
    others.iter().any(|p| {
        let along = offset(p).dot(d);
        along > front - SWEEP_MARGIN
            && along < front + PUSH_TRAVEL + SWEEP_MARGIN
            && offset(p).dot(across).abs() < half_width + SWEEP_MARGIN
    })
}

/// The pixels of the surface under (`u`, `v`): those reached from it through raised neighbours
/// no more than [`SAME_SURFACE_STEP`] higher or lower and of about its colour
/// ([`SAME_COLOUR_STEP`]), which a neighbouring object's edge usually is not.
fn own_top(heights: &HeightMap, rgb: &[u8], u: u32, v: u32) -> Vec<bool> {
    let size = heights.size();
    let colour = |u: u32, v: u32| {
        let i = 3 * (v * size + u) as usize;
        rgb.get(i..i + 3).map_or([0; 3], |c| [c[0], c[1], c[2]])
    };
    let alike = |a: [u8; 3], b: [u8; 3]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| u32::from(x.abs_diff(y)))
            .sum::<u32>()
            <= SAME_COLOUR_STEP
    };
    let raised = |u: u32, v: u32| heights.at(u, v) > FLOOR_TOP + OCCUPIED_ABOVE_FLOOR;
    let mut own = vec![false; (size * size) as usize];
    if !raised(u, v) {
        return own;
    }
    own[(v * size + u) as usize] = true;
    let mut frontier = vec![(u, v)];
    while let Some((u, v)) = frontier.pop() {
        let here = heights.at(u, v);
        let steps = [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)];
        for (du, dv) in steps {
            let (nu, nv) = (u as i64 + du, v as i64 + dv);
            if nu < 0 || nv < 0 || nu >= size as i64 || nv >= size as i64 {
                continue;
            }
            let (nu, nv) = (nu as u32, nv as u32);
            let index = (nv * size + nu) as usize;
            if !own[index]
                && raised(nu, nv)
                && (heights.at(nu, nv) - here).abs() < SAME_SURFACE_STEP
                && alike(colour(u, v), colour(nu, nv))
            {
                own[index] = true;
                frontier.push((nu, nv));
            }
        }
    }
    own
}

/// Away from the other objects' surfaces around the target, the nearer the stronger, and away
/// from any wall within [`WALL_REACH`].
fn preferred_direction(tote: &Tote, target: Vector, others: &[Vector]) -> Vector {
    // Each surface point repels, fading to nothing at the neighbourhood's edge.
    let mut away = Vector::ZERO;
    let mut count = 0;
    for p in others {
        let off = Vector::new(target.x - p.x, target.y - p.y, 0.0);
        let distance = off.length();
        if distance > 1e-3 && distance < NEIGHBOURHOOD {
            away += off / distance * (1.0 - distance / NEIGHBOURHOOD);
            count += 1;
        }
    }
    if count > 0 {
        away /= count as f32;
    }
    for axis in 0..2 {
        let c = tote.center[axis];
        let h = tote.inner_half[axis];
        let t = [target.x, target.y][axis];
        let unit = if axis == 0 { Vector::X } else { Vector::Y };
        let low = t - (c - h);
        let high = (c + h) - t;
        if low < WALL_REACH {
            away += unit * (2.0 * (WALL_REACH - low) / WALL_REACH);
        }
        if high < WALL_REACH {
            away -= unit * (2.0 * (WALL_REACH - high) / WALL_REACH);
        }
    }
    if away.length() < 1e-3 {
        // Alone and in the open: towards the bin's centre, or any way at its centre.
        let to_centre = Vector::new(tote.center[0] - target.x, tote.center[1] - target.y, 0.0);
        return if to_centre.length() > 1e-3 {
            to_centre.normalize()
        } else {
            Vector::X
        };
    }
    away.normalize()
}

/// Whether the palm, its short side along the stroke `d`, clears the walls with the TCP at `p`.
fn clear_of_walls(tote: &Tote, p: Vector, d: Vector) -> bool {
    let along = GRIPPER.palm_half_across;
    let across = GRIPPER.palm_half_along;
    let reach = [
        d.x.abs() * along + d.y.abs() * across,
        d.y.abs() * along + d.x.abs() * across,
    ];
    (0..2).all(|axis| {
        let t = [p.x, p.y][axis];
        (t - tote.center[axis]).abs() <= tote.inner_half[axis] - reach[axis] - WALL_MARGIN
    })
}

/// Whether `p` lies over the tote's floor at least `margin` from every wall.
fn inside(tote: &Tote, p: Vector, margin: f32) -> bool {
    (0..2).all(|axis| {
        let t = [p.x, p.y][axis];
        (t - tote.center[axis]).abs() <= tote.inner_half[axis] - margin
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::policy::synthetic::blocks_frame;
    use crate::vision::camera::Camera;

    fn grasp_at(u: u32, v: u32) -> PixelGrasp {
        PixelGrasp {
            u,
            v,
            angle_deg: 0.0,
        }
    }

    /// Horizontal distance between two points.
    fn apart(a: Vector, b: Vector) -> f32 {
        Vector::new(a.x - b.x, a.y - b.y, 0.0).length()
    }

    #[test]
    fn a_block_beside_another_is_pushed_away_from_it_from_free_floor() {
        let camera = Camera::top_down();
        // The target around pixel (60, 64), its neighbour just to the right in the image, too
        // close for the hand to start between them: the push leaves at an angle.
        let frame = blocks_frame(&camera, &[[55, 65, 58, 70], [68, 80, 56, 72]]);
        let heights = HeightMap::new(&camera, &frame);
        let push = plan_push(&heights, &frame, grasp_at(60, 64)).expect("free floor all round");
        let target = heights.point(60, 64);
        let neighbour = heights.point(74, 64);
        let away = Vector::new(target.x - neighbour.x, target.y - neighbour.y, 0.0).normalize();
        assert!(
            push.direction().dot(away) > 0.5,
            "pushed along {:?}, away is {away:?}",
            push.direction()
        );
        // It starts behind the target, on floor no block covers, and ends past it.
        assert!((push.start - target).dot(push.direction()) < 0.0);
        assert!((push.end - target).dot(push.direction()) >= PAST_TARGET_MIN - 1e-3);
        assert_eq!(push.start.z, FLOOR_TOP + PUSH_HEIGHT);
        for p in heights.surface_points() {
            if p.z > FLOOR_TOP + OCCUPIED_ABOVE_FLOOR {
                assert!(
                    apart(p, push.start) > START_CLEARANCE,
                    "{p:?} under the start"
                );
            }
        }
    }

    #[test]
    fn a_block_at_a_wall_is_pushed_off_it_and_the_palm_clears_every_wall() {
        let camera = Camera::top_down();
        let tote = PICK_TOTE;
        // A block from 1 to 9 cm off the wall at the image's left edge, on the middle row: no
        // room to start between it and the wall.
        let heights = HeightMap::new(&camera, &blocks_frame(&camera, &[]));
        let column_off_wall = |gap: f32| {
            (0..128u32)
                .find(|&u| inside(&tote, heights.point(u, 64), gap))
                .expect("the tote is in view")
        };
        let [near, far] = [column_off_wall(0.01), column_off_wall(0.09)];
        let frame = blocks_frame(&camera, &[[near, far, 58, 70]]);
        let heights = HeightMap::new(&camera, &frame);
        let middle = (near + far) / 2;
        let target = heights.point(middle, 64);
        let push =
            plan_push(&heights, &frame, grasp_at(middle, 64)).expect("a push along the wall");
        let wall_normal = Vector::new(0.0, if target.y < tote.center[1] { 1.0 } else { -1.0 }, 0.0);
        let along_the_wall_or_off_it = push.direction().dot(wall_normal) >= 0.0;
        assert!(along_the_wall_or_off_it, "{push:?} runs into the wall");
        for p in [push.start, push.end] {
            assert!(clear_of_walls(&tote, p, push.direction()), "{p:?}");
        }
    }

    #[test]
    fn packed_blocks_of_one_height_are_told_apart_by_colour_and_pushed_apart() {
        let camera = Camera::top_down();
        // Two blocks of one height touching along a column boundary; the right one is red.
        let mut frame = blocks_frame(&camera, &[[50, 59, 58, 70], [60, 69, 58, 70]]);
        for v in 58..=70u32 {
            for u in 60..=69u32 {
                let i = 3 * (v * 128 + u) as usize;
                frame.rgb[i] = 200;
            }
        }
        let heights = HeightMap::new(&camera, &frame);
        let target = heights.point(54, 64);
        let neighbour = heights.point(65, 64);
        let push = plan_push(&heights, &frame, grasp_at(54, 64)).expect("free floor around");
        let away = Vector::new(target.x - neighbour.x, target.y - neighbour.y, 0.0).normalize();
        assert!(
            push.direction().dot(away) > 0.5,
            "pushed along {:?}, away from the red block is {away:?}",
            push.direction()
        );
        // The stroke moves the block its travel from where the hand meets it, not the pile.
        let own = own_top(&heights, &frame.rgb, 54, 64);
        assert!(
            !own[(64 * 128 + 65) as usize],
            "the red block counted as the target's"
        );
        let travel = (push.end - target).dot(push.direction())
            - extent_along(
                target,
                push.direction(),
                &[
                    heights.point(50, 64),
                    heights.point(59, 64),
                    heights.point(54, 58),
                    heights.point(54, 70),
                ],
            )
            .0;
        assert!(
            travel < PUSH_TRAVEL + 0.01,
            "the block is pushed {travel} m"
        );
    }

    #[test]
    fn no_push_when_the_floor_round_the_target_is_covered() {
        let camera = Camera::top_down();
        let frame = blocks_frame(&camera, &[[0, 127, 0, 127]]);
        let heights = HeightMap::new(&camera, &frame);
        assert_eq!(plan_push(&heights, &frame, grasp_at(64, 64)), None);
    }
}
