//! Which evaluations can stand side by side: the settings that make two runs of a task
//! comparable (the seeds, empty_bin's attempt budget, the objects), the name under which `eval`
//! keeps a run's report in `DATA/reports` (one per task, policy and such settings, so that a
//! small probe never replaces a larger run's report), and how `graspmap report` groups and
//! describes them.

use std::path::{Path, PathBuf};

use crate::assets::BUNDLED_PREFIX;
use crate::named::{counted, shell_word, Named};
use crate::policy::PolicyKind;
use crate::present::eval_report::Task;

/// empty_bin's attempts per scene unless `--max-attempts` says otherwise (the reference's).
pub(crate) const DEFAULT_MAX_ATTEMPTS: u32 = 25;

/// The settings that decide what an evaluation's figures mean: runs of one task agree on them,
/// or are not compared. Policy settings (the checkpoint, `--verify-top`, suppression, ...)
/// are not among them: they are what a comparison compares.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct Comparable {
    /// The task's name.
    pub(crate) task: String,
    /// The base seeds of the whole sweep.
    pub(crate) seeds: Vec<u64>,
    /// empty_bin: the most attempts per scene (`None` for train and test, which make 3 per object).
    pub(crate) max_attempts: Option<u32>,
    /// empty_bin: failed attempts in a row that end a scene (0 = never).
    pub(crate) give_up_after: Option<u32>,
    /// Where the object models came from (`bundled:objects` or the `--objects-dir` given).
    pub(crate) objects_dir: String,
    /// The split file (`bundled:objects/split.json` or the `--split` given).
    pub(crate) split: String,
    /// The objects of the task, in order.
    pub(crate) objects: Vec<String>,
    /// The part of the sweep a shard ran (`"I/N"`), `None` for a whole sweep.
    pub(crate) shard: Option<String>,
}

impl Comparable {
    /// The settings of a run.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        task: Task,
        seeds: &[u64],
        max_attempts: u32,
        give_up_after: u32,
        objects_dir: &Path,
        split: &Path,
        objects: &[String],
        shard: Option<String>,
    ) -> Self {
        let bin = task == Task::EmptyBin;
        Self {
            task: task.name().to_owned(),
            seeds: seeds.to_vec(),
            max_attempts: bin.then_some(max_attempts),
            give_up_after: bin.then_some(give_up_after),
            objects_dir: objects_dir.display().to_string(),
            split: split.display().to_string(),
            objects: objects.to_vec(),
            shard,
        }
    }

    /// The settings a run of the task gets without flags: its default seed and attempt budget,
    /// on the bundled objects and split.
    pub(crate) fn is_default(&self) -> bool {
        let default_seed = Task::ALL
            .iter()
            .find(|t| t.name() == self.task)
            .map_or(0, |t| t.default_seed());
        self.seeds == [default_seed]
            && self.max_attempts.unwrap_or(DEFAULT_MAX_ATTEMPTS) == DEFAULT_MAX_ATTEMPTS
            && self.give_up_after.unwrap_or(0) == 0
            && self.objects_dir.starts_with(BUNDLED_PREFIX)
            && self.split.starts_with(BUNDLED_PREFIX)
    }

    /// Eight hex digits of the settings (shard aside), `None` for the defaults.
    fn key(&self) -> Option<String> {
        use sha2::Digest;
        if self.is_default() {
            return None;
        }
        let text = format!(
            "task={}\nseeds={:?}\nmax_attempts={:?}\ngive_up_after={:?}\nobjects_dir={}\nsplit={}\nobjects={:?}\n",
            self.task,
            self.seeds,
            self.max_attempts,
            self.give_up_after,
            self.objects_dir,
            self.split,
            self.objects
        );
        let digest = sha2::Sha256::digest(text.as_bytes());
        Some(digest[..4].iter().map(|b| format!("{b:02x}")).collect())
    }

    /// Where `eval` keeps the report of a run with these settings and `policy` under `data`:
    /// `DATA/reports/eval_<task>_<policy>.json` for the defaults, with `_<key>` before `.json`
    /// for any other settings, and `_shard<I>of<N>` for a shard.
    pub(crate) fn kept_path(&self, data: &Path, policy: PolicyKind) -> PathBuf {
        let mut name = format!("eval_{}_{}", self.task, policy.name());
        if let Some(key) = self.key() {
            name += &format!("_{key}");
        }
        if let Some(shard) = &self.shard {
            name += &format!("_shard{}", shard.replace('/', "of"));
        }
        data.join("reports").join(name + ".json")
    }

    /// The settings in words, for the report page: "seeds 1-10, at most 3 attempts a scene,
    /// objects from DIR".
    pub(crate) fn describe(&self) -> String {
        let mut parts = vec![format!(
            "{} {}",
            if self.seeds.len() == 1 {
                "seed"
            } else {
                "seeds"
            },
            seed_list(&self.seeds)
        )];
        if let Some(n) = self.max_attempts {
            parts.push(format!(
                "at most {} a scene",
                counted(n as usize, "attempt")
            ));
        }
        if let Some(k) = self.give_up_after.filter(|&k| k > 0) {
            parts.push(format!("giving up after {k} failures in a row"));
        }
        parts.push(format!("objects from {}", self.objects_dir));
        if !self.split.starts_with(BUNDLED_PREFIX) {
            parts.push(format!("split {}", self.split));
        }
        if let Some(shard) = &self.shard {
            parts.push(format!("shard {shard} only"));
        }
        parts.join(", ")
    }

    /// The `eval` flags beyond `--task` and `--policy` that give a run these settings
    /// (a shard's aside).
    pub(crate) fn eval_flags(&self) -> String {
        let mut flags = String::new();
        let default_seed = Task::ALL
            .iter()
            .find(|t| t.name() == self.task)
            .map_or(0, |t| t.default_seed());
        if self.seeds != [default_seed] {
            flags += &format!(" --seeds {}", seed_list(&self.seeds));
        }
        if let Some(n) = self.max_attempts.filter(|&n| n != DEFAULT_MAX_ATTEMPTS) {
            flags += &format!(" --max-attempts {n}");
        }
        if let Some(k) = self.give_up_after.filter(|&k| k > 0) {
            flags += &format!(" --give-up-after {k}");
        }
        if !self.objects_dir.starts_with(BUNDLED_PREFIX) {
            flags += &format!(" --objects-dir {}", shell_word(&self.objects_dir));
        }
        if !self.split.starts_with(BUNDLED_PREFIX) {
            flags += &format!(" --split {}", shell_word(&self.split));
        }
        flags
    }
}

/// Seeds as `--seeds` takes them: runs of consecutive seeds as ranges, e.g. `1-10,20`.
pub(crate) fn seed_list(seeds: &[u64]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut i = 0;
    while i < seeds.len() {
        let mut j = i;
        while j + 1 < seeds.len() && seeds[j + 1] == seeds[j] + 1 {
            j += 1;
        }
        parts.push(match j - i {
            0 => seeds[i].to_string(),
            1 => format!("{},{}", seeds[i], seeds[j]),
            _ => format!("{}-{}", seeds[i], seeds[j]),
        });
        i = j + 1;
    }
    parts.join(",")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(task: Task, seeds: &[u64], max_attempts: u32, objects_dir: &str) -> Comparable {
        Comparable::new(
            task,
            seeds,
            max_attempts,
            0,
            Path::new(objects_dir),
            Path::new("bundled:objects/split.json"),
            &["YcbBanana".to_owned()],
            None,
        )
    }

    #[test]
    fn the_defaults_keep_the_plain_name_and_other_settings_their_own() {
        let data = Path::new("d");
        let default = settings(Task::EmptyBin, &[2], 25, "bundled:objects");
        assert!(default.is_default());
        assert_eq!(
            default.kept_path(data, PolicyKind::Oracle),
            Path::new("d/reports/eval_empty_bin_oracle.json")
        );
        let probe = settings(Task::EmptyBin, &[2], 1, "bundled:objects");
        let elsewhere = settings(Task::EmptyBin, &[2], 25, "/tmp/objects");
        let more = settings(Task::EmptyBin, &[1, 2, 3], 25, "bundled:objects");
        let mut names: Vec<PathBuf> = [&default, &probe, &elsewhere, &more]
            .iter()
            .map(|s| s.kept_path(data, PolicyKind::Model))
            .collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), 4, "{names:?}");
        assert!(names.iter().all(|n| n
            .file_name()
            .unwrap()
            .to_string_lossy()
            .starts_with("eval_empty_bin_model")));
        // train and test make 3 attempts per object whatever --max-attempts holds.
        assert_eq!(
            settings(Task::Train, &[0], 1, "bundled:objects"),
            settings(Task::Train, &[0], 25, "bundled:objects")
        );
        assert_eq!(
            probe.eval_flags(),
            " --max-attempts 1",
            "the flags that remake it"
        );
        assert_eq!(
            more.describe(),
            "seeds 1-3, at most 25 attempts a scene, objects from bundled:objects"
        );
    }

    #[test]
    fn seed_lists_are_written_as_eval_reads_them() {
        assert_eq!(seed_list(&[0, 1000, 2000]), "0,1000,2000");
        assert_eq!(seed_list(&[1, 2, 3, 4, 7, 8]), "1-4,7,8");
        assert_eq!(seed_list(&[5]), "5");
    }
}
