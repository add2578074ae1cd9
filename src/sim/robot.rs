//! The UR5 loaded from its URDF (rapier3d-urdf for colliders, urdf-rs for the chain), driven as kinematic links, plus the parallel-jaw gripper.
//!
//! The arm is position-controlled: every physics step each link body gets its next kinematic pose
//! from forward kinematics of the URDF chain, so it sweeps through the scene and its contacts are
//! real. The fingers are dynamic bodies on prismatic joints with force-bounded motors, so a grip
//! holds by friction alone.

use std::path::Path;

use anyhow::{bail, Context};
use rapier3d::math::{Pose, Rotation, Vector};
use rapier3d::prelude::*;
use rapier3d_urdf::{UrdfLoaderOptions, UrdfRobot};

use crate::assets::urdf::{rpy_rotation, UrdfFile, Visual};
use crate::grasp::gripper::GRIPPER;
use crate::sim::kinematics::Joints;

/// Collision groups: which families of colliders may touch.
pub(crate) mod groups {
    use rapier3d::prelude::{Group, InteractionGroups, InteractionTestMode};

    pub(crate) const ENVIRONMENT: Group = Group::GROUP_1;
    pub(crate) const PEDESTAL: Group = Group::GROUP_2;
    pub(crate) const ARM: Group = Group::GROUP_3;
    pub(crate) const FINGER: Group = Group::GROUP_4;
    pub(crate) const OBJECT: Group = Group::GROUP_5;

    fn groups(member: Group, filter: Group) -> InteractionGroups {
        InteractionGroups::new(member, filter, InteractionTestMode::And)
    }
    pub(crate) fn environment() -> InteractionGroups {
        groups(ENVIRONMENT, ARM.union(FINGER).union(OBJECT))
    }
    /// The arm stands on its pedestal, so only objects may touch it.
    pub(crate) fn pedestal() -> InteractionGroups {
        groups(PEDESTAL, OBJECT)
    }
    pub(crate) fn arm() -> InteractionGroups {
        groups(ARM, ENVIRONMENT.union(OBJECT))
    }
    pub(crate) fn finger() -> InteractionGroups {
        groups(FINGER, ENVIRONMENT.union(OBJECT))
    }
    pub(crate) fn object() -> InteractionGroups {
        groups(
            OBJECT,
            ENVIRONMENT
                .union(PEDESTAL)
                .union(ARM)
                .union(FINGER)
                .union(OBJECT),
        )
    }
    /// Parked: the arm and hand touch nothing while objects are dropped past them.
    pub(crate) fn none() -> InteractionGroups {
        groups(Group::NONE, Group::NONE)
    }
}

/// How far the upper finger link sits back from the pad's inner face (m).
const LINK_SETBACK: f32 = 0.006;
/// Each finger's mass (kg); lighter fingers made the joint solve unstable.
const FINGER_MASS: f32 = 0.3;

/// The URDF's links in topological order from the root, with their joints and visuals, and
/// each chain slot's index among the URDF's links.
fn kinematic_chain(
    robot: &urdf_rs::Robot,
    file: &UrdfFile,
) -> anyhow::Result<(Vec<ChainLink>, Vec<usize>)> {
    let links = &robot.links;
    let find_link = |name: &str| links.iter().position(|l| l.name == name);
    // Topological order from the root (the one link that is nobody's child).
    let root = links
        .iter()
        .position(|l| robot.joints.iter().all(|j| j.child.link != l.name))
        .context("robot urdf has no root link")?;
    let mut order = vec![root];
    let mut chain = vec![ChainLink {
        parent: None,
        origin: Pose::IDENTITY,
        axis: Vector::Z,
        joint: None,
        body: None,
        visuals: file.link_geometry(root)?.visuals,
    }];
    let mut cursor = 0;
    while cursor < order.len() {
        let parent_name = &links[order[cursor]].name;
        for joint in robot
            .joints
            .iter()
            .filter(|j| &j.parent.link == parent_name)
        {
            let child = find_link(&joint.child.link)
                .with_context(|| format!("joint {} names unknown link", joint.name))?;
            let [x, y, z] = joint.origin.xyz.0;
            let [r, p, yw] = joint.origin.rpy.0;
            let axis = joint.axis.xyz.0;
            let joint_index = match joint.joint_type {
                urdf_rs::JointType::Fixed => None,
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => Some(
                    JOINT_NAMES
                        .iter()
                        .position(|n| *n == joint.name)
                        .with_context(|| format!("unexpected ur5 joint '{}'", joint.name))?,
                ),
                ref other => bail!("joint {} has unsupported type {other:?}", joint.name),
            };
            chain.push(ChainLink {
                parent: Some(cursor),
                origin: Pose::from_parts(
                    Vector::new(x as f32, y as f32, z as f32),
                    rpy_rotation(r, p, yw),
                ),
                axis: Vector::new(axis[0] as f32, axis[1] as f32, axis[2] as f32).normalize(),
                joint: joint_index,
                body: None,
                visuals: file.link_geometry(child)?.visuals,
            });
            order.push(child);
        }
        cursor += 1;
    }
    Ok((chain, order))
}

/// One link of the URDF chain, in topological order.
#[derive(Debug, Clone)]
struct ChainLink {
    parent: Option<usize>,
    origin: Pose,
    axis: Vector,
    /// Index into the joint vector for revolute joints; None for fixed joints and the root.
    joint: Option<usize>,
    body: Option<RigidBodyHandle>,
    visuals: Vec<Visual>,
}

/// The arm: its URDF chain and the kinematic bodies that follow it.
pub(crate) struct Arm {
    base: Pose,
    chain: Vec<ChainLink>,
    tool0: usize,
    pub(crate) colliders: Vec<ColliderHandle>,
    pub(crate) joints: Joints,
}

/// Names of the six revolute joints, in joint-vector order.
pub(crate) const JOINT_NAMES: [&str; 6] = [
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
];

impl Arm {
    /// Loads the URDF: rapier3d-urdf builds the colliders, urdf-rs gives the chain and visuals.
    pub(crate) fn load(world: &mut PhysicsWorld, urdf: &str, base: Pose) -> anyhow::Result<Self> {
        let name = Path::new("bundled:ur5/ur5.urdf");
        let file = UrdfFile::parse(urdf, name)?;
        let options = UrdfLoaderOptions {
            make_roots_fixed: true,
            apply_imported_mass_props: false,
            squeeze_empty_fixed_links: false,
            ..Default::default()
        };
        // The bundled URDF names no mesh files, so the mesh directory is never read.
        let (urdf_robot, robot) = UrdfRobot::from_str(urdf, options, Path::new("."))
            .with_context(|| format!("loading robot {}", name.display()))?;

        let (mut chain, order) = kinematic_chain(&robot, &file)?;
        let links = &robot.links;
        let tool0 = order
            .iter()
            .position(|&l| links[l].name == "tool0")
            .context("robot urdf has no tool0 link")?;

        let mut colliders = Vec::new();
        for link in urdf_robot.links {
            let Some(slot) = order.iter().position(|&l| l == link.urdf_link_index) else {
                continue;
            };
            let mut body = link.body;
            body.set_body_type(RigidBodyType::KinematicPositionBased, true);
            let handle = world.insert_body(body);
            for c in link.colliders {
                let mut collider = c.collider;
                collider.set_collision_groups(groups::arm());
                collider.set_active_collision_types(
                    ActiveCollisionTypes::default() | ActiveCollisionTypes::KINEMATIC_FIXED,
                );
                colliders.push(world.insert_collider(collider, Some(handle)));
            }
            chain[slot].body = Some(handle);
        }
        let mut arm = Self {
            base,
            chain,
            tool0,
            colliders,
            joints: crate::sim::kinematics::HOME_JOINTS,
        };
        arm.teleport(world, crate::sim::kinematics::HOME_JOINTS);
        Ok(arm)
    }

    /// World pose of every chain link for joint values `q`.
    fn link_poses(&self, q: &Joints) -> Vec<Pose> {
        let mut poses: Vec<Pose> = Vec::with_capacity(self.chain.len());
        for link in &self.chain {
            let pose = match link.parent {
                None => self.base,
                Some(p) => {
                    let turn = link.joint.map_or(Rotation::IDENTITY, |j| {
                        Rotation::from_axis_angle(link.axis, q[j] as f32)
                    });
                    poses[p] * link.origin * Pose::from_rotation(turn)
                }
            };
            poses.push(pose);
        }
        poses
    }

    /// World pose of tool0 from the URDF chain.
    pub(crate) fn tool0_pose(&self, q: &Joints) -> Pose {
        self.link_poses(q)[self.tool0]
    }

    /// Moves every link body to `q` at once; only for initial placement.
    pub(crate) fn teleport(&mut self, world: &mut PhysicsWorld, q: Joints) {
        for (link, pose) in self.chain.iter().zip(self.link_poses(&q)) {
            if let Some(body) = link.body.and_then(|h| world.bodies.get_mut(h)) {
                body.set_position(pose, true);
            }
        }
        self.joints = q;
    }

    /// Schedules the kinematic bodies to reach `q` at the end of the next step.
    pub(crate) fn drive(&mut self, world: &mut PhysicsWorld, q: Joints) {
        for (link, pose) in self.chain.iter().zip(self.link_poses(&q)) {
            if let Some(body) = link.body.and_then(|h| world.bodies.get_mut(h)) {
                body.set_next_kinematic_position(pose);
            }
        }
        self.joints = q;
    }

    /// Drawable pieces in world coordinates for the current joints.
    pub(crate) fn visuals(&self) -> impl Iterator<Item = (Pose, &Visual)> + '_ {
        let poses = self.link_poses(&self.joints);
        self.chain
            .iter()
            .zip(poses)
            .flat_map(|(link, pose)| link.visuals.iter().map(move |v| (pose, v)))
    }
}

/// The parallel-jaw gripper: a kinematic palm at tool0 and two motorised fingers.
pub(crate) struct Gripper {
    pub(crate) palm: RigidBodyHandle,
    pub(crate) palm_collider: ColliderHandle,
    pub(crate) fingers: [RigidBodyHandle; 2],
    pub(crate) finger_colliders: [Vec<ColliderHandle>; 2],
    pub(crate) pads: [ColliderHandle; 2],
    joints: [ImpulseJointHandle; 2],
    force: f32,
}

/// How far inside its resting point a closed finger's hold target lies (m); see
/// [`Gripper::hold`]. Long and soft: as a grasped object settles in the jaw the grip force
/// drops by only 5 % per millimetre (with 5 mm, marginal cap grasps on the mustard bottle
/// slipped out during the lift: 73 labelling rounds for 60 labels instead of 67).
const HOLD_SQUEEZE: f32 = 0.02;
/// Closing and opening speed of each finger (m/s).
const FINGER_SPEED: f32 = 0.15;
/// Gain of the force-based velocity motors: high, so that the motor saturates at the grip
/// force as soon as a finger is blocked instead of easing off near the target speed.
const FINGER_DAMPING: f32 = 1.0e8;

/// One finger as [`Gripper::new`] builds it: its body, the pad and the link that carry it,
/// and its prismatic joint to the palm.
struct Finger {
    body: RigidBodyHandle,
    pad: ColliderHandle,
    link: ColliderHandle,
    joint: ImpulseJointHandle,
}

impl Finger {
    /// The finger on `side` (+1 or −1 along tool0's y) of the open jaw.
    fn new(
        world: &mut PhysicsWorld,
        tool0: Pose,
        palm: RigidBodyHandle,
        side: f32,
        force: f32,
        pad_friction: f32,
    ) -> Self {
        // Finger frame: origin on the pad's inner face, on the closing axis; the finger
        // extends outward (away from the other finger) along `side`·y.
        let half_open = GRIPPER.max_opening / 2.0;
        let body = world.insert_body(
            RigidBodyBuilder::dynamic()
                .pose(tool0 * Pose::from_translation(Vector::new(0.0, side * half_open, 0.0)))
                // No CCD: its motion clamping hides the contact from the motor, which
                // then never builds up the grip force.
                .can_sleep(false),
        );
        // A contact with a held object that reads deeper than the box allows is a
        // narrow-phase misfire, dropped for the step (penetration.rs): one spun a held pear out
        // of the jaw on the way to bin 2. The link's contacts are screened like the pad's.
        let part = |half_length: f32, setback: f32, centre_z: f32| {
            ColliderBuilder::cuboid(
                GRIPPER.pad_width / 2.0,
                GRIPPER.pad_thickness / 2.0,
                half_length,
            )
            .translation(Vector::new(0.0, side * setback, centre_z))
            .mass(FINGER_MASS / 2.0)
            .friction(pad_friction)
            .friction_combine_rule(CoefficientCombineRule::Multiply)
            .collision_groups(groups::finger())
            .active_hooks(ActiveHooks::MODIFY_SOLVER_CONTACTS)
        };
        let pad = part(
            GRIPPER.pad_height / 2.0,
            GRIPPER.pad_thickness / 2.0,
            GRIPPER.tcp_offset - GRIPPER.pad_height / 2.0,
        );
        let pad = world.insert_collider(pad, Some(body));
        let link_length = GRIPPER.tcp_offset - GRIPPER.pad_height - GRIPPER.palm_length;
        let link = part(
            link_length / 2.0,
            LINK_SETBACK + GRIPPER.pad_thickness / 2.0,
            GRIPPER.palm_length + link_length / 2.0,
        );
        let link = world.insert_collider(link, Some(body));
        // Anchored at the pads: with the anchor up at the palm, the long lever arm to the
        // pad let rapier's joint solve absorb the motor force (1 N reached the object
        // instead of 40 N).
        let anchor = Vector::new(0.0, 0.0, GRIPPER.tcp_offset - GRIPPER.pad_height / 2.0);
        let joint = PrismaticJointBuilder::new(Vector::Y * side)
            .local_anchor1(anchor)
            .local_anchor2(anchor)
            .limits([0.0, half_open])
            .motor_model(MotorModel::AccelerationBased)
            .motor_velocity(FINGER_SPEED, FINGER_DAMPING)
            .motor_max_force(force)
            .contacts_enabled(false);
        let joint = world.insert_impulse_joint(palm, body, joint);
        Self {
            body,
            pad,
            link,
            joint,
        }
    }
}

impl Gripper {
    /// Builds the gripper open at `tool0`, with `force` newtons per finger.
    pub(crate) fn new(
        world: &mut PhysicsWorld,
        tool0: Pose,
        force: f32,
        pad_friction: f32,
    ) -> Self {
        let palm = world.insert_body(RigidBodyBuilder::kinematic_position_based().pose(tool0));
        let palm_collider = world.insert_collider(
            ColliderBuilder::cuboid(
                GRIPPER.palm_half_across,
                GRIPPER.palm_half_along,
                GRIPPER.palm_length / 2.0,
            )
            .translation(Vector::new(0.0, 0.0, GRIPPER.palm_length / 2.0))
            .collision_groups(groups::arm())
            // Its contacts are screened for the narrow phase's misfires, as the pads' are.
            .active_hooks(ActiveHooks::MODIFY_SOLVER_CONTACTS)
            .active_collision_types(
                ActiveCollisionTypes::default() | ActiveCollisionTypes::KINEMATIC_FIXED,
            ),
            Some(palm),
        );
        let [a, b] =
            [1.0f32, -1.0].map(|side| Finger::new(world, tool0, palm, side, force, pad_friction));
        Self {
            palm,
            palm_collider,
            fingers: [a.body, b.body],
            finger_colliders: [vec![a.pad, a.link], vec![b.pad, b.link]],
            pads: [a.pad, b.pad],
            joints: [a.joint, b.joint],
            force,
        }
    }

    /// Commands both finger motors: positive speed opens.
    fn command(&self, world: &mut PhysicsWorld, speed: f32) {
        for handle in self.joints {
            if let Some(joint) = world.impulse_joints.get_mut(handle, true) {
                joint
                    .data
                    .set_motor_model(JointAxis::LinX, MotorModel::AccelerationBased)
                    .set_motor_velocity(JointAxis::LinX, speed, FINGER_DAMPING)
                    .set_motor_max_force(JointAxis::LinX, self.force);
            }
        }
    }

    /// Once closed, holds each finger where it stopped, as the 2F-85's non-backdrivable drive
    /// does: a spring preloaded to the grip force toward a point [`HOLD_SQUEEZE`] further in.
    ///
    /// Two force-capped velocity motors pushing against each other leave the fingers and the
    /// object between them free to slide together along the closing line, so that the swing
    /// to bin 2 shook light objects out of the jaw. Held like this, a slide by x loads one
    /// finger less and leaves the other at the cap: a restoring force of x times the spring
    /// rate, while the grip stays bounded by `force`.
    pub(crate) fn hold(&self, world: &mut PhysicsWorld) {
        let stiffness = self.force / HOLD_SQUEEZE;
        // Critically damped for the finger's own mass.
        let damping = 2.0 * (stiffness * FINGER_MASS).sqrt();
        for (finger, handle) in self.fingers.iter().zip(self.joints) {
            let target = (self.finger_offset(world, *finger) - HOLD_SQUEEZE).max(0.0);
            if let Some(joint) = world.impulse_joints.get_mut(handle, true) {
                joint
                    .data
                    .set_motor_model(JointAxis::LinX, MotorModel::ForceBased)
                    .set_motor(JointAxis::LinX, target, 0.0, stiffness, damping)
                    .set_motor_max_force(JointAxis::LinX, self.force);
            }
        }
    }

    /// A finger's distance from the closing centre, which is also its joint coordinate (m).
    fn finger_offset(&self, world: &PhysicsWorld, finger: RigidBodyHandle) -> f32 {
        let palm = world.bodies[self.palm].position();
        palm.inverse_transform_point(world.bodies[finger].translation())
            .y
            .abs()
    }

    /// Starts closing with the bounded force.
    pub(crate) fn close(&self, world: &mut PhysicsWorld) {
        self.command(world, -FINGER_SPEED);
    }

    /// Starts opening.
    pub(crate) fn open(&self, world: &mut PhysicsWorld) {
        self.command(world, FINGER_SPEED);
    }

    /// Moves the palm with tool0 at the end of the next step.
    pub(crate) fn drive(&self, world: &mut PhysicsWorld, tool0: Pose) {
        if let Some(palm) = world.bodies.get_mut(self.palm) {
            palm.set_next_kinematic_position(tool0);
        }
    }

    /// Distance between the pads' inner faces (m).
    pub(crate) fn opening(&self, world: &PhysicsWorld) -> f32 {
        self.finger_offset(world, self.fingers[0]) + self.finger_offset(world, self.fingers[1])
    }

    /// Largest finger speed relative to the palm (m/s), to tell when a close has finished.
    pub(crate) fn finger_speed(&self, world: &PhysicsWorld) -> f32 {
        let palm = &world.bodies[self.palm];
        self.fingers
            .iter()
            .map(|&f| (world.bodies[f].linvel() - palm.linvel()).length())
            .fold(0.0, f32::max)
    }

    /// Sets every gripper collider's interaction groups (parking disables them).
    pub(crate) fn set_collisions(&self, world: &mut PhysicsWorld, enabled: bool) {
        let mut set = |h: ColliderHandle, g: InteractionGroups| {
            if let Some(c) = world.colliders.get_mut(h) {
                c.set_collision_groups(g);
            }
        };
        set(
            self.palm_collider,
            if enabled {
                groups::arm()
            } else {
                groups::none()
            },
        );
        for h in self.finger_colliders.iter().flatten() {
            set(
                *h,
                if enabled {
                    groups::finger()
                } else {
                    groups::none()
                },
            );
        }
    }

    /// The gripper's drawable boxes in world coordinates.
    pub(crate) fn drawables(&self, world: &PhysicsWorld) -> Vec<(Pose, Vector, [f32; 3])> {
        let mut out = Vec::new();
        for (h, color) in std::iter::once((self.palm_collider, [0.15, 0.15, 0.17])).chain(
            self.finger_colliders
                .iter()
                .flatten()
                .map(|h| (*h, [0.25, 0.25, 0.28])),
        ) {
            let c = &world.colliders[h];
            if let Some(cuboid) = c.shape().as_cuboid() {
                out.push((*c.position(), cuboid.half_extents, color));
            }
        }
        out
    }
}
