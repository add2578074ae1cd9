//! The physical workcell in rapier3d: ground, two totes, the UR5 on its pedestal, the gripper and dropped objects.
//!
//! Everything here uses rapier's own math types (glam, f32); the closed-form IK in
//! `kinematics` works in nalgebra f64 and is converted at its call sites in `pick`.

mod arrange;
mod guard;
mod invariants;
pub(crate) mod kinematics;
mod penetration;
pub mod pick;
mod place;
pub mod push;
pub(crate) mod recording;
pub use recording::oblique_camera;
pub(crate) mod robot;
mod shapes;
mod stepping;

use anyhow::Context;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rapier3d::math::{Pose, Rotation, Vector};
use rapier3d::prelude::*;

use crate::assets::objects::ObjectModel;
use crate::grasp::tote::{self, Tote, PICK_TOTE, PLACE_TOTE};
use crate::vision::camera::Camera;
use crate::vision::render::{Drawable, Shape};
use penetration::penetration;
use robot::{groups, Arm, Gripper};
use shapes::shared_shape;

/// Physics rate (Hz). 240 Hz kept thin fingers from tunnelling through small objects.
pub(crate) const PHYSICS_HZ: f32 = 240.0;

/// Robot base position on top of the pedestal.
pub(crate) const ROBOT_BASE: Vector = Vector::new(0.0, 0.0, 0.4);

/// Parts a step is split into while the arm is held and an object moves faster than
/// `stepping::FAST_OBJECT_SPEED`. An object dropped 0.2–0.7 m lands at 2–3.7 m/s, 8–15 mm per step, and
/// a landing (or a drill landing on a thin clamp) left an object 5–10 mm inside the floor for a
/// step or two: 15 times in the drops of the soak's 200 scenes. With quarter steps there were
/// none; halves left 3, and quarters only above 0.5 m/s left 1 (the soaks in the measurement
/// diary, `git show 2c24231:docs/history.md`; today's soak: BENCHMARKS.md#physics-soak).
pub(crate) const FAST_SUBSTEPS: u32 = 4;
const PEDESTAL_RADIUS: f32 = 0.0734;
/// How far below a tote's floor top an object's centre may be and still count as inside (m).
const LOCATE_BELOW_FLOOR: f32 = 0.01;
/// How far above a tote's wall tops an object's centre may be and still count as inside (m).
const LOCATE_ABOVE_WALLS: f32 = 0.3;

/// Friction of the totes, ground and pads; combined by multiplication, so contacts take the object's μ.
pub(crate) const ENVIRONMENT_FRICTION: f32 = 1.0;

/// Angular damping of objects (1/s).
pub(crate) const OBJECT_ANGULAR_DAMPING: f32 = 1.0;
/// Longest wait for a dropped object to settle before the next falls (s).
const MAX_SETTLE_SECONDS: f32 = 4.0;
/// Drop positions (the reference's): x and y over bin 1's middle, height above the ground (m).
const DROP_X: [f32; 2] = [0.38, 0.62];
/// See [`DROP_X`].
const DROP_Y: [f32; 2] = [-0.22, 0.22];
/// See [`DROP_X`].
const DROP_HEIGHT: [f32; 2] = [0.2, 0.7];

/// Settings of a workcell that users may change.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct WorkcellConfig {
    /// Grip force per finger (N). Default 40.
    pub(crate) grip_force: f32,
    /// Pad friction, multiplied with the object's. Default 1.0.
    pub(crate) pad_friction: f32,
}

impl Default for WorkcellConfig {
    fn default() -> Self {
        Self {
            grip_force: 40.0,
            pad_friction: 1.0,
        }
    }
}

/// An object in the scene.
pub(crate) struct SceneObject {
    /// The model it was built from.
    pub(crate) model: ObjectModel,
    /// Its rigid body.
    pub(crate) body: RigidBodyHandle,
    /// Its compound collider.
    pub(crate) collider: ColliderHandle,
    /// Mask id in rendered frames (index + 1).
    pub(crate) id: u16,
    /// Its centre of mass in its body's frame (uniform density), which locates it: a mesh's
    /// frame can lie outside the object (the public YCB clamp's lies 28–57 mm below its mesh).
    pub(crate) centre: Vector,
}

/// Where an object ended up: resting inside a tote's inner volume, or lost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ObjectLocation {
    /// Resting inside bin 1.
    Bin1,
    /// Resting inside bin 2.
    Bin2,
    /// Anywhere else.
    Lost,
}

/// The simulated workcell.
pub struct Workcell {
    pub(crate) world: PhysicsWorld,
    pub(crate) arm: Arm,
    pub(crate) gripper: Gripper,
    pub(crate) objects: Vec<SceneObject>,
    /// Shared with the recording's snapshots, which render it once per workcell.
    scenery: std::sync::Arc<[Drawable]>,
    environment: Vec<ColliderHandle>,
    steps: u64,
    recorder: Option<Recorder>,
    camera: Camera,
    /// The camera over bin 2, which the place reads.
    place_camera: Camera,
    /// The invariant violations seen so far, when watching for them.
    violations: Option<Vec<String>>,
    /// What the workcell is doing, for the violations' messages.
    phase: &'static str,
    /// Whether the arm was last told to stay where it is (see [`Workcell::step`]).
    arm_held: bool,
    /// Parts a step is split into while an object moves fast (see [`Workcell::step`]).
    fast_substeps: u32,
}

/// Sends a snapshot of the scene every few steps while the arm moves (for `--record`) to a
/// thread that renders it: the physics runs on one core, and rendering a frame in line with it
/// took about as long as the 24 steps between frames.
struct Recorder {
    /// Snapshot every this many physics steps.
    every: u64,
    /// Where the snapshots go, in step order.
    footage: recording::FootageSender,
    /// The render thread of [`Workcell::start_recording`], which returns the frames once
    /// `footage` is closed; `None` when the footage goes to a recording the caller owns.
    renderer: Option<std::thread::JoinHandle<Vec<image::RgbImage>>>,
}

impl Workcell {
    /// Builds the empty workcell with the robot at home.
    pub fn new(config: &WorkcellConfig) -> anyhow::Result<Self> {
        let mut world = PhysicsWorld::new();
        configure_solver(&mut world);
        let (scenery, environment) = build_scenery(&mut world);
        let arm = Arm::load(
            &mut world,
            crate::assets::UR5_URDF,
            Pose::from_translation(ROBOT_BASE),
        )?;
        let tool0 = arm.tool0_pose(&arm.joints);
        let gripper = Gripper::new(&mut world, tool0, config.grip_force, config.pad_friction);
        Ok(Self {
            world,
            arm,
            gripper,
            objects: Vec::new(),
            scenery: scenery.into(),
            environment,
            steps: 0,
            recorder: None,
            camera: Camera::top_down(),
            place_camera: Camera::place_top_down(),
            violations: None,
            phase: "idle",
            arm_held: true,
            fast_substeps: FAST_SUBSTEPS,
        })
    }

    /// The top-down camera that every observation of the bin is taken with.
    pub(crate) fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Simulated time so far (s).
    pub fn time(&self) -> f64 {
        self.steps as f64 / PHYSICS_HZ as f64
    }

    /// The objects in the scene.
    pub(crate) fn objects(&self) -> &[SceneObject] {
        &self.objects
    }

    /// Pose of an object's body.
    pub fn object_pose(&self, index: usize) -> Pose {
        *self.world.bodies[self.objects[index].body].position()
    }

    /// World pose of tool0 for the current joints (URDF chain).
    pub(crate) fn tool0_pose(&self) -> Pose {
        self.arm.tool0_pose(&self.arm.joints)
    }

    /// Starts recording frames of the oblique view of the whole workcell every `every` steps,
    /// for [`Workcell::take_recording`] to return.
    pub(crate) fn start_recording(&mut self, every: u64) {
        let (footage, received) = std::sync::mpsc::channel();
        let renderer = std::thread::spawn(move || {
            let mut film = recording::ObliqueFilm::new();
            received
                .iter()
                .filter_map(|footage| match footage {
                    recording::Footage::Scene(snapshot) => Some(film.frame(&snapshot)),
                    recording::Footage::Inset(_) => None,
                })
                .collect()
        });
        self.recorder = Some(Recorder {
            every: every.max(1),
            footage,
            renderer: Some(renderer),
        });
    }

    /// Sends a snapshot of the scene to `footage` every `every` steps, until
    /// [`Workcell::take_recording`]; the caller's recording renders them, and the workcell never
    /// waits for it.
    pub(crate) fn record_into(&mut self, every: u64, footage: recording::FootageSender) {
        self.recorder = Some(Recorder {
            every: every.max(1),
            footage,
            renderer: None,
        });
    }

    /// Stops recording; the frames of [`Workcell::start_recording`] (none for
    /// [`Workcell::record_into`], whose frames are its recording's).
    pub(crate) fn take_recording(&mut self) -> Vec<image::RgbImage> {
        let Some(recorder) = self.recorder.take() else {
            return Vec::new();
        };
        drop(recorder.footage);
        // A render thread that panicked leaves no frames; the attempt itself is unharmed.
        recorder
            .renderer
            .map(|r| r.join().unwrap_or_default())
            .unwrap_or_default()
    }

    /// What a recording's frame shows now.
    pub(crate) fn snapshot(&self) -> recording::Snapshot {
        recording::Snapshot {
            scenery: self.scenery.clone(),
            moving: self.moving_drawables(),
        }
    }

    /// Adds an object at `pose`, at rest.
    pub fn add_object(&mut self, model: &ObjectModel, pose: Pose) -> anyhow::Result<usize> {
        let shapes = model
            .collisions
            .iter()
            .map(|c| Ok((c.pose, shared_shape(&c.shape)?)))
            .collect::<anyhow::Result<Vec<_>>>()
            .with_context(|| format!("building collision shape of {}", model.name))?;
        let body = self.world.insert_body(
            RigidBodyBuilder::dynamic()
                .pose(pose)
                .ccd_enabled(true)
                // Stands in for rolling resistance, which rapier lacks: without it a lying
                // can keeps rolling across the bin long after the camera image is taken.
                .angular_damping(OBJECT_ANGULAR_DAMPING),
        );
        let shape = SharedShape::compound(shapes);
        let centre = shape.mass_properties(1.0).local_com;
        let collider = self.world.insert_collider(
            ColliderBuilder::new(shape)
                .mass(model.mass)
                .friction(model.friction)
                .friction_combine_rule(CoefficientCombineRule::Multiply)
                .restitution(0.0)
                .collision_groups(groups::object()),
            Some(body),
        );
        let id = self.objects.len() as u16 + 1;
        self.objects.push(SceneObject {
            model: model.clone(),
            body,
            collider,
            id,
            centre,
        });
        Ok(self.objects.len() - 1)
    }

    /// Drops objects one after another into bin 1 from seeded random poses (docs/workcell.md), each
    /// settling before the next falls, with the parked arm's colliders switched off.
    pub fn drop_objects(&mut self, models: &[ObjectModel], seed: u64) -> anyhow::Result<()> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        self.set_robot_collisions(false);
        for model in models {
            let position = Vector::new(
                rng.random_range(DROP_X[0]..=DROP_X[1]),
                rng.random_range(DROP_Y[0]..=DROP_Y[1]),
                rng.random_range(DROP_HEIGHT[0]..=DROP_HEIGHT[1]),
            );
            let pi = std::f32::consts::PI;
            let rotation = Rotation::from_euler(
                rapier3d::glamx::EulerRot::ZYX,
                rng.random_range(-pi..=pi),
                rng.random_range(-pi..=pi),
                rng.random_range(-pi..=pi),
            );
            self.add_object(model, Pose::from_parts(position, rotation))?;
            self.enter("drop");
            self.settle(MAX_SETTLE_SECONDS);
        }
        self.set_robot_collisions(true);
        self.enter("idle");
        Ok(())
    }

    fn set_robot_collisions(&mut self, enabled: bool) {
        for &h in &self.arm.colliders {
            if let Some(c) = self.world.colliders.get_mut(h) {
                c.set_collision_groups(if enabled {
                    groups::arm()
                } else {
                    groups::none()
                });
            }
        }
        self.gripper.set_collisions(&mut self.world, enabled);
    }

    /// Everything drawable, in world coordinates; object ids are index + 1, the rest 0.
    pub fn drawables(&self) -> Vec<Drawable> {
        let mut out = self.scenery.to_vec();
        out.extend(self.moving_drawables());
        out
    }

    /// The drawables of the arm, the hand and the objects: [`Workcell::drawables`] without the
    /// scenery, in the same order.
    fn moving_drawables(&self) -> Vec<Drawable> {
        let mut out = Vec::new();
        for (pose, visual) in self.arm.visuals() {
            out.push(Drawable {
                shape: visual.shape.clone(),
                pose: pose * visual.pose,
                color: visual.color,
                id: 0,
            });
        }
        for (pose, half, color) in self.gripper.drawables(&self.world) {
            out.push(Drawable {
                shape: Shape::Cuboid { half_extents: half },
                pose,
                color,
                id: 0,
            });
        }
        for object in &self.objects {
            let pose = *self.world.bodies[object.body].position();
            for visual in &object.model.visuals {
                out.push(Drawable {
                    shape: visual.shape.clone(),
                    pose: pose * visual.pose,
                    color: visual.color,
                    id: object.id,
                });
            }
        }
        out
    }

    /// Renders the top-down camera (docs/camera.md).
    pub fn capture(&self) -> crate::vision::render::Frame {
        crate::vision::render::render(&self.camera, &self.drawables())
    }

    /// An object's centre of mass in the world.
    pub fn object_centre(&self, index: usize) -> Vector {
        self.object_pose(index)
            .transform_point(self.objects[index].centre)
    }

    /// Where an object is, by its centre of mass: inside a tote's inner volume, or lost. Not by
    /// its body's origin, which a mesh can put outside the object: the public YCB clamp resting
    /// upright on a floor had its origin 10 mm under the floor's top, and counted as lost from
    /// either bin.
    pub fn locate(&self, index: usize) -> ObjectLocation {
        let p = self.object_centre(index);
        let inside = |tote: &Tote| {
            (p.x - tote.center[0]).abs() <= tote.inner_half[0]
                && (p.y - tote.center[1]).abs() <= tote.inner_half[1]
                && p.z >= tote.floor_top - LOCATE_BELOW_FLOOR
                && p.z <= tote.wall_top + LOCATE_ABOVE_WALLS
        };
        if inside(&PICK_TOTE) {
            ObjectLocation::Bin1
        } else if inside(&PLACE_TOTE) {
            ObjectLocation::Bin2
        } else {
            ObjectLocation::Lost
        }
    }

    /// True when a collider of the environment (ground, totes) touches `collider`.
    pub(crate) fn touches_environment(&self, collider: ColliderHandle, tolerance: f32) -> bool {
        self.environment_penetration(collider) > tolerance
    }

    /// How deep `collider` is sunk into the environment (m); 0 when apart.
    pub(crate) fn environment_penetration(&self, collider: ColliderHandle) -> f32 {
        self.environment_penetration_beyond(collider, f32::NEG_INFINITY)
    }

    /// How deep `collider` is sunk into the environment (m), measured only against the boxes
    /// whose contact points (from before the last step) read deeper than `screen`; 0 otherwise.
    /// A check made every step screens this way: the exact query for every object resting on
    /// the floor made every empty_bin attempt measurably slower.
    pub(crate) fn environment_penetration_beyond(
        &self,
        collider: ColliderHandle,
        screen: f32,
    ) -> f32 {
        self.environment
            .iter()
            .map(|&env| penetration(&self.world, env, collider, screen))
            .fold(0.0, f32::max)
    }

    /// Largest normal force (N) between two colliders during the last step.
    pub(crate) fn contact_force(&self, a: ColliderHandle, b: ColliderHandle) -> f32 {
        self.world
            .contact_pair(a, b)
            .map_or(0.0, |pair| pair.total_impulse_magnitude() * PHYSICS_HZ)
    }
}

/// Whether two colliders are in contact (within `gap` metres).
pub(crate) fn in_contact(
    world: &PhysicsWorld,
    a: ColliderHandle,
    b: ColliderHandle,
    gap: f32,
) -> bool {
    world.contact_pair(a, b).is_some_and(|pair| {
        pair.manifolds()
            .iter()
            .flat_map(|m| m.points.iter())
            .any(|p| p.dist <= gap)
    })
}

/// The fixed scenery (ground, both totes, the pedestal): its drawables, and the environment's
/// colliders that the arm must not touch.
fn build_scenery(world: &mut PhysicsWorld) -> (Vec<Drawable>, Vec<ColliderHandle>) {
    let mut scenery = Scenery::default();
    scenery.add_fixed_box(
        world,
        Vector::new(0.0, 0.0, -0.05),
        Vector::new(2.0, 2.0, 0.05),
        [0.55, 0.55, 0.52],
    );
    for tote in [PICK_TOTE, PLACE_TOTE] {
        scenery.add_tote(world, &tote);
    }
    let pedestal_pose = Pose::from_parts(
        Vector::new(0.0, 0.0, ROBOT_BASE.z / 2.0),
        Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2),
    );
    world.insert_collider(
        ColliderBuilder::cylinder(ROBOT_BASE.z / 2.0, PEDESTAL_RADIUS)
            .position(pedestal_pose)
            .collision_groups(groups::pedestal()),
        None,
    );
    scenery.drawables.push(Drawable {
        shape: Shape::Cylinder {
            radius: PEDESTAL_RADIUS,
            half_height: ROBOT_BASE.z / 2.0,
        },
        pose: pedestal_pose,
        color: [0.5, 0.5, 0.5],
        id: 0,
    });
    (scenery.drawables, scenery.environment)
}

/// The scenery as [`build_scenery`] adds it.
#[derive(Default)]
struct Scenery {
    drawables: Vec<Drawable>,
    environment: Vec<ColliderHandle>,
}

impl Scenery {
    const TOTE_COLOR: [f32; 3] = [0.38, 0.39, 0.41];

    /// A fixed box of the environment, centred at `center` with half extents `half`.
    fn add_fixed_box(
        &mut self,
        world: &mut PhysicsWorld,
        center: Vector,
        half: Vector,
        color: [f32; 3],
    ) {
        let handle = world.insert_collider(
            ColliderBuilder::cuboid(half.x, half.y, half.z)
                .translation(center)
                .friction(ENVIRONMENT_FRICTION)
                .friction_combine_rule(CoefficientCombineRule::Multiply)
                .collision_groups(groups::environment())
                // Its contacts are screened for the narrow phase's misfires (depth.rs); a
                // hooked pair is never recycled, so its contacts are fresh every step.
                .active_hooks(ActiveHooks::MODIFY_SOLVER_CONTACTS),
            None,
        );
        self.environment.push(handle);
        self.drawables.push(Drawable {
            shape: Shape::Cuboid { half_extents: half },
            pose: Pose::from_translation(center),
            color,
            id: 0,
        });
    }

    /// A tote: its floor, then its walls across x, then across y.
    fn add_tote(&mut self, world: &mut PhysicsWorld, tote: &Tote) {
        let center = Vector::new(tote.center[0], tote.center[1], 0.0);
        let [hx, hy] = tote.inner_half;
        let t = tote::WALL_THICKNESS;
        self.add_fixed_box(
            world,
            Vector::new(center.x, center.y, tote.floor_top / 2.0),
            Vector::new(hx + t, hy + t, tote.floor_top / 2.0),
            Self::TOTE_COLOR,
        );
        let wall_half_z = (tote.wall_top - tote.floor_top) / 2.0;
        let wall_z = tote.floor_top + wall_half_z;
        for sx in [-1.0, 1.0] {
            self.add_fixed_box(
                world,
                Vector::new(center.x + sx * (hx + t / 2.0), center.y, wall_z),
                Vector::new(t / 2.0, hy + t, wall_half_z),
                Self::TOTE_COLOR,
            );
        }
        for sy in [-1.0, 1.0] {
            self.add_fixed_box(
                world,
                Vector::new(center.x, center.y + sy * (hy + t / 2.0), wall_z),
                Vector::new(hx, t / 2.0, wall_half_z),
                Self::TOTE_COLOR,
            );
        }
    }
}

/// Solver settings the grasps depend on.
fn configure_solver(world: &mut PhysicsWorld) {
    world.gravity = Vector::new(0.0, 0.0, -9.8);
    let p = &mut world.integration_parameters;
    p.dt = 1.0 / PHYSICS_HZ;
    p.friction_model = FrictionModel::Coulomb;
    // The default recycling distance (5 cm) lets fingers pass through small objects.
    p.normalized_contact_recycle_distance = 0.001;
    p.contact_softness = SpringCoefficients::new(120.0, 10.0);
    // Contacts with the fixed totes and ground. Rapier's default (60 Hz) is tuned for 60 Hz
    // steps and is softer than the contacts above: a finger coming down on an object pushed it
    // 5–50 mm into the floor before the protective stop, and objects under a load stayed 5 mm
    // deep for seconds. At 480 Hz the floor wins that squeeze and the finger's contact gives.
    p.static_contact_softness = SpringCoefficients::new(480.0, 10.0);
    p.num_solver_iterations = 8;
    // Rapier merges manifolds that share a normal into one cluster before solving them. Against
    // the floor and walls, clusters let a dropped hammer land 5–7 mm into the empty floor, and
    // held a mustard bottle resting by a wall between two of that wall's clusters with opposite
    // normals, each pushing 12 N·s a step, until one let go and the bottle shot off at 1.7 m/s,
    // 10.9 mm deep. Without clustering the soak found neither (BENCHMARKS.md#physics-soak).
    p.contact_clustering = false;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::kinematics::Ur5;
    use rand::Rng;

    #[test]
    fn urdf_chain_and_closed_form_kinematics_agree() {
        let cell = Workcell::new(&WorkcellConfig::default()).unwrap();
        let ur5 = Ur5::new(pick::to_isometry(&Pose::from_translation(ROBOT_BASE)));
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for _ in 0..200 {
            let q: crate::sim::kinematics::Joints =
                std::array::from_fn(|_| rng.random_range(-3.0..3.0));
            let urdf = cell.arm.tool0_pose(&q);
            let dh = ur5.forward(&q);
            let t = dh.translation.vector;
            let dh_t = Vector::new(t.x as f32, t.y as f32, t.z as f32);
            assert!((urdf.translation - dh_t).length() < 1e-4, "{q:?}");
            let r = dh.rotation;
            let dh_r = Rotation::from_xyzw(r.i as f32, r.j as f32, r.k as f32, r.w as f32);
            assert!(urdf.rotation.angle_between(dh_r) < 1e-4, "{q:?}");
        }
    }

    #[test]
    fn home_pose_parks_the_hand_outside_the_camera_view_of_the_bin() {
        let cell = Workcell::new(&WorkcellConfig::default()).unwrap();
        let tool0 = cell.tool0_pose().translation;
        assert!((tool0 - Vector::new(0.487, 0.109, 0.832)).length() < 0.002);
        // An empty bin renders with no robot pixels inside the tote's floor area.
        let frame = cell.capture();
        let camera = crate::vision::camera::Camera::top_down();
        let mut floor_pixels = 0;
        for v in 0..128 {
            for u in 0..128 {
                let p = camera.pixel_to_world(u, v, frame.depth_at(u, v));
                let over_floor = (p.x - PICK_TOTE.center[0]).abs() < PICK_TOTE.inner_half[0] - 0.01
                    && (p.y - PICK_TOTE.center[1]).abs() < PICK_TOTE.inner_half[1] - 0.01;
                if over_floor {
                    floor_pixels += 1;
                    assert!(
                        p.z < 0.03,
                        "something above the floor at pixel ({u}, {v}): {p:?}"
                    );
                }
            }
        }
        assert!(
            floor_pixels > 5000,
            "only {floor_pixels} pixels see the floor"
        );
    }

    #[test]
    fn objects_are_located_by_their_centre_of_mass_not_their_frame() {
        // A plate whose frame lies 40 mm below it, as the public YCB clamp's lies below its mesh.
        let plate = ObjectModel {
            name: "Plate".into(),
            mass: 0.1,
            friction: 0.5,
            collisions: vec![crate::assets::urdf::Collision {
                shape: crate::assets::urdf::CollisionShape::Cuboid {
                    half_extents: Vector::new(0.04, 0.04, 0.01),
                },
                pose: Pose::from_translation(Vector::new(0.0, 0.0, 0.04)),
            }],
            visuals: Vec::new(),
        };
        let mut cell = Workcell::new(&WorkcellConfig::default()).unwrap();
        for (x, expected) in [(0.5, ObjectLocation::Bin1), (-0.5, ObjectLocation::Bin2)] {
            // Lying on the floor, its frame 10 mm under the floor's top.
            let frame = Vector::new(x, 0.0, tote::FLOOR_TOP + 0.01 - 0.04);
            let i = cell
                .add_object(&plate, Pose::from_translation(frame))
                .unwrap();
            assert_eq!(cell.locate(i), expected);
            let centre = cell.object_centre(i);
            assert!((centre - (frame + Vector::new(0.0, 0.0, 0.04))).length() < 1e-6);
        }
    }

    #[test]
    fn objects_are_located_by_bin() {
        let mut cell = Workcell::new(&WorkcellConfig::default()).unwrap();
        let library = crate::assets::objects::ObjectLibrary::bundled();
        let ball = library.load("YcbTennisBall").unwrap();
        for (position, expected) in [
            (Vector::new(0.5, 0.1, 0.06), ObjectLocation::Bin1),
            (Vector::new(-0.6, -0.2, 0.06), ObjectLocation::Bin2),
            (Vector::new(0.0, 0.8, 0.04), ObjectLocation::Lost),
        ] {
            let i = cell
                .add_object(&ball, Pose::from_translation(position))
                .unwrap();
            assert_eq!(cell.locate(i), expected, "{position:?}");
        }
    }
}
