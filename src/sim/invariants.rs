//! The soak's physics invariants, checked after every step when asked: every object's pose and
//! velocity finite, and none sunk into the ground or a tote.

use super::Workcell;

/// The soak's limit on how deep an object may sink into the ground or a tote (m).
pub const MAX_SINK: f32 = 0.005;
/// Violations kept per check before the rest are dropped.
const MAX_VIOLATIONS: usize = 20;
impl Workcell {
    /// Checks the physics after every step from now on: every body's pose and velocity finite,
    /// and no object sunk deeper than [`MAX_SINK`] into the ground or a tote. Slower; for the
    /// soak test.
    pub fn watch_invariants(&mut self) {
        self.violations.get_or_insert_with(Vec::new);
    }

    /// The violations seen since the last call, each naming the object and the time.
    pub fn take_violations(&mut self) -> Vec<String> {
        self.violations
            .as_mut()
            .map(std::mem::take)
            .unwrap_or_default()
    }

    /// Names what the workcell does from now on, for the violations' messages.
    pub(super) fn enter(&mut self, phase: &'static str) {
        self.phase = phase;
    }

    pub(super) fn check_invariants(&mut self) {
        let t = self.time();
        let phase = self.phase;
        let mut found = Vec::new();
        for object in &self.objects {
            let body = &self.world.bodies[object.body];
            let name = &object.model.name;
            let finite = body.translation().is_finite()
                && body.rotation().is_finite()
                && body.linvel().is_finite()
                && body.angvel().is_finite();
            if !finite {
                found.push(format!(
                    "t {t:.3} s ({phase}): {name} has a non-finite pose or velocity"
                ));
                continue;
            }
            let sunk = self.environment_penetration(object.collider);
            if sunk > MAX_SINK {
                let at = body.translation();
                found.push(format!(
                    "t {t:.3} s ({phase}): {name} is {:.1} mm inside the ground or a tote, at ({:.3}, {:.3}, {:.3}) m moving {:.2} m/s",
                    sunk * 1e3,
                    at.x,
                    at.y,
                    at.z,
                    body.linvel().length()
                ));
            }
        }
        if let Some(violations) = &mut self.violations {
            // The first few say what went wrong; a stuck object would repeat every step.
            let room = MAX_VIOLATIONS.saturating_sub(violations.len());
            violations.extend(found.into_iter().take(room));
        }
    }
}
