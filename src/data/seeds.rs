//! The seeds a run derives from the one a user gives (docs/data.md, docs/evaluation.md): a
//! labelling round's `seed + 100·j + r`, an evaluation attempt's `seed + 100·i + a + 10000`,
//! an improve round's `seed·1000 + r`. Every derivation goes through [`derived_seed`], which
//! refuses to wrap: a wrapped seed would repeat another seed's scenes without a word.

/// A derived seed that would pass `u64::MAX`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("seed {seed} is too large: the seeds derived from it ({formula}) would pass {max}; give a seed of at most {largest}", max = u64::MAX)]
pub(crate) struct SeedOverflow {
    /// The seed given.
    pub(crate) seed: u64,
    /// How the run derives its seeds, for the message.
    pub(crate) formula: &'static str,
    /// The largest seed whose derived seeds all fit.
    pub(crate) largest: u64,
}

/// `seed · scale + offset`, or an error saying which seeds fit when it would pass `u64::MAX`.
/// `formula` says the derivation in words, e.g. `seed + 100·i + a + 10000`.
pub(crate) fn derived_seed(
    seed: u64,
    scale: u64,
    offset: u64,
    formula: &'static str,
) -> Result<u64, SeedOverflow> {
    seed.checked_mul(scale)
        .and_then(|s| s.checked_add(offset))
        .ok_or(SeedOverflow {
            seed,
            formula,
            largest: (u64::MAX - offset) / scale.max(1),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_that_fit_are_derived_and_the_rest_refused_with_the_largest_that_fits() {
        assert_eq!(derived_seed(7, 1, 10_203, "f"), Ok(10_210));
        assert_eq!(derived_seed(7, 1000, 2, "f"), Ok(7002));
        let largest = u64::MAX - 10_000;
        assert_eq!(derived_seed(largest, 1, 10_000, "f"), Ok(u64::MAX));
        let err = derived_seed(largest + 1, 1, 10_000, "f").unwrap_err();
        assert_eq!(err.largest, largest);
        assert!(
            err.to_string().contains(&format!("at most {largest}")),
            "{err}"
        );
        let err = derived_seed(u64::MAX / 1000 + 1, 1000, 0, "f").unwrap_err();
        assert_eq!(err.largest, u64::MAX / 1000);
        // The largest it names is itself accepted.
        assert!(derived_seed(err.largest, 1000, 0, "f").is_ok());
    }
}
