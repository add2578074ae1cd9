//! How the workcell advances time: one step (split while an object falls fast), holding the
//! arm, and settling. The solver's settings are set once, in [`super::Workcell::new`].

use rapier3d::prelude::RigidBodyHandle;

use super::penetration::DropMisfiredContacts;
use super::{recording, Workcell, PHYSICS_HZ};
use crate::sim::kinematics::Joints;

/// Consecutive still steps (0.25 s) that count as settled.
pub(super) const SETTLED_STEPS: u32 = 60;
/// An object moving slower than this (m/s) and turning slower than [`STILL_ANGULAR_SPEED`]
/// is still.
const STILL_LINEAR_SPEED: f32 = 0.005;
/// See [`STILL_LINEAR_SPEED`] (rad/s).
const STILL_ANGULAR_SPEED: f32 = 0.05;
/// See [`FAST_SUBSTEPS`] (m/s).
const FAST_OBJECT_SPEED: f32 = 0.3;

impl Workcell {
    /// Advances physics by one step of `1 / PHYSICS_HZ`, in [`FAST_SUBSTEPS`] parts while the arm
    /// is held and an object moves fast. The invariants, when watched, are checked after each part.
    pub(crate) fn step(&mut self) {
        // A moving arm's kinematic links reach their target at the end of the world's step, so a
        // split step would move them the whole way in its first part: split only a held arm.
        let fast = self.arm_held
            && self
                .objects
                .iter()
                .any(|o| self.world.bodies[o.body].linvel().length() > FAST_OBJECT_SPEED);
        let parts = if fast { self.fast_substeps } else { 1 };
        let dt = self.world.integration_parameters.dt;
        self.world.integration_parameters.dt = dt / parts as f32;
        for _ in 0..parts {
            self.world.step_with_events(&DropMisfiredContacts, &());
            if self.violations.is_some() {
                self.check_invariants();
            }
        }
        self.world.integration_parameters.dt = dt;
        self.steps += 1;
        let due = self
            .recorder
            .as_ref()
            .is_some_and(|r| self.steps.is_multiple_of(r.every));
        if due {
            let snapshot = self.snapshot();
            if let Some(r) = &self.recorder {
                // A recording that stopped listening (its thread failed) leaves the physics be.
                let _ = r.footage.send(recording::Footage::Scene(snapshot));
            }
        }
    }

    /// Steps until every object is at rest (or `max_seconds` pass); returns the seconds simulated.
    pub fn settle(&mut self, max_seconds: f32) -> f32 {
        let max_steps = (max_seconds * PHYSICS_HZ) as u32;
        let mut calm = 0;
        let mut steps = 0;
        while steps < max_steps {
            self.hold_arm();
            self.step();
            steps += 1;
            let moving = self.objects.iter().any(|o| !self.is_still(o.body));
            calm = if moving { 0 } else { calm + 1 };
            // A rocking object is briefly still at each turn; a calm spell this long is rest.
            if calm >= SETTLED_STEPS {
                break;
            }
        }
        steps as f32 / PHYSICS_HZ
    }

    /// Whether a body is asleep, or moving no faster than the still speeds.
    pub(super) fn is_still(&self, body: RigidBodyHandle) -> bool {
        let b = &self.world.bodies[body];
        let moving = !b.is_sleeping()
            && (b.linvel().length() > STILL_LINEAR_SPEED
                || b.angvel().length() > STILL_ANGULAR_SPEED);
        !moving
    }

    /// Keeps the arm and palm where they are for the next step.
    pub(crate) fn hold_arm(&mut self) {
        let q = self.arm.joints;
        self.drive_arm(q);
        self.arm_held = true;
    }

    /// Schedules arm links and palm to reach `q` at the end of the next step.
    pub(crate) fn drive_arm(&mut self, q: Joints) {
        self.arm_held = false;
        self.arm.drive(&mut self.world, q);
        let tool0 = self.arm.tool0_pose(&q);
        self.gripper.drive(&mut self.world, tool0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{WorkcellConfig, FAST_SUBSTEPS};

    /// Drops all 15 objects with `seed`, stepping fast motion in `parts`; the invariant violations.
    fn drop_violations(seed: u64, parts: u32) -> Vec<String> {
        let library = crate::assets::objects::ObjectLibrary::bundled();
        let split = library.default_split().read().unwrap();
        let models = library.load_all(&split.all()).unwrap();
        let mut cell = Workcell::new(&WorkcellConfig::default()).unwrap();
        cell.fast_substeps = parts;
        cell.watch_invariants();
        cell.drop_objects(&models, seed).unwrap();
        cell.take_violations()
    }

    #[test]
    fn quarter_steps_keep_a_fast_landing_out_of_the_floor() {
        // Of seeds 0–299, 13 drops land an object more than 5 mm into the floor in whole steps
        // and none in quarter steps; 87 by the widest margin (the hammer, 9.7 mm). If a physics
        // or object change moves that, search the seeds again for one that breaks the limit in
        // whole steps.
        let whole = drop_violations(87, 1);
        assert!(
            !whole.is_empty(),
            "whole steps no longer break the limit on seed 87; pick another seed"
        );
        let split = drop_violations(87, FAST_SUBSTEPS);
        assert!(split.is_empty(), "quarter steps: {split:?}");
    }
}
