//! The push: the closed hand goes down beside an object and strokes it sideways, to break up a
//! pile the grasp checks find no way into (docs/evaluation.md, "Pushing").
//!
//! The same guarded motions as a pick: touching an object on the way down, pressing harder than
//! the protective-stop force, or reaching the totes stops the hand where it is, and the push
//! ends there.

use super::guard::Guard;
use super::pick::{tool0_for, Stop, APPROACH_HEIGHT};
use super::{Workcell, ROBOT_BASE};
use crate::grasp::world::WorldPush;
use crate::sim::kinematics::Ur5;
use crate::sim::pick::to_isometry;
use rapier3d::math::{Pose, Vector};

/// Longest wait for the fingers to close before a push (s).
const CLOSE_BEFORE_PUSH: f32 = 0.6;

/// How a push went.
#[derive(Debug, Clone, PartialEq)]
pub struct PushOutcome {
    /// Whether the hand travelled the whole stroke.
    pub completed: bool,
    /// What stopped it, or how far it went.
    pub detail: String,
    /// Simulated seconds the push took, the return home included.
    pub sim_seconds: f64,
}

impl Workcell {
    /// Executes a push: close, approach above the start, go down, stroke to the end, then back
    /// off home and let the bin settle.
    pub fn push(&mut self, push: &WorldPush) -> PushOutcome {
        let start = self.time();
        let (completed, detail) = match self.push_inner(push) {
            Ok(()) => (
                true,
                format!("pushed {:.0} mm", 1000.0 * (push.end - push.start).length()),
            ),
            Err(Stop::Collision(what)) => (false, format!("the push stopped: {what}")),
            Err(Stop::Ik(e)) => (false, format!("the push stopped: {e}")),
        };
        self.recover();
        PushOutcome {
            completed,
            detail,
            sim_seconds: self.time() - start,
        }
    }

    fn push_inner(&mut self, push: &WorldPush) -> Result<(), Stop> {
        let ur5 = Ur5::new(to_isometry(&Pose::from_translation(ROBOT_BASE)));
        // Fingers closing across the stroke keep the palm's long side across it too, so the
        // palm reaches least far ahead and behind the fingers, towards the walls.
        let direction = push.direction().cross(Vector::Z);
        let above = push.start + Vector::new(0.0, 0.0, APPROACH_HEIGHT);
        let (approach_q, closing) = self.approach(&ur5, above, direction).map_err(Stop::Ik)?;
        let guard = Guard { objects: true };
        self.enter("push");
        self.gripper.close(&mut self.world);
        self.wait_for_fingers(CLOSE_BEFORE_PUSH);
        self.move_joints(approach_q, guard)?;
        self.move_line(&ur5, tool0_for(push.start, closing), guard)?;
        self.move_line(&ur5, tool0_for(push.end, closing), guard)
    }
}
