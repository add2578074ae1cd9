//! The pick sequence (docs/grasping.md): open, approach, straight descent, close, lift, home, check, and place in bin 2.
//!
//! Every motion is simulated step by step. Collisions with the totes or pushing hard on objects
//! stop the arm, and IK failures end the attempt, each as a typed outcome rather than an error.

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use rapier3d::math::{Pose, Rotation, Vector};

use super::guard::{CollisionStop, Guard, CREEP_GAP, CREEP_RATE};
use super::{in_contact, ObjectLocation, Workcell, PHYSICS_HZ};
use crate::grasp::gripper::GRIPPER;
use crate::grasp::world::WorldGrasp;
use crate::named::named_enum;
use crate::sim::kinematics::{
    IkError, JointTrajectory, Joints, TrapezoidProfile, Ur5, HOME_JOINTS,
};

/// Joint-space speed limit of the trapezoidal moves (rad/s).
pub(crate) const JOINT_SPEED: f64 = 3.0;
/// Joint-space acceleration limit (rad/s²).
pub(crate) const JOINT_ACCELERATION: f64 = 6.0;
/// Joint-space acceleration limit while carrying an object (rad/s²). At 2 rad/s² the start of
/// the half turn jerked a mustard bottle held by its cap out of the jaw over the floor beside
/// bin 1 (the fifteen-mesh emptying in tests/suite/place.rs, seed 1, attempt 3); at 1 rad/s² it
/// is carried, for 0.6 s more per carry.
pub(crate) const CARRY_ACCELERATION: f64 = 1.0;
/// Joint-space speed limit while carrying an object (rad/s). The half turn of the base to bin 2
/// swings a held object round at up to this rate: at 2 rad/s the pull on a mustard bottle held
/// 85 mm off its centre of mass outgrew the pads' grip, and it spun out of the jaw over the
/// floor between the bins; the pull grows with the square of the rate (docs/grasping.md,
/// "Carrying").
pub(crate) const CARRY_SPEED: f64 = 1.2;
/// Cartesian speed of the vertical descent and lift (m/s).
pub(crate) const LINE_SPEED: f64 = 0.5;
/// Cartesian acceleration of the vertical descent and lift (m/s²).
pub(crate) const LINE_ACCELERATION: f64 = 2.0;
/// Height of the approach point above the target, and of the lift (m).
pub(crate) const APPROACH_HEIGHT: f32 = 0.3;
/// Height an object must rise for a grasp to count (m).
pub(crate) const LIFT_SUCCESS_HEIGHT: f32 = 0.2;
/// Below this opening the fingers count as fully closed (m).
pub(crate) const CLOSED_OPENING: f32 = 0.004;
/// Longest wait for the fingers to open (s).
pub(super) const OPEN_WAIT: f32 = 0.6;
/// Longest wait for the fingers to close on an object (s).
const CLOSE_WAIT: f32 = 1.0;
/// Longest wait for the objects to come to rest after an attempt (s).
pub(super) const AFTER_ATTEMPT_SETTLE: f32 = 2.0;
/// After a failure the hand backs up to at least this TCP height (m), then
/// [`RECOVER_BACKOFF`] higher, before going home.
const RECOVER_TCP_HEIGHT: f32 = 0.25;
/// See [`RECOVER_TCP_HEIGHT`] (m).
const RECOVER_BACKOFF: f32 = 0.1;
/// After a failure the hand first backs this far straight up, and only then opens (m).
const RECOVER_RELIEF: f32 = 0.03;
/// Distance within which a pad counts as touching an object (m).
const TOUCH_GAP: f32 = 0.002;

named_enum! {
    /// Why an attempt ended the way it did.
    #[derive(serde::Deserialize)]
    pub enum PickReason {
        /// Lifted, carried home and placed.
        Success = "success", "lifted, carried home and placed",
        /// The fingers closed on nothing.
        EmptyHand = "empty_hand", "the fingers closed on nothing",
        /// Something was touched but it did not stay between the pads up to home.
        Slipped = "slipped", "something was touched but it did not stay between the pads up to home",
        /// The arm or hand ran into the totes, the ground, or pressed hard on an object.
        Collision = "collision", "the arm or hand ran into the totes, the ground, or pressed hard on an object",
        /// No IK solution along the path.
        IkUnreachable = "ik_unreachable", "no IK solution along the path",
        /// The planner found no feasible grasp (reported by planners, not by execution).
        Ungraspable = "ungraspable", "the planner found no feasible grasp",
        /// No grasp passed the checks, so the hand pushed instead of grasping (not a grasp
        /// attempt: pick success leaves it out).
        Pushed = "pushed", "no grasp passed the checks, so the hand pushed instead",
    }
}

/// Result of one pick attempt.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PickOutcome {
    /// True when an object was lifted, carried home and released over bin 2.
    pub success: bool,
    /// The reason, `success` included.
    pub reason: PickReason,
    /// Human-readable detail (what collided, how far the object rose...).
    pub detail: String,
    /// Name of the object that was held, when any was.
    pub(crate) object: Option<String>,
    /// After a success, where the held object came to rest: `Bin2` when it was placed, `Bin1`
    /// or `Lost` when it ended anywhere else. `None` for a failure.
    pub placed: Option<ObjectLocation>,
    /// After a success, where the held object's centre of mass was when the hand opened over
    /// bin 2 (world, m).
    pub released_at: Option<[f32; 3]>,
    /// Simulated seconds the attempt took.
    pub(crate) sim_seconds: f64,
}

impl PickOutcome {
    /// A failed attempt in which nothing was held (the time is filled in by [`Workcell::pick`]).
    pub(crate) fn failure(reason: PickReason, detail: String) -> Self {
        Self {
            success: false,
            reason,
            detail,
            object: None,
            placed: None,
            released_at: None,
            sim_seconds: 0.0,
        }
    }
}

pub(super) enum Stop {
    Collision(CollisionStop),
    Ik(IkError),
}

impl Workcell {
    /// Executes a full pick attempt for a world grasp; on success the object is placed in bin 2.
    pub fn pick(&mut self, grasp: &WorldGrasp) -> PickOutcome {
        let start = self.time();
        let mut outcome = self.pick_inner(grasp);
        outcome.sim_seconds = self.time() - start;
        outcome
    }

    fn pick_inner(&mut self, grasp: &WorldGrasp) -> PickOutcome {
        let ur5 = Ur5::new(to_isometry(&Pose::from_translation(super::ROBOT_BASE)));
        let grasp_tool0 = tool0_for;
        let above = grasp.tcp + Vector::new(0.0, 0.0, APPROACH_HEIGHT);
        let (approach_q, closing) = match self.approach(&ur5, above, grasp.closing) {
            Ok(approach) => approach,
            Err(e) => return PickOutcome::failure(PickReason::IkUnreachable, e.to_string()),
        };

        let heights_before: Vec<f32> = (0..self.objects.len())
            .map(|i| self.object_pose(i).translation.z)
            .collect();
        let guard = Guard { objects: true };
        self.enter("open");
        self.gripper.open(&mut self.world);
        self.wait_for_fingers(OPEN_WAIT);
        self.trace("opened");
        self.enter("approach");
        if let Err(stop) = self.move_joints(approach_q, guard) {
            return self.abort(stop);
        }
        self.trace("approached");
        self.enter("descend");
        if let Err(stop) = self.move_line(&ur5, grasp_tool0(grasp.tcp, closing), guard) {
            return self.abort(stop);
        }
        tracing::debug!(?closing, "intended closing direction");
        self.trace("descended");
        self.enter("close");
        self.gripper.close(&mut self.world);
        self.wait_for_fingers(CLOSE_WAIT);
        self.gripper.hold(&mut self.world);
        self.trace("closed");
        let carry = Guard { objects: false };
        self.enter("lift");
        if let Err(stop) = self.move_line(&ur5, grasp_tool0(above, closing), carry) {
            return self.abort(stop);
        }
        self.trace("lifted");
        if let Err(failure) = self.check_held(&heights_before, "after the lift") {
            self.recover();
            return failure;
        }
        self.enter("carry home");
        if let Err(stop) = self.move_joints(HOME_JOINTS, carry) {
            return self.abort(stop);
        }
        let held = match self.check_held(&heights_before, "at home") {
            Ok(held) => held,
            Err(failure) => {
                self.recover();
                return failure;
            }
        };
        let lift_at_home = self.lift_of(held, &heights_before);
        self.place(held, lift_at_home)
    }

    /// The joints that put the TCP at `above` with the fingers along ±`closing`, and that
    /// direction: the jaw is symmetric, so whichever sign needs less wrist travel.
    pub(super) fn approach(
        &self,
        ur5: &Ur5,
        above: Vector,
        closing: Vector,
    ) -> Result<(Joints, Vector), IkError> {
        let current = self.arm.joints;
        let candidates = [closing, -closing].map(|c| {
            ur5.inverse(&to_isometry(&tool0_for(above, c)), &current)
                .map(|q| (q, c, joint_distance(&q, &current)))
        });
        match candidates {
            [Ok(a), Ok(b)] => Ok(if a.2 <= b.2 { (a.0, a.1) } else { (b.0, b.1) }),
            [Ok(a), Err(_)] | [Err(_), Ok(a)] => Ok((a.0, a.1)),
            [Err(e), Err(_)] => Err(e),
        }
    }

    fn trace(&self, phase: &str) {
        tracing::debug!(
            phase,
            t = self.time(),
            tool0 = ?self.tool0_pose().translation,
            finger_axis = ?(self.tool0_pose().rotation * Vector::Y),
            opening = self.gripper.opening(&self.world),
            objects = ?self.objects.iter().map(|o| self.world.bodies[o.body].translation()).collect::<Vec<_>>(),
        );
    }

    fn lift_of(&self, index: usize, heights_before: &[f32]) -> f32 {
        self.object_pose(index).translation.z - heights_before[index]
    }

    /// Which object is held between both pads, risen by the success height; or why none is.
    fn check_held(&self, heights_before: &[f32], when: &str) -> Result<usize, PickOutcome> {
        let opening = self.gripper.opening(&self.world);
        let touching: Vec<usize> = (0..self.objects.len())
            .filter(|&i| {
                let c = self.objects[i].collider;
                self.gripper
                    .pads
                    .iter()
                    .any(|&pad| in_contact(&self.world, pad, c, TOUCH_GAP))
            })
            .collect();
        let held = touching.iter().copied().find(|&i| {
            let c = self.objects[i].collider;
            self.gripper
                .pads
                .iter()
                .all(|&pad| in_contact(&self.world, pad, c, TOUCH_GAP))
                && self.lift_of(i, heights_before) >= LIFT_SUCCESS_HEIGHT
        });
        match held {
            Some(i) if opening > CLOSED_OPENING => Ok(i),
            _ => {
                let (reason, detail) = if touching.is_empty() && opening <= CLOSED_OPENING {
                    (
                        PickReason::EmptyHand,
                        format!("fingers closed on nothing {when}"),
                    )
                } else {
                    let lifted = touching
                        .first()
                        .map(|&i| self.lift_of(i, heights_before))
                        .unwrap_or(0.0);
                    (
                        PickReason::Slipped,
                        format!(
                            "object not held {when} (opening {:.3} m, object rose {:.3} m)",
                            opening, lifted
                        ),
                    )
                };
                Err(PickOutcome {
                    object: touching
                        .first()
                        .map(|&i| self.objects[i].model.name.clone()),
                    ..PickOutcome::failure(reason, detail)
                })
            }
        }
    }

    fn abort(&mut self, stop: Stop) -> PickOutcome {
        let (reason, detail) = match stop {
            Stop::Collision(what) => (PickReason::Collision, what.to_string()),
            Stop::Ik(e) => (PickReason::IkUnreachable, e.to_string()),
        };
        self.recover();
        PickOutcome::failure(reason, detail)
    }

    /// After a failed attempt: back a little straight up, open, back further up, and return home,
    /// without collision stops.
    pub(super) fn recover(&mut self) {
        self.enter("recover");
        let ur5 = Ur5::new(to_isometry(&Pose::from_translation(super::ROBOT_BASE)));
        // Relieve first, as a robot does after a protective stop: a pad left pressing on an
        // object while the hand held still to open hammered it into the floor (thin scissors
        // 5.3 mm deep, spinning at 10–20 rad/s between pad and floor).
        let mut relieved = self.tool0_pose();
        relieved.translation.z += RECOVER_RELIEF;
        let _ = self.move_line_unchecked(&ur5, relieved);
        self.gripper.open(&mut self.world);
        self.wait_for_fingers(OPEN_WAIT);
        let mut up = self.tool0_pose();
        up.translation.z = up
            .translation
            .z
            .max(RECOVER_TCP_HEIGHT + GRIPPER.tcp_offset)
            + RECOVER_BACKOFF;
        let _ = self.move_line_unchecked(&ur5, up);
        self.recover_home();
        self.enter("settle");
        self.settle(AFTER_ATTEMPT_SETTLE);
    }

    pub(super) fn recover_home(&mut self) {
        let trajectory = JointTrajectory::new(
            self.arm.joints,
            HOME_JOINTS,
            JOINT_SPEED,
            JOINT_ACCELERATION,
        );
        self.follow(|t| Some(trajectory.sample(t)), trajectory.duration(), None)
            .ok();
    }

    #[cfg(test)]
    fn hold_for(&mut self, seconds: f32) {
        for _ in 0..(seconds * PHYSICS_HZ) as u32 {
            self.hold_arm();
            self.step();
        }
    }

    /// Holds the arm while the finger motors run, until they stop or `max_seconds` pass.
    pub(super) fn wait_for_fingers(&mut self, max_seconds: f32) {
        let max_steps = (max_seconds * PHYSICS_HZ) as u32;
        let min_steps = (0.08 * PHYSICS_HZ) as u32;
        let mut still = 0;
        for i in 0..max_steps {
            self.hold_arm();
            self.step();
            still = if self.gripper.finger_speed(&self.world) < 0.002 {
                still + 1
            } else {
                0
            };
            if i >= min_steps && still >= 6 {
                break;
            }
        }
    }

    pub(super) fn move_joints(&mut self, target: Joints, guard: Guard) -> Result<(), Stop> {
        // Carrying, accelerate gently: a hard swing flings light objects out of the jaw.
        let (speed, acceleration) = if guard.objects {
            (JOINT_SPEED, JOINT_ACCELERATION)
        } else {
            (CARRY_SPEED, CARRY_ACCELERATION)
        };
        let trajectory = JointTrajectory::new(self.arm.joints, target, speed, acceleration);
        self.follow(
            |t| Some(trajectory.sample(t)),
            trajectory.duration(),
            Some(guard),
        )
        .map_err(|e| e.unwrap_or_else(|| unreachable!("joint moves have no ik")))
    }

    /// A straight line of tool0 from where it is to `target` (same orientation), IK at every step.
    pub(super) fn move_line(&mut self, ur5: &Ur5, target: Pose, guard: Guard) -> Result<(), Stop> {
        self.line(ur5, target, Some(guard))
    }

    pub(super) fn move_line_unchecked(&mut self, ur5: &Ur5, target: Pose) -> Result<(), Stop> {
        self.line(ur5, target, None)
    }

    fn line(&mut self, ur5: &Ur5, target: Pose, guard: Option<Guard>) -> Result<(), Stop> {
        let start = self.tool0_pose();
        let from = start.translation;
        let length = (target.translation - from).length() as f64;
        let profile = TrapezoidProfile::new(length, LINE_SPEED, LINE_ACCELERATION);
        let mut near = self.arm.joints;
        let mut ik_error = None;
        let result = self.follow(
            |t| {
                let s = if length > 0.0 {
                    (profile.position(t) / length) as f32
                } else {
                    1.0
                };
                let pose = Pose::from_parts(from.lerp(target.translation, s), target.rotation);
                match ur5.inverse(&to_isometry(&pose), &near) {
                    Ok(q) => {
                        near = q;
                        Some(q)
                    }
                    Err(e) => {
                        ik_error = Some(e);
                        None
                    }
                }
            },
            profile.duration(),
            guard,
        );
        match (result, ik_error) {
            (Err(_), Some(e)) => Err(Stop::Ik(e)),
            (Err(Some(stop)), None) => Err(stop),
            (Err(None), None) => unreachable!("a stop without a cause"),
            (Ok(()), _) => Ok(()),
        }
    }

    /// Steps physics along `path(t)` for `duration` seconds. `Err(None)` when `path` gives up
    /// (IK failure), `Err(Some(..))` when a guarded collision stops the arm where it is.
    fn follow(
        &mut self,
        mut path: impl FnMut(f64) -> Option<Joints>,
        duration: f64,
        guard: Option<Guard>,
    ) -> Result<(), Option<Stop>> {
        let dt = 1.0 / PHYSICS_HZ as f64;
        let guards_objects = guard.is_some_and(|g| g.objects);
        // Objects may rest a little sunk (under a heavier one, against a wall); only what the
        // move adds counts. Only moves that guard objects look at it.
        let sunk_before: Vec<f32> = if guards_objects {
            self.objects
                .iter()
                .map(|o| self.environment_penetration(o.collider))
                .collect()
        } else {
            Vec::new()
        };
        let mut t = 0.0;
        let mut i = 0u64;
        while t < duration {
            i += 1;
            // Near an object a guarded move creeps, as a robot's force-guarded approach does: at
            // full speed one step presses a finger 2 mm into an object, or the object 5 mm into
            // the floor, before any check can stop it.
            let rate = if guards_objects && self.hand_near_object(CREEP_GAP) {
                CREEP_RATE
            } else {
                1.0
            };
            t = (t + dt * rate).min(duration);
            let q = path(t).ok_or(None)?;
            let previous = self.arm.joints;
            self.drive_arm(q);
            self.step();
            if i.is_multiple_of(12) && tracing::enabled!(tracing::Level::TRACE) {
                let forces: Vec<f32> = self
                    .gripper
                    .pads
                    .iter()
                    .flat_map(|&p| self.objects.iter().map(move |o| (p, o.collider)))
                    .map(|(p, c)| self.contact_force(p, c))
                    .collect();
                tracing::trace!(t = self.time(), opening = self.gripper.opening(&self.world), ?forces, object = ?self.objects.first().map(|o| self.world.bodies[o.body].translation()));
            }
            if let Some(guard) = guard {
                if let Some(what) = self.collision(guard, &sunk_before) {
                    // The arm stops: it stays where it was before this step.
                    self.arm.joints = previous;
                    self.hold_arm();
                    self.step();
                    return Err(Some(Stop::Collision(what)));
                }
            }
        }
        Ok(())
    }
}

/// The tool0 pose that puts the TCP at `tcp`, pointing straight down, with the fingers sliding
/// along the horizontal `closing` direction.
pub(super) fn tool0_for(tcp: Vector, closing: Vector) -> Pose {
    // Tool z points down; fingers slide along tool y = the closing direction.
    let z = Vector::new(0.0, 0.0, -1.0);
    let y = closing;
    let x = y.cross(z);
    let rotation = Rotation::from_mat3(&rapier3d::glamx::Mat3::from_cols(x, y, z));
    Pose::from_parts(tcp + Vector::new(0.0, 0.0, GRIPPER.tcp_offset), rotation)
}

fn joint_distance(a: &Joints, b: &Joints) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// rapier pose (f32, glam) → nalgebra isometry (f64) for the IK.
pub(crate) fn to_isometry(pose: &Pose) -> Isometry3<f64> {
    let t = pose.translation;
    let q = pose.rotation;
    Isometry3::from_parts(
        Translation3::new(t.x as f64, t.y as f64, t.z as f64),
        UnitQuaternion::from_quaternion(Quaternion::new(
            q.w as f64, q.x as f64, q.y as f64, q.z as f64,
        )),
    )
}

#[cfg(test)]
mod tests {
    use super::super::robot::groups;
    use super::super::WorkcellConfig;
    use super::*;
    use rapier3d::prelude::{ColliderBuilder, RigidBodyBuilder};

    /// How far a 50 g cube held in the closed jaw moves along the closing line, relative to
    /// the hand, under a steady 5 N push along that line.
    fn slide_under_push(hold: bool) -> f32 {
        let mut cell = Workcell::new(&WorkcellConfig::default()).unwrap();
        cell.set_robot_collisions(true);
        // Only the push acts along the closing line; without gravity the cube waits for the jaw.
        cell.world.gravity = Vector::ZERO;
        let tool0 = cell.tool0_pose();
        let centre = tool0
            * Pose::from_translation(Vector::new(
                0.0,
                0.0,
                GRIPPER.tcp_offset - GRIPPER.pad_height / 2.0,
            ));
        let cube = cell
            .world
            .insert_body(RigidBodyBuilder::dynamic().pose(centre));
        cell.world.insert_collider(
            ColliderBuilder::cuboid(0.02, 0.02, 0.02)
                .mass(0.05)
                .friction(0.8)
                .collision_groups(groups::object()),
            Some(cube),
        );
        cell.gripper.close(&mut cell.world);
        cell.wait_for_fingers(1.0);
        if hold {
            cell.gripper.hold(&mut cell.world);
        }
        let relative = |cell: &Workcell| {
            cell.tool0_pose()
                .inverse_transform_point(cell.world.bodies[cube].translation())
        };
        let before = relative(&cell);
        let closing = tool0.rotation * Vector::Y;
        cell.world.bodies[cube].add_force(closing * 5.0, true);
        cell.hold_for(0.5);
        (relative(&cell) - before).length()
    }

    #[test]
    fn a_held_object_resists_a_push_along_the_closing_line() {
        // Two force-capped motors pushing against each other let the jaw and the object
        // slide together, towards a finger's end stop.
        let free = slide_under_push(false);
        assert!(free > 0.01, "without the hold the cube moved only {free} m");
        // Held, the spring rate (grip force / squeeze, 2 kN/m) balances 5 N within 2.5 mm.
        let held = slide_under_push(true);
        assert!(held < 0.005, "held, the cube still moved {held} m");
    }
}
