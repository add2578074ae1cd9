//! The protective stops of guarded moves: the arm or a finger entering the totes, a part
//! pushing on an object past the UR5's force limit, an object pressed into the floor; and the
//! creep that slows guarded moves near objects so that one step cannot press far.

use super::{in_contact, Workcell};

/// A force this large between the arm (or fingers) and an object stops the arm (N): the
/// UR5's default protective-stop force.
const OBJECT_FORCE_LIMIT: f32 = 150.0;
/// Penetration into the totes or ground that counts as a collision (m).
const ENVIRONMENT_PENETRATION: f32 = 0.002;
/// An object pushed this deep into the totes or ground during a guarded move stops the arm
/// (m), counted from where it was when the move began (see [`RESTING_SINK`]). The guard looks
/// after each step; creeping, a finger moves 0.4 mm a step, so a stopped object stays well under
/// the soak's 5 mm.
const OBJECT_PRESSED_DEPTH: f32 = 0.0025;
/// How deep an object may rest in the tote before the pressed-object guard counts from its
/// depth instead (m).
const RESTING_SINK: f32 = 0.0015;
/// Objects whose contact points read shallower than this (m) skip the guard's exact depth
/// query: a step moves a pressed object well under the guard's 2.5 mm.
const GUARD_SCREEN_DEPTH: f32 = 0.0005;
/// A guarded move slows to this fraction of its speed while the hand is within [`CREEP_GAP`] of
/// an object.
pub(super) const CREEP_RATE: f64 = 0.2;
/// How near the hand must come to an object for a guarded move to creep (m).
pub(super) const CREEP_GAP: f32 = 0.01;

/// What stopped the arm: the protective stops of a real UR5 and the gripper's guard.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum CollisionStop {
    /// An arm link or the palm entered a tote or the ground.
    #[error("the arm hit the bin or the ground")]
    ArmHitEnvironment,
    /// A finger entered a tote or the ground.
    #[error("a finger hit the bin or the ground")]
    FingerHitEnvironment,
    /// An object sank deeper into the tote during the move (pressed by the hand, or by an
    /// object the hand pushes).
    #[error("the gripper pressed {object} into the tote")]
    PressedIntoTote {
        /// The object's name.
        object: String,
    },
    /// A part pushed on an object harder than the protective-stop force.
    #[error("the {part} pressed on {object} with {force:.0} N")]
    Pressed {
        /// "arm", "palm" or "finger".
        part: &'static str,
        /// The object's name.
        object: String,
        /// The contact force (N).
        force: f32,
    },
}

/// What may not be touched during a motion.
#[derive(Clone, Copy)]
pub(super) struct Guard {
    /// Check pushing forces on objects (off while carrying one).
    pub(super) objects: bool,
}

impl Workcell {
    /// Whether a finger or the palm is within `gap` of any object.
    pub(super) fn hand_near_object(&self, gap: f32) -> bool {
        self.gripper
            .finger_colliders
            .iter()
            .flatten()
            .chain([&self.gripper.palm_collider])
            .any(|&part| {
                self.objects
                    .iter()
                    .any(|o| in_contact(&self.world, part, o.collider, gap))
            })
    }

    /// The first guarded contact, described, if any.
    pub(super) fn collision(&self, guard: Guard, sunk_before: &[f32]) -> Option<CollisionStop> {
        for &c in self
            .arm
            .colliders
            .iter()
            .chain([&self.gripper.palm_collider])
        {
            if self.touches_environment(c, ENVIRONMENT_PENETRATION) {
                return Some(CollisionStop::ArmHitEnvironment);
            }
        }
        for &c in self.gripper.finger_colliders.iter().flatten() {
            if self.touches_environment(c, ENVIRONMENT_PENETRATION) {
                return Some(CollisionStop::FingerHitEnvironment);
            }
        }
        if guard.objects {
            // Forces on an object scale with its mass in rapier's soft contacts, so a pad coming
            // down on a 28 g brick never reaches the force limit: it sinks the brick into the
            // floor instead. How deep an object is pushed into the tote stands in for the force,
            // for any object: a finger on the drill may press the banana under it.
            for (object, &before) in self.objects.iter().zip(sunk_before) {
                // Counted from where it lay, but never from deeper than a light object rests:
                // one already sunk under a heavier neighbour has less room left before 5 mm.
                let sunk = self.environment_penetration_beyond(object.collider, GUARD_SCREEN_DEPTH);
                if sunk - before.min(RESTING_SINK) > OBJECT_PRESSED_DEPTH {
                    tracing::debug!(object = %object.model.name, sunk, before, tool0 = ?self.tool0_pose().translation, "pressed into the tote");
                    return Some(CollisionStop::PressedIntoTote {
                        object: object.model.name.clone(),
                    });
                }
            }
            let parts = self
                .arm
                .colliders
                .iter()
                .map(|&c| (c, "arm"))
                .chain([(self.gripper.palm_collider, "palm")])
                .chain(
                    self.gripper
                        .finger_colliders
                        .iter()
                        .flatten()
                        .map(|&c| (c, "finger")),
                );
            for (c, part) in parts {
                for object in &self.objects {
                    let force = self.contact_force(c, object.collider);
                    if force > OBJECT_FORCE_LIMIT {
                        tracing::debug!(
                            part,
                            tool0 = ?self.tool0_pose().translation,
                            object = ?self.world.bodies[object.body].translation(),
                            "pressed"
                        );
                        return Some(CollisionStop::Pressed {
                            part,
                            object: object.model.name.clone(),
                            force,
                        });
                    }
                }
            }
        }
        None
    }
}
