//! Statistics for evaluation reports: success rates with Wilson intervals, mean and spread.

/// A success rate with its 95 % Wilson score interval.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Rate {
    /// Successes.
    pub(crate) successes: usize,
    /// Trials.
    pub(crate) trials: usize,
    /// successes / trials (0 when there were none).
    pub(crate) rate: f64,
    /// Lower end of the 95 % Wilson interval.
    pub(crate) wilson_low: f64,
    /// Upper end of the 95 % Wilson interval.
    pub(crate) wilson_high: f64,
}

/// z for a two-sided 95 % interval.
const Z95: f64 = 1.959_963_984_540_054;

impl Rate {
    /// The rate and its interval. Wilson's interval stays inside [0, 1] and is sensible at 0 and
    /// at all successes, unlike the normal approximation, which matters at 15–90 trials.
    pub(crate) fn new(successes: usize, trials: usize) -> Self {
        assert!(
            successes <= trials,
            "{successes} successes in {trials} trials"
        );
        if trials == 0 {
            return Self {
                successes,
                trials,
                rate: 0.0,
                wilson_low: 0.0,
                wilson_high: 1.0,
            };
        }
        let n = trials as f64;
        let p = successes as f64 / n;
        let z2 = Z95 * Z95;
        let denominator = 1.0 + z2 / n;
        let centre = (p + z2 / (2.0 * n)) / denominator;
        let half = Z95 * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt() / denominator;
        Self {
            successes,
            trials,
            rate: p,
            wilson_low: (centre - half).max(0.0),
            wilson_high: (centre + half).min(1.0),
        }
    }

    /// "25/30 = 83.3 % (95 % CI 66.4–92.7 %)".
    pub(crate) fn describe(&self) -> String {
        format!(
            "{}/{} = {:.1} % (95 % CI {:.1}–{:.1} %)",
            self.successes,
            self.trials,
            100.0 * self.rate,
            100.0 * self.wilson_low,
            100.0 * self.wilson_high
        )
    }
}

/// Mean and sample standard deviation (n − 1; 0 for fewer than two values).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Spread {
    /// Mean.
    pub(crate) mean: f64,
    /// Sample standard deviation.
    pub(crate) std: f64,
    /// Smallest value.
    pub(crate) min: f64,
    /// Largest value.
    pub(crate) max: f64,
    /// Number of values.
    pub(crate) count: usize,
}

impl Spread {
    /// The spread of `values` (all zeros when empty).
    pub(crate) fn of(values: &[f64]) -> Self {
        let count = values.len();
        if count == 0 {
            return Self {
                mean: 0.0,
                std: 0.0,
                min: 0.0,
                max: 0.0,
                count,
            };
        }
        let mean = values.iter().sum::<f64>() / count as f64;
        let std = if count < 2 {
            0.0
        } else {
            (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (count - 1) as f64).sqrt()
        };
        Self {
            mean,
            std,
            min: values.iter().copied().fold(f64::INFINITY, f64::min),
            max: values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            count,
        }
    }
}

/// The median (mean of the middle two for even counts; 0 when empty).
pub(crate) fn median(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mid = sorted.len() / 2;
    if sorted.len().is_multiple_of(2) {
        (sorted[mid - 1] + sorted[mid]) / 2.0
    } else {
        sorted[mid]
    }
}

/// How often each failure reason occurred: the one tally behind every report's failure column.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub(crate) struct FailureTally(std::collections::BTreeMap<String, usize>);

impl FailureTally {
    /// Counts one failure.
    pub(crate) fn add(&mut self, reason: &str) {
        *self.0.entry(reason.to_owned()).or_default() += 1;
    }

    /// The tally of the given reasons.
    pub(crate) fn of<'a>(reasons: impl IntoIterator<Item = &'a str>) -> Self {
        let mut tally = Self::default();
        for reason in reasons {
            tally.add(reason);
        }
        tally
    }

    /// Each reason's count, in name order.
    pub(crate) fn counts(&self) -> &std::collections::BTreeMap<String, usize> {
        &self.0
    }

    /// "collision 2, slipped 1", or "-" when nothing failed.
    pub(crate) fn describe(&self) -> String {
        if self.0.is_empty() {
            return "-".to_owned();
        }
        self.0
            .iter()
            .map(|(reason, n)| format!("{reason} {n}"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failure_tallies_count_by_reason_in_name_order() {
        let tally = FailureTally::of(["slipped", "collision", "slipped"]);
        assert_eq!(tally.describe(), "collision 1, slipped 2");
        assert_eq!(FailureTally::default().describe(), "-");
        assert_eq!(
            serde_json::to_string(&tally).unwrap(),
            r#"{"collision":1,"slipped":2}"#
        );
    }

    #[test]
    fn wilson_matches_published_values() {
        // 8/10: 0.4902–0.9433 (Wilson 1927; as in every stats package).
        let r = Rate::new(8, 10);
        assert!((r.wilson_low - 0.4902).abs() < 1e-4, "{r:?}");
        assert!((r.wilson_high - 0.9433).abs() < 1e-4, "{r:?}");
        let none = Rate::new(0, 15);
        assert_eq!(none.wilson_low, 0.0);
        assert!((none.wilson_high - 0.2039).abs() < 1e-4, "{none:?}");
        let all = Rate::new(15, 15);
        assert!((all.wilson_low - 0.7961).abs() < 1e-4, "{all:?}");
        assert_eq!(all.wilson_high, 1.0);
        assert_eq!(Rate::new(0, 0).rate, 0.0);
        assert_eq!(
            Rate::new(25, 30).describe(),
            "25/30 = 83.3 % (95 % CI 66.4–92.7 %)"
        );
    }

    #[test]
    fn spread_and_median() {
        let s = Spread::of(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        assert_eq!(s.mean, 5.0);
        assert!((s.std - 2.138).abs() < 1e-3);
        assert_eq!((s.min, s.max, s.count), (2.0, 9.0, 8));
        assert_eq!(Spread::of(&[3.0]).std, 0.0);
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
