//! Failure suppression (`--n-past-action N`): the last N executed grasps, and how they lower
//! the network's maps before the next choice (docs/evaluation.md).

use std::collections::VecDeque;

use crate::grasp::rotate::rotate_point;
use crate::grasp::{angle_bin, bin_angle, PixelGrasp, BINS};
use crate::model::maps::AffordanceMaps;

/// How failure suppression lowers the maps around past actions.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub(crate) struct SuppressionConfig {
    /// Actions remembered (the user's `--n-past-action`); 0 turns suppression off.
    pub(crate) remember: usize,
    /// Standard deviation of the subtracted Gaussian, in pixels.
    pub(crate) sigma_px: f32,
    /// Lower the rotations within this many bins of the past action's (circularly, 22.5° each):
    /// 0 = its own rotation only, 4 = all 8.
    pub(crate) rotation_reach: usize,
    /// The height of the Gaussian subtracted from the rotations beyond `rotation_reach` (0 =
    /// leave them alone): a partial lowering makes spots that failed at any angle wait until
    /// the untried ones have had their turn, without ruling them out. Left out of reports and
    /// trial manifests when 0, so that those written before it existed still match.
    #[serde(skip_serializing_if = "is_zero")]
    pub(crate) other_rotations: f32,
    /// Whether successful actions enter the memory too.
    pub(crate) remember_successes: bool,
}

fn is_zero(value: &f32) -> bool {
    *value == 0.0
}

impl Default for SuppressionConfig {
    /// The measured choice (BENCHMARKS.md#failure-suppression): σ = 4 px, the failed
    /// rotation only, failures only; `remember` 0 (off) until the user asks.
    fn default() -> Self {
        Self {
            remember: 0,
            sigma_px: 4.0,
            rotation_reach: 0,
            other_rotations: 0.0,
            remember_successes: false,
        }
    }
}

/// The last N executed grasps and the map lowering they cause. Any policy's grasps are kept, so
/// that the oracle can read them too (it orders objects by them instead of lowering maps).
#[derive(Debug, Clone)]
pub(crate) struct Suppression {
    config: SuppressionConfig,
    past: VecDeque<PixelGrasp>,
}

impl Suppression {
    /// An empty memory.
    pub(crate) fn new(config: SuppressionConfig) -> Self {
        Self {
            config,
            past: VecDeque::new(),
        }
    }

    /// Remembers an executed grasp (a no-op for successes unless configured, and when off).
    pub(crate) fn record(&mut self, grasp: PixelGrasp, success: bool) {
        if self.config.remember == 0 || (success && !self.config.remember_successes) {
            return;
        }
        if self.past.len() == self.config.remember {
            self.past.pop_front();
        }
        self.past.push_back(grasp);
    }

    /// The remembered grasps, oldest first.
    pub(crate) fn past(&self) -> impl Iterator<Item = &PixelGrasp> {
        self.past.iter()
    }

    /// Subtracts a unit-peak Gaussian around each remembered action in the rotations within
    /// reach, and one of `other_rotations`' height in the rest, and clips to [0, 1]. The
    /// action's original-image grasp centre is carried into each rotated frame, so all bins see
    /// the same spot on the object.
    pub(crate) fn apply(&self, maps: &mut AffordanceMaps) {
        for past in &self.past {
            let centre = [past.u as f32 + 0.5, past.v as f32 + 0.5];
            let past_bin = angle_bin(past.angle_deg);
            for bin in 0..BINS {
                let apart = (bin + BINS - past_bin) % BINS;
                let peak = if apart.min(BINS - apart) <= self.config.rotation_reach {
                    1.0
                } else {
                    self.config.other_rotations
                };
                if peak <= 0.0 {
                    continue;
                }
                let rotated = rotate_point(centre, -bin_angle(bin), maps.size());
                maps.lower_around(bin, rotated, self.config.sigma_px, peak);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::maps::tests::bumpy_maps;
    use crate::model::maps::Choice;

    #[test]
    fn with_one_remembered_action_the_same_pixel_is_never_chosen_twice_in_a_row() {
        for rotation_reach in [0, 1, 4] {
            let raw = bumpy_maps();
            let mut memory = Suppression::new(SuppressionConfig {
                remember: 1,
                rotation_reach,
                ..SuppressionConfig::default()
            });
            let mut previous: Option<Choice> = None;
            for _ in 0..20 {
                let mut maps = raw.clone();
                memory.apply(&mut maps);
                let choice = maps.choose();
                if let Some(p) = previous {
                    assert!(
                        (p.bin, p.rotated) != (choice.bin, choice.rotated),
                        "rotation_reach {rotation_reach}: chose {choice:?} twice in a row"
                    );
                }
                memory.record(choice.grasp, false);
                previous = Some(choice);
            }
        }
    }

    #[test]
    fn suppression_moves_the_choice_to_the_next_best_spot_and_forgets_old_actions() {
        let raw = bumpy_maps();
        let mut memory = Suppression::new(SuppressionConfig {
            remember: 2,
            rotation_reach: 4,
            ..SuppressionConfig::default()
        });
        let first = raw.choose();
        assert_eq!((first.grasp.u, first.grasp.v), (40, 60));
        memory.record(first.grasp, false);
        let mut maps = raw.clone();
        memory.apply(&mut maps);
        let second = maps.choose();
        assert_eq!((second.grasp.u, second.grasp.v), (80, 70));
        memory.record(second.grasp, false);
        let mut maps = raw.clone();
        memory.apply(&mut maps);
        assert_eq!((maps.choose().grasp.u, maps.choose().grasp.v), (64, 30));
        assert!((0..BINS).all(|b| maps.map(b).iter().all(|v| (0.0..=1.0).contains(v))));
        // A third failure pushes the first out of the two-action memory.
        memory.record(maps.choose().grasp, false);
        let mut maps = raw.clone();
        memory.apply(&mut maps);
        assert_eq!((maps.choose().grasp.u, maps.choose().grasp.v), (40, 60));
    }

    #[test]
    fn successes_are_forgotten_unless_configured_and_zero_means_off() {
        let choice = bumpy_maps().choose();
        let mut off = Suppression::new(SuppressionConfig::default());
        off.record(choice.grasp, false);
        assert_eq!(off.past().count(), 0);
        let mut failures = Suppression::new(SuppressionConfig {
            remember: 4,
            ..SuppressionConfig::default()
        });
        failures.record(choice.grasp, true);
        assert_eq!(failures.past().count(), 0);
        let mut all = Suppression::new(SuppressionConfig {
            remember: 4,
            remember_successes: true,
            ..SuppressionConfig::default()
        });
        all.record(choice.grasp, true);
        assert_eq!(all.past().count(), 1);
    }

    #[test]
    fn the_other_rotations_are_lowered_by_their_own_depth() {
        let raw = bumpy_maps();
        let first = raw.choose();
        let mut memory = Suppression::new(SuppressionConfig {
            remember: 1,
            other_rotations: 0.25,
            ..SuppressionConfig::default()
        });
        memory.record(first.grasp, false);
        let mut maps = raw.clone();
        memory.apply(&mut maps);
        for bin in 0..BINS {
            // Each map's largest drop is its Gaussian's peak at the carried centre, where the
            // bumps stand 0.8 high or more: the failed bin loses all of it, the others 0.25.
            let drop = raw
                .map(bin)
                .iter()
                .zip(maps.map(bin))
                .map(|(before, after)| before - after)
                .fold(0.0f32, f32::max);
            if bin == first.bin {
                assert!(drop > 0.8, "bin {bin}: dropped {drop}");
            } else {
                assert!((drop - 0.25).abs() < 0.01, "bin {bin}: dropped {drop}");
            }
        }
    }

    #[test]
    fn suppression_reaches_only_the_nearby_rotations() {
        let raw = bumpy_maps();
        let first = raw.choose();
        assert_eq!(first.bin, 0, "the tilt favours bin 0");
        for (reach, lowered) in [(0, vec![0]), (1, vec![0, 1, 7]), (4, (0..BINS).collect())] {
            let mut memory = Suppression::new(SuppressionConfig {
                remember: 1,
                rotation_reach: reach,
                ..SuppressionConfig::default()
            });
            memory.record(first.grasp, false);
            let mut maps = raw.clone();
            memory.apply(&mut maps);
            for bin in 0..BINS {
                let changed = maps.map(bin) != raw.map(bin);
                assert_eq!(changed, lowered.contains(&bin), "reach {reach}, bin {bin}");
            }
        }
    }
}
