//! UR5 kinematics: forward kinematics, closed-form inverse kinematics and trapezoidal motion profiles.
//!
//! Conventions: SI units and radians throughout, world frame z up, `f64` everywhere. The arm is
//! described by the standard UR5 Denavit–Hartenberg parameters with
//! `T_i = Rz(q_i) · Tz(d_i) · Tx(a_i) · Rx(alpha_i)`. The robot base frame is DH frame 0 and sits at
//! [`Ur5::base`] in the world; DH frame 6 is `tool0`, whose z axis is the approach axis.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// A UR5 joint configuration in radians, shoulder pan (index 0) to wrist 3 (index 5).
pub(crate) type Joints = [f64; 6];

/// Home configuration, with the arm over the pick bin (+x side of the world).
pub(crate) const HOME_JOINTS: Joints = [-PI, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 0.0];

/// Place configuration, with the arm over the place bin (−x side of the world).
pub(crate) const PLACE_JOINTS: Joints = [0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 0.0];

/// Symmetric joint limit in radians: every joint must stay within `[-JOINT_LIMIT, JOINT_LIMIT]`.
pub(crate) const JOINT_LIMIT: f64 = TAU;

/// DH twist angles `alpha_i` of the UR5.
const DH_ALPHA: [f64; 6] = [FRAC_PI_2, 0.0, 0.0, FRAC_PI_2, -FRAC_PI_2, 0.0];

/// Largest tool0 position error (m) accepted when verifying an IK solution with `forward`.
const FK_POSITION_TOLERANCE: f64 = 1e-6;

/// Largest tool0 rotation error (rad) accepted when verifying an IK solution with `forward`.
const FK_ROTATION_TOLERANCE: f64 = 1e-6;

/// How far beyond ±1 an `acos` argument may drift through rounding before a branch is dropped.
const ACOS_TOLERANCE: f64 = 1e-9;

/// Below this `|sin q5|` the wrist is singular (joint 4 and joint 6 axes aligned) and q6 is free.
const WRIST_SINGULARITY: f64 = 1e-10;

/// Solutions closer than this (max-abs, rad) are reported once by `inverse_all`.
#[cfg(test)]
const DUPLICATE_TOLERANCE: f64 = 1e-9;

/// Inverse-kinematics failure.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum IkError {
    /// No closed-form solution reproduces the pose; `x`, `y`, `z` is the requested tool0 world position.
    #[error("pose at ({x:.3}, {y:.3}, {z:.3}) m is out of the ur5's reach")]
    Unreachable {
        /// World x of the requested tool0 position (m).
        x: f64,
        /// World y of the requested tool0 position (m).
        y: f64,
        /// World z of the requested tool0 position (m).
        z: f64,
    },
    /// The chosen solution puts a joint outside its limits (`joint` is the 0-based index into [`Joints`]).
    #[error("joint {joint} would be at {value:.3} rad, outside [{min:.3}, {max:.3}]")]
    OutOfLimit {
        /// 0-based joint index (0 = shoulder pan, 5 = wrist 3).
        joint: usize,
        /// The offending joint value (rad).
        value: f64,
        /// Lower limit (rad).
        min: f64,
        /// Upper limit (rad).
        max: f64,
    },
}

/// UR5 geometry (standard DH lengths, metres) and where its base frame (DH frame 0) sits in the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Ur5 {
    /// World pose of the robot base frame (DH frame 0).
    pub(crate) base: Isometry3<f64>,
    /// DH `d1`: shoulder height above the base frame.
    pub(crate) d1: f64,
    /// DH `a2`: upper-arm length (negative in the UR convention).
    pub(crate) a2: f64,
    /// DH `a3`: forearm length (negative in the UR convention).
    pub(crate) a3: f64,
    /// DH `d4`: shoulder-to-wrist lateral offset.
    pub(crate) d4: f64,
    /// DH `d5`: wrist 1 to wrist 2 offset.
    pub(crate) d5: f64,
    /// DH `d6`: wrist 3 to tool0 flange offset.
    pub(crate) d6: f64,
}

impl Ur5 {
    /// Standard UR5 with its base frame at `base` in the world.
    pub(crate) fn new(base: Isometry3<f64>) -> Self {
        Self {
            base,
            d1: 0.089159,
            a2: -0.425,
            a3: -0.39225,
            d4: 0.10915,
            d5: 0.09465,
            d6: 0.0823,
        }
    }

    /// World pose of tool0.
    pub(crate) fn forward(&self, q: &Joints) -> Isometry3<f64> {
        (0..6).fold(self.base, |pose, i| pose * self.link(i, q[i]))
    }

    /// World poses of DH frames 1..=6 (frame i is the frame after joint i; frame 6 == tool0). Used to place link bodies.
    ///
    /// Element `k` of the array is DH frame `k + 1`, so `frames(q)[5] == forward(q)`.
    #[cfg(test)]
    pub(crate) fn frames(&self, q: &Joints) -> [Isometry3<f64>; 6] {
        let mut out = [Isometry3::identity(); 6];
        let mut pose = self.base;
        for (i, frame) in out.iter_mut().enumerate() {
            pose *= self.link(i, q[i]);
            *frame = pose;
        }
        out
    }

    /// Every closed-form solution (up to 8) for a world tool0 pose, each wrapped into the joint limits.
    ///
    /// Angles are wrapped into `[-π, π]`. Every returned solution reproduces `target` through
    /// [`Ur5::forward`] to within 1e-6 m and 1e-6 rad; branches that do not (out of reach, or lost
    /// to rounding right at a reach boundary) are dropped, and coincident branches (at a singularity)
    /// are reported once. At a wrist singularity (`sin q5 ≈ 0`) q6 is free and is set to 0.
    /// An empty vector means the pose is unreachable.
    #[cfg(test)]
    pub(crate) fn inverse_all(&self, target: &Isometry3<f64>) -> Vec<Joints> {
        let mut out: Vec<Joints> = Vec::with_capacity(8);
        for q in self.candidates(target, 0.0) {
            let duplicate = out
                .iter()
                .any(|p| max_abs_distance(p, &q) < DUPLICATE_TOLERANCE);
            if !duplicate && self.reproduces(&q, target) {
                out.push(q);
            }
        }
        out
    }

    /// The closed-form solution nearest to `near` in joint space.
    ///
    /// Each joint of each closed-form branch is first wrapped into `[-π, π]`; then, per joint, the
    /// equivalent among `q`, `q - 2π`, `q + 2π` that lies within ±[`JOINT_LIMIT`] and is nearest to
    /// `near` is taken. Among the branches so adjusted, the one with the smallest **Euclidean (L2)**
    /// joint-space distance to `near` is returned. Every candidate is verified with
    /// [`Ur5::forward`] and rejected if its tool0 error exceeds 1e-6 m or 1e-6 rad. At a wrist
    /// singularity (`sin q5 ≈ 0`) q6 is free and `near[5]` is kept.
    ///
    /// # Errors
    /// [`IkError::Unreachable`] when no branch reproduces `target`; [`IkError::OutOfLimit`] if the
    /// selected solution has a joint outside ±[`JOINT_LIMIT`] (cannot happen for finite inputs,
    /// since every branch is wrapped into the limits, but is checked nonetheless).
    pub(crate) fn inverse(
        &self,
        target: &Isometry3<f64>,
        near: &Joints,
    ) -> Result<Joints, IkError> {
        let mut best: Option<(f64, Joints)> = None;
        for raw in self.candidates(target, near[5]) {
            let mut q = raw;
            for (value, &reference) in q.iter_mut().zip(near) {
                *value = nearest_equivalent(*value, reference);
            }
            if !self.reproduces(&q, target) {
                continue;
            }
            let distance = l2_distance(&q, near);
            if best.is_none_or(|(d, _)| distance < d) {
                best = Some((distance, q));
            }
        }
        let Some((_, q)) = best else {
            let p = target.translation.vector;
            return Err(IkError::Unreachable {
                x: p.x,
                y: p.y,
                z: p.z,
            });
        };
        if let Some((joint, &value)) = q
            .iter()
            .enumerate()
            .find(|(_, v)| v.is_nan() || v.abs() > JOINT_LIMIT)
        {
            return Err(IkError::OutOfLimit {
                joint,
                value,
                min: -JOINT_LIMIT,
                max: JOINT_LIMIT,
            });
        }
        Ok(q)
    }

    /// Homogeneous DH transform of link `i` (0-based) at joint angle `q`.
    fn link(&self, i: usize, q: f64) -> Isometry3<f64> {
        let d = [self.d1, 0.0, 0.0, self.d4, self.d5, self.d6];
        let a = [0.0, self.a2, self.a3, 0.0, 0.0, 0.0];
        dh_transform(q, d[i], a[i], DH_ALPHA[i])
    }

    /// Whether `forward(q)` matches `target` within the verification tolerances.
    fn reproduces(&self, q: &Joints, target: &Isometry3<f64>) -> bool {
        let reached = self.forward(q);
        let position_error = (reached.translation.vector - target.translation.vector).norm();
        let rotation_error = rotation_angle(&reached.rotation.rotation_to(&target.rotation));
        position_error <= FK_POSITION_TOLERANCE && rotation_error <= FK_ROTATION_TOLERANCE
    }

    /// Raw closed-form branches (unverified), each joint wrapped into `[-π, π]`.
    ///
    /// `free_q6` is used for q6 when the wrist is singular.
    fn candidates(&self, target: &Isometry3<f64>, free_q6: f64) -> Vec<Joints> {
        let mut out = Vec::with_capacity(8);
        // Everything below is in the base frame (DH frame 0).
        let local = self.base.inverse() * target;
        let rotation = local.rotation.to_rotation_matrix();
        let m = rotation.matrix();
        let x6: Vector3<f64> = m.column(0).into_owned();
        let y6: Vector3<f64> = m.column(1).into_owned();
        let z6: Vector3<f64> = m.column(2).into_owned();
        let p6 = local.translation.vector;

        // Wrist centre (frame 5 origin). Joints 2..4 are parallel to z1 = (s1, -c1, 0), so the wrist
        // centre lies at a fixed offset d4 along z1: p5 · z1 = d4.
        let p5 = p6 - self.d6 * z6;
        let radius = p5.x.hypot(p5.y);
        let Some(shoulder) = acos_checked(self.d4 / radius) else {
            return out;
        };
        let phi = p5.y.atan2(p5.x);

        for q1 in [phi + FRAC_PI_2 + shoulder, phi + FRAC_PI_2 - shoulder] {
            let (s1, c1) = q1.sin_cos();
            // z6 · z1 = cos q5, and p6 · z1 = d4 + d6 cos q5.
            let Some(wrist) = acos_checked((p6.x * s1 - p6.y * c1 - self.d4) / self.d6) else {
                continue;
            };
            for q5 in [wrist, -wrist] {
                let s5 = q5.sin();
                let q6 = if s5.abs() < WRIST_SINGULARITY {
                    free_q6
                } else {
                    // z1 expressed in frame 6 is (s5 c6, -s5 s6, c5).
                    let x = x6.x * s1 - x6.y * c1;
                    let y = y6.x * s1 - y6.y * c1;
                    (-y / s5).atan2(x / s5)
                };
                // Frame 4 seen from frame 1: a planar motion about z1 (angle q2+q3+q4, origin at
                // (a2 c2 + a3 c23, a2 s2 + a3 s23)) followed by Tz(d4) Rx(π/2).
                let t14 = self.link(0, q1).inverse()
                    * local
                    * self.link(5, q6).inverse()
                    * self.link(4, q5).inverse();
                let r14 = t14.rotation.to_rotation_matrix();
                let q234 = r14[(1, 0)].atan2(r14[(0, 0)]);
                let px = t14.translation.vector.x;
                let py = t14.translation.vector.y;
                let cos3 = (px * px + py * py - self.a2 * self.a2 - self.a3 * self.a3)
                    / (2.0 * self.a2 * self.a3);
                let Some(elbow) = acos_checked(cos3) else {
                    continue;
                };
                for q3 in [elbow, -elbow] {
                    let (s3, c3) = q3.sin_cos();
                    let q2 = py.atan2(px) - (self.a3 * s3).atan2(self.a2 + self.a3 * c3);
                    let q4 = q234 - q2 - q3;
                    out.push([q1, q2, q3, q4, q5, q6].map(wrap_angle));
                }
            }
        }
        out
    }
}

/// `Rz(theta) · Tz(d) · Tx(a) · Rx(alpha)`.
fn dh_transform(theta: f64, d: f64, a: f64, alpha: f64) -> Isometry3<f64> {
    let (s, c) = theta.sin_cos();
    let rotation = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), theta)
        * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), alpha);
    Isometry3::from_parts(Translation3::new(a * c, a * s, d), rotation)
}

/// Rotation angle of a unit quaternion in `[0, π]`, accurate for small angles.
fn rotation_angle(q: &UnitQuaternion<f64>) -> f64 {
    2.0 * q.imag().norm().atan2(q.scalar().abs())
}

/// `acos(x)`, clamping rounding overshoot up to [`ACOS_TOLERANCE`]; `None` outside (or NaN).
fn acos_checked(x: f64) -> Option<f64> {
    if x.abs() <= 1.0 + ACOS_TOLERANCE {
        Some(x.clamp(-1.0, 1.0).acos())
    } else {
        None
    }
}

/// Wrap an angle into `[-π, π]`.
fn wrap_angle(angle: f64) -> f64 {
    angle - TAU * (angle / TAU).round()
}

/// Among `angle` wrapped into `[-π, π]` and its ±2π equivalents within the joint limits, the one nearest `reference`.
fn nearest_equivalent(angle: f64, reference: f64) -> f64 {
    let wrapped = wrap_angle(angle);
    [wrapped, wrapped - TAU, wrapped + TAU]
        .into_iter()
        .filter(|c| c.abs() <= JOINT_LIMIT)
        .min_by(|a, b| (a - reference).abs().total_cmp(&(b - reference).abs()))
        .unwrap_or(wrapped)
}

fn l2_distance(a: &Joints, b: &Joints) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

fn max_abs_distance(a: &Joints, b: &Joints) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Trapezoidal profile along a scalar distance (used for straight Cartesian lines): returns s(t) in [0, length].
///
/// Accelerates at `max_acceleration` up to `max_velocity`, cruises, then decelerates symmetrically
/// to rest. When the distance is too short to reach `max_velocity` the profile is triangular (peak
/// velocity `sqrt(max_acceleration · |length|)`). A zero length gives a zero-duration profile. A
/// negative `length` runs from 0 down to `length` with the same timing as `|length|`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TrapezoidProfile {
    /// Signed target distance.
    length: f64,
    /// `|length|`.
    distance: f64,
    acceleration: f64,
    /// Cruise velocity (equal to `max_velocity` unless triangular).
    peak_velocity: f64,
    accel_time: f64,
    cruise_time: f64,
    duration: f64,
}

impl TrapezoidProfile {
    /// Time-optimal trapezoid (or triangle) covering `length` with the given limits.
    ///
    /// # Panics
    /// If `length` is not finite, or `max_velocity` / `max_acceleration` are not finite and positive.
    pub(crate) fn new(length: f64, max_velocity: f64, max_acceleration: f64) -> Self {
        assert!(
            length.is_finite(),
            "profile length must be finite, got {length}"
        );
        assert!(
            max_velocity.is_finite() && max_velocity > 0.0,
            "max_velocity must be finite and positive, got {max_velocity}"
        );
        assert!(
            max_acceleration.is_finite() && max_acceleration > 0.0,
            "max_acceleration must be finite and positive, got {max_acceleration}"
        );
        let distance = length.abs();
        // Distance spent accelerating to max_velocity and braking back to rest.
        let ramps = max_velocity * max_velocity / max_acceleration;
        let (peak_velocity, cruise_time) = if distance <= ramps {
            ((max_acceleration * distance).sqrt(), 0.0)
        } else {
            (max_velocity, (distance - ramps) / max_velocity)
        };
        let accel_time = peak_velocity / max_acceleration;
        Self {
            length,
            distance,
            acceleration: max_acceleration,
            peak_velocity,
            accel_time,
            cruise_time,
            duration: 2.0 * accel_time + cruise_time,
        }
    }

    /// Total time in seconds (0 for a zero length).
    pub(crate) fn duration(&self) -> f64 {
        self.duration
    }

    /// Distance covered at time `t` (clamped into `[0, duration]`): exactly 0 at the start and
    /// exactly `length` at the end, monotone in between.
    pub(crate) fn position(&self, t: f64) -> f64 {
        if t.is_nan() || t <= 0.0 {
            return 0.0;
        }
        if t >= self.duration {
            return self.length;
        }
        let a = self.acceleration;
        let s = if t < self.accel_time {
            0.5 * a * t * t
        } else if t < self.accel_time + self.cruise_time {
            0.5 * self.peak_velocity * self.accel_time + self.peak_velocity * (t - self.accel_time)
        } else {
            let remaining = self.duration - t;
            self.distance - 0.5 * a * remaining * remaining
        };
        let s = s.clamp(0.0, self.distance);
        if self.length < 0.0 {
            -s
        } else {
            s
        }
    }
}

/// Synchronised trapezoidal-velocity joint-space move: every joint starts and ends together,
/// the slowest joint moves at up to `max_velocity` rad/s with `max_acceleration` rad/s².
///
/// The path is the straight line from `from` to `to` in joint space, timed by a
/// [`TrapezoidProfile`] over the largest single-joint displacement: that joint (the one that
/// limits the move) reaches at most `max_velocity` / `max_acceleration`, and every other joint
/// moves proportionally slower.
#[derive(Debug, Clone)]
pub(crate) struct JointTrajectory {
    from: Joints,
    to: Joints,
    /// Largest absolute joint displacement (rad).
    span: f64,
    profile: TrapezoidProfile,
}

impl JointTrajectory {
    /// Plan a move from `from` to `to`.
    ///
    /// # Panics
    /// If a joint value is not finite, or `max_velocity` / `max_acceleration` are not finite and positive.
    pub(crate) fn new(from: Joints, to: Joints, max_velocity: f64, max_acceleration: f64) -> Self {
        let span = max_abs_distance(&from, &to);
        let span = if from.iter().chain(&to).all(|v| v.is_finite()) {
            span
        } else {
            f64::NAN
        };
        Self {
            from,
            to,
            span,
            profile: TrapezoidProfile::new(span, max_velocity, max_acceleration),
        }
    }

    /// Duration in seconds; 0 when `from == to`.
    pub(crate) fn duration(&self) -> f64 {
        self.profile.duration()
    }

    /// Joint configuration at time `t`, clamped into `[0, duration]`; `sample(0) == from` and
    /// `sample(duration) == to` exactly.
    pub(crate) fn sample(&self, t: f64) -> Joints {
        if t.is_nan() || t <= 0.0 {
            return self.from;
        }
        if t >= self.duration() {
            return self.to;
        }
        let fraction = self.profile.position(t) / self.span;
        std::array::from_fn(|i| self.from[i] + fraction * (self.to[i] - self.from[i]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn ur5() -> Ur5 {
        let base = rapier3d::math::Pose::from_translation(crate::sim::ROBOT_BASE);
        Ur5::new(crate::sim::pick::to_isometry(&base))
    }

    fn pose_errors(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
        let dp = (a.translation.vector - b.translation.vector).norm();
        let dr = rotation_angle(&a.rotation.rotation_to(&b.rotation));
        (dp, dr)
    }

    fn assert_vec(actual: Vector3<f64>, expected: [f64; 3], tol: f64, what: &str) {
        let expected = Vector3::from(expected);
        assert!(
            (actual - expected).norm() < tol,
            "{what}: got {actual:?}, expected {expected:?}"
        );
    }

    /// Tool pointing straight down (tool z = world −z) with the given yaw.
    fn downward(x: f64, y: f64, z: f64, yaw: f64) -> Isometry3<f64> {
        let rotation = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw)
            * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), PI);
        Isometry3::from_parts(Translation3::new(x, y, z), rotation)
    }

    fn angle_diff(a: f64, b: f64) -> f64 {
        wrap_angle(a - b).abs()
    }

    #[test]
    fn home_and_place_forward_kinematics() {
        let robot = ur5();

        let home = robot.forward(&HOME_JOINTS);
        assert_vec(
            home.translation.vector,
            [0.4869, 0.1092, 0.8319],
            1e-3,
            "home position",
        );
        let r = home.rotation.to_rotation_matrix();
        assert_vec(
            r.matrix().column(0).into_owned(),
            [0.0, -1.0, 0.0],
            1e-9,
            "home x",
        );
        assert_vec(
            r.matrix().column(1).into_owned(),
            [-1.0, 0.0, 0.0],
            1e-9,
            "home y",
        );
        assert_vec(
            r.matrix().column(2).into_owned(),
            [0.0, 0.0, -1.0],
            1e-9,
            "home z",
        );

        let place = robot.forward(&PLACE_JOINTS);
        assert_vec(
            place.translation.vector,
            [-0.4869, -0.1091, 0.8319],
            1e-3,
            "place position",
        );
        let r = place.rotation.to_rotation_matrix();
        assert_vec(
            r.matrix().column(2).into_owned(),
            [0.0, 0.0, -1.0],
            1e-9,
            "place z",
        );
    }

    #[test]
    fn frames_end_at_tool0_and_start_at_shoulder() {
        let robot = Ur5::new(Isometry3::new(
            Vector3::new(0.3, -0.2, 0.5),
            Vector3::new(0.1, -0.2, 0.7),
        ));
        let q = [0.3, -1.2, 1.1, -0.4, 0.9, -2.0];
        let frames = robot.frames(&q);
        let (dp, dr) = pose_errors(&frames[5], &robot.forward(&q));
        assert!(dp < 1e-12 && dr < 1e-12);
        // Frame 1 origin is d1 along the base z axis, whatever q1 is.
        let shoulder = robot.base * nalgebra::Point3::new(0.0, 0.0, robot.d1);
        assert!((frames[0].translation.vector - shoulder.coords).norm() < 1e-12);
        // Frames 1..3 are separated by |a2| and |a3|.
        let upper = (frames[1].translation.vector - frames[0].translation.vector).norm();
        let fore = (frames[2].translation.vector - frames[1].translation.vector).norm();
        assert!((upper - 0.425).abs() < 1e-12 && (fore - 0.39225).abs() < 1e-12);
    }

    #[test]
    fn ik_round_trip_over_both_bins() {
        let robot = ur5();
        let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_0005);
        let mut worst = (0.0_f64, 0.0_f64);
        let mut count = 0;
        for (x_range, near) in [(0.25..=0.75, HOME_JOINTS), (-0.75..=-0.25, PLACE_JOINTS)] {
            for _ in 0..600 {
                let target = downward(
                    rng.random_range(x_range.clone()),
                    rng.random_range(-0.35..=0.35),
                    rng.random_range(0.20..=0.75),
                    rng.random_range(-PI..=PI),
                );
                let q = robot
                    .inverse(&target, &near)
                    .unwrap_or_else(|e| panic!("IK failed for {target:?}: {e}"));
                assert!(q.iter().all(|v| v.abs() <= JOINT_LIMIT));
                let (dp, dr) = pose_errors(&robot.forward(&q), &target);
                assert!(dp < 1e-4 && dr < 1e-4, "FK(IK) error {dp} m, {dr} rad");
                worst = (worst.0.max(dp), worst.1.max(dr));
                count += 1;
            }
        }
        assert!(count >= 1000);
        eprintln!(
            "worst FK(IK) error over {count} poses: {:e} m, {:e} rad",
            worst.0, worst.1
        );
    }

    #[test]
    fn ik_with_rotated_base() {
        let robot = Ur5::new(Isometry3::new(
            Vector3::new(1.0, 2.0, 0.3),
            Vector3::new(0.0, 0.0, 2.0),
        ));
        let q = [1.0, -1.3, 1.7, -2.0, -1.4, 0.5];
        let target = robot.forward(&q);
        let solved = robot.inverse(&target, &q).expect("reachable");
        assert!(max_abs_distance(&solved, &q) < 1e-6, "{solved:?} vs {q:?}");
    }

    #[test]
    fn ik_returns_near_configuration() {
        let robot = ur5();
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..300 {
            let q: Joints = std::array::from_fn(|i| HOME_JOINTS[i] + rng.random_range(-0.3..=0.3));
            let solved = robot.inverse(&robot.forward(&q), &q).expect("reachable");
            assert!(
                max_abs_distance(&solved, &q) < 1e-6,
                "IK(FK(q)) = {solved:?}, q = {q:?}"
            );
        }
    }

    #[test]
    fn inverse_all_finds_eight_distinct_solutions() {
        let robot = ur5();
        let q = [0.4, -1.1, 1.3, -0.9, 1.1, 0.6];
        let target = robot.forward(&q);
        let solutions = robot.inverse_all(&target);
        assert_eq!(solutions.len(), 8, "{solutions:#?}");
        for (i, a) in solutions.iter().enumerate() {
            assert!(a.iter().all(|v| v.abs() <= PI + 1e-12));
            let (dp, dr) = pose_errors(&robot.forward(a), &target);
            assert!(dp < 1e-6 && dr < 1e-6);
            for b in &solutions[..i] {
                let separation = (0..6).map(|j| angle_diff(a[j], b[j])).fold(0.0, f64::max);
                assert!(separation > 1e-3, "duplicate solutions {a:?} {b:?}");
            }
        }
        assert!(solutions
            .iter()
            .any(|s| (0..6).all(|j| angle_diff(s[j], q[j]) < 1e-9)));
    }

    #[test]
    fn wrist_singularity_keeps_near_q6() {
        let robot = ur5();
        let q = [0.4, -1.1, 1.3, -0.9, 0.0, 0.6];
        let target = robot.forward(&q);
        let near = [0.4, -1.1, 1.3, -0.9, 0.0, 1.5];
        let solved = robot.inverse(&target, &near).expect("reachable");
        assert!((solved[5] - 1.5).abs() < 1e-12);
        let (dp, dr) = pose_errors(&robot.forward(&solved), &target);
        assert!(dp < 1e-6 && dr < 1e-6);
        assert!(!robot.inverse_all(&target).is_empty());
    }

    #[test]
    fn unreachable_poses_are_reported() {
        let robot = ur5();
        let far = downward(2.0, 0.0, 0.4, 0.0);
        assert_eq!(
            robot.inverse(&far, &HOME_JOINTS),
            Err(IkError::Unreachable {
                x: 2.0,
                y: 0.0,
                z: 0.4
            })
        );
        assert!(robot.inverse_all(&far).is_empty());
        // Wrist centre on the base axis (closer than d4): no shoulder solution.
        let over_base = downward(0.0, 0.0, 0.9, 0.0);
        assert!(matches!(
            robot.inverse(&over_base, &HOME_JOINTS),
            Err(IkError::Unreachable { .. })
        ));
        let message = IkError::Unreachable {
            x: 2.0,
            y: 0.0,
            z: 0.4,
        }
        .to_string();
        assert_eq!(
            message,
            "pose at (2.000, 0.000, 0.400) m is out of the ur5's reach"
        );
        let message = IkError::OutOfLimit {
            joint: 2,
            value: 7.0,
            min: -JOINT_LIMIT,
            max: JOINT_LIMIT,
        }
        .to_string();
        assert_eq!(
            message,
            "joint 2 would be at 7.000 rad, outside [-6.283, 6.283]"
        );
    }

    #[test]
    fn nearest_equivalent_uses_two_pi_shifts() {
        assert!((nearest_equivalent(3.0, -3.0) - (3.0 - TAU)).abs() < 1e-12);
        assert!((nearest_equivalent(-3.0, 6.0) - (TAU - 3.0)).abs() < 1e-12);
        // 0.5 + 2π would exceed the joint limit, so 0.5 itself is the nearest admissible value.
        assert!((nearest_equivalent(0.5, 100.0) - 0.5).abs() < 1e-12);
        assert!((nearest_equivalent(-3.0, 100.0) - (TAU - 3.0)).abs() < 1e-12);
        assert!((nearest_equivalent(7.0, 0.0) - (7.0 - TAU)).abs() < 1e-12);
    }

    #[test]
    fn joint_trajectory_properties() {
        let from = HOME_JOINTS;
        let to = [-2.5, -1.2, 1.9, -1.0, -1.2, 0.8];
        let (v, a) = (1.0, 2.0);
        let trajectory = JointTrajectory::new(from, to, v, a);
        let duration = trajectory.duration();
        assert!(duration > 0.0);
        assert_eq!(trajectory.sample(0.0), from);
        assert_eq!(trajectory.sample(-1.0), from);
        assert_eq!(trajectory.sample(duration), to);
        assert_eq!(trajectory.sample(duration + 1.0), to);

        let dt = 1e-3;
        let steps = (duration / dt).ceil() as usize;
        let mut previous = trajectory.sample(0.0);
        let mut fastest = 0.0_f64;
        for k in 1..=steps {
            let current = trajectory.sample(k as f64 * dt);
            for j in 0..6 {
                let speed = (current[j] - previous[j]).abs() / dt;
                assert!(speed <= v + 1e-9, "joint {j} at {speed} rad/s");
                fastest = fastest.max(speed);
            }
            previous = current;
        }
        // The move is long enough to cruise at the limit.
        assert!(fastest > 0.99 * v);

        let mut last = 0.0;
        for k in 0..=200 {
            let mut target = from;
            target[2] += 0.02 * k as f64;
            let d = JointTrajectory::new(from, target, v, a).duration();
            assert!(d >= last, "duration not monotone at step {k}");
            last = d;
        }

        let still = JointTrajectory::new(from, from, v, a);
        assert_eq!(still.duration(), 0.0);
        assert_eq!(still.sample(0.0), from);
        assert_eq!(still.sample(1.0), from);
    }

    #[test]
    fn trapezoid_profile_shapes() {
        let (v, a) = (1.0, 2.0);
        // Long move: trapezoid, T = L/v + v/a.
        let long = TrapezoidProfile::new(2.0, v, a);
        assert!((long.duration() - 2.5).abs() < 1e-12);
        assert_eq!(long.position(0.0), 0.0);
        assert_eq!(long.position(long.duration()), 2.0);
        assert!((long.position(1.25) - 1.0).abs() < 1e-12);

        // Short move: triangle, T = 2 sqrt(L/a), peak speed sqrt(a L) < v.
        let short = TrapezoidProfile::new(0.01, v, a);
        assert!((short.duration() - 2.0 * (0.01_f64 / a).sqrt()).abs() < 1e-12);
        assert!((short.position(short.duration() / 2.0) - 0.005).abs() < 1e-12);
        assert_eq!(short.position(short.duration()), 0.01);

        // Exactly at the trapezoid/triangle boundary both formulas agree.
        let edge = TrapezoidProfile::new(v * v / a, v, a);
        assert!((edge.duration() - 2.0 * v / a).abs() < 1e-12);

        let zero = TrapezoidProfile::new(0.0, v, a);
        assert_eq!(zero.duration(), 0.0);
        assert_eq!(zero.position(0.0), 0.0);
        assert_eq!(zero.position(1.0), 0.0);

        let negative = TrapezoidProfile::new(-0.3, v, a);
        assert_eq!(negative.position(negative.duration()), -0.3);

        for profile in [long, short] {
            let mut last = 0.0;
            let mut t = 0.0;
            while t <= profile.duration() + 0.01 {
                let s = profile.position(t);
                assert!(s >= last && s <= profile.distance);
                let speed = (s - last) / 1e-3;
                assert!(speed <= v + 1e-9);
                last = s;
                t += 1e-3;
            }
        }
    }
}
