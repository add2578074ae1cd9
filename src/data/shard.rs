//! Shards: the parts of a sweep (`eval --shard I/N`) or a collection (`collect --shard I/N`)
//! that run apart, and the checks that `merge` makes before joining them (docs/cluster.md).

use std::path::Path;

use anyhow::bail;
use serde::{Deserialize, Serialize};

/// Which part of the scenes a run holds: scene `s` (0-based; for a sweep, the position of its
/// seed in `--seeds`) belongs to shard `s mod count + 1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Shard {
    /// 1-based shard number.
    pub index: u32,
    /// Shards in all.
    pub count: u32,
}

impl Shard {
    /// The whole run as one shard.
    pub(crate) const WHOLE: Shard = Shard { index: 1, count: 1 };

    /// Parses `I/N` with 1 ≤ I ≤ N.
    pub(crate) fn parse(text: &str) -> Result<Self, String> {
        let (i, n) = text
            .split_once('/')
            .ok_or_else(|| format!("'{text}' is not I/N (e.g. 2/4)"))?;
        let number = |s: &str| {
            s.trim()
                .parse::<u32>()
                .map_err(|_| format!("'{text}' is not I/N with whole numbers (e.g. 2/4)"))
        };
        let (index, count) = (number(i)?, number(n)?);
        if count == 0 || index == 0 || index > count {
            return Err(format!(
                "'{text}': the shard number must lie in 1..={count} and the count be at least 1 (e.g. 2/4)"
            ));
        }
        Ok(Self { index, count })
    }

    /// Whether scene `scene` (0-based) is this shard's.
    pub(crate) fn holds(self, scene: u64) -> bool {
        scene % u64::from(self.count) == u64::from(self.index - 1)
    }

    /// Whether this is the whole run.
    pub(crate) fn is_whole(self) -> bool {
        self.count == 1
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// The shards of `count` that are not among `given`, in order.
pub(crate) fn missing(count: u32, given: &[Shard]) -> Vec<Shard> {
    (1..=count)
        .map(|index| Shard { index, count })
        .filter(|s| !given.contains(s))
        .collect()
}

/// Refuses `shard`, read from `path`, when it cannot join `earlier` (the shards read before it,
/// with where each came from) in one merge: its count differs from the first's, or another
/// already holds it. `of` names what the shards split ("sweep", "run").
pub(crate) fn check_joins(
    shard: Shard,
    path: &Path,
    earlier: &[(Shard, &Path)],
    of: &str,
) -> anyhow::Result<()> {
    if let Some((first, first_path)) = earlier.first() {
        if first.count != shard.count {
            bail!(
                "{} is shard {shard}, and {} is shard {first}: the shard counts differ; merge only the shards of one {of}",
                path.display(),
                first_path.display(),
            );
        }
    }
    if let Some((_, twin)) = earlier.iter().find(|(s, _)| *s == shard) {
        bail!(
            "{} and {} both hold shard {shard}: the shards overlap; give each shard once",
            twin.display(),
            path.display()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_split_the_scenes_disjointly_and_cover_them() {
        let shards: Vec<Shard> = (1..=3).map(|i| Shard { index: i, count: 3 }).collect();
        for scene in 0..30 {
            assert_eq!(shards.iter().filter(|s| s.holds(scene)).count(), 1);
        }
        assert!(Shard::WHOLE.holds(17));
        assert_eq!(Shard::parse("2/4"), Ok(Shard { index: 2, count: 4 }));
        for bad in ["0/4", "5/4", "1/0", "x/2", "3", "-1/2"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn missing_shards_are_listed_in_order() {
        let given = [Shard { index: 3, count: 4 }, Shard { index: 1, count: 4 }];
        let names: Vec<String> = missing(4, &given).iter().map(Shard::to_string).collect();
        assert_eq!(names, ["2/4", "4/4"]);
        assert!(missing(1, &[Shard::WHOLE]).is_empty());
    }

    #[test]
    fn shards_join_only_with_the_same_count_and_never_twice() {
        let (a, b) = (Path::new("a.json"), Path::new("b.json"));
        let first = [(Shard { index: 1, count: 2 }, a)];
        assert!(check_joins(Shard { index: 2, count: 2 }, b, &first, "sweep").is_ok());
        let other = check_joins(Shard { index: 2, count: 3 }, b, &first, "sweep").unwrap_err();
        assert_eq!(
            other.to_string(),
            "b.json is shard 2/3, and a.json is shard 1/2: the shard counts differ; merge only the shards of one sweep"
        );
        let twice = check_joins(Shard { index: 1, count: 2 }, b, &first, "run").unwrap_err();
        assert_eq!(
            twice.to_string(),
            "a.json and b.json both hold shard 1/2: the shards overlap; give each shard once"
        );
    }
}
