//! Labelling progress (`progress.json` beside `labels.json`): the rounds run and each label's
//! click source per object, so that a rerun of `graspmap label` continues from the right round.

use std::io::Write;
use std::path::Path;

use anyhow::Context;

use super::atomic::write_atomic;

/// Where labelling stands per object, so that a rerun continues from the right round.
pub(crate) const PROGRESS_FILE: &str = "progress.json";

/// Labelling progress, kept beside labels.json.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Progress {
    /// `graspmap.label-progress/2` (version 1, which named one click source for the whole
    /// dataset, is read and upgraded).
    pub(crate) schema: String,
    /// The seed the rounds were drawn with.
    pub(crate) seed: u64,
    /// Version 1's one click source; only read, moved into each object's `sources`.
    #[serde(default, skip_serializing)]
    pub(crate) source: Option<String>,
    /// Objects dropped per round (`--clutter`). Left out when 1, the reference protocol, so
    /// that files from before clutter rounds existed read, and are written, as they were.
    #[serde(default = "one_object", skip_serializing_if = "is_one_object")]
    pub(crate) clutter: u32,
    /// Per object: rounds run and labels stored after them.
    pub(crate) rounds: Vec<ObjectProgress>,
}

fn one_object() -> u32 {
    1
}

fn is_one_object(clutter: &u32) -> bool {
    *clutter == 1
}

/// One object's progress.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ObjectProgress {
    /// Object name.
    pub(crate) object: String,
    /// Rounds run, failed ones included.
    pub(crate) rounds: u32,
    /// Labels stored when the last round was counted.
    pub(crate) labels: u32,
    /// The click source of each stored label, in label order (`scripted`, `file`,
    /// `interactive`, `web`; `imported` for labels from a dataset without progress.json,
    /// the run that resumed it for one whose run was killed before it recorded its source). A dataset may
    /// be topped up by another source, so these can differ.
    #[serde(default)]
    pub(crate) sources: Vec<String>,
}

impl Progress {
    /// Parses progress.json, upgrading version 1; `path` names it in errors.
    pub(crate) fn parse(text: &str, path: &Path) -> anyhow::Result<Self> {
        let mut progress: Progress = serde_json::from_str(text).with_context(|| {
            format!(
                "{} is corrupt (delete it, or start over with graspmap label --force)",
                path.display()
            )
        })?;
        if progress.schema == Self::SCHEMA_V1 {
            let source = progress.source.take().unwrap_or_else(|| "unknown".into());
            for object in &mut progress.rounds {
                object.sources = vec![source.clone(); object.labels as usize];
            }
            progress.schema = Self::SCHEMA.to_owned();
        }
        Ok(progress)
    }

    /// The schema name.
    pub(crate) const SCHEMA: &'static str = "graspmap.label-progress/2";
    /// The first version, read and upgraded.
    const SCHEMA_V1: &'static str = "graspmap.label-progress/1";

    /// A new, empty progress record for `seed`.
    pub(crate) fn new(seed: u64) -> Self {
        Progress {
            schema: Self::SCHEMA.to_owned(),
            seed,
            source: None,
            clutter: 1,
            rounds: Vec::new(),
        }
    }

    /// Each stored label's click source, for `object`.
    pub(crate) fn sources_of(&self, object: &str) -> &[String] {
        self.rounds
            .iter()
            .find(|p| p.object == object)
            .map_or(&[], |p| p.sources.as_slice())
    }

    /// Makes `object`'s source list as long as its label count: a new label's source is
    /// `source`; a list longer than the labels (never written so) is cut.
    pub(crate) fn record_sources(&mut self, object: &str, source: &str) {
        if let Some(p) = self.rounds.iter_mut().find(|p| p.object == object) {
            let labels = p.labels as usize;
            p.sources.truncate(labels);
            while p.sources.len() < labels {
                p.sources.push(source.to_owned());
            }
        }
    }

    /// Removes `object`'s k-th label (1-based) from the record: one label fewer, its source
    /// gone; the rounds already run stay counted, so the next round refills the label with a
    /// new seed.
    pub(crate) fn remove_label(&mut self, object: &str, k: usize) {
        if let Some(p) = self.rounds.iter_mut().find(|p| p.object == object) {
            p.labels = p.labels.saturating_sub(1);
            if (1..=p.sources.len()).contains(&k) {
                p.sources.remove(k - 1);
            }
        }
    }

    /// Rounds run and labels recorded for `object`.
    pub(crate) fn entry(&self, object: &str) -> (u32, u32) {
        self.rounds
            .iter()
            .find(|p| p.object == object)
            .map_or((0, 0), |p| (p.rounds, p.labels))
    }

    /// Rounds already run for `object`.
    pub(crate) fn rounds_of(&self, object: &str) -> u32 {
        self.entry(object).0
    }

    /// Records that `object` has run `rounds` rounds and has `labels` labels.
    pub(crate) fn set_rounds(&mut self, object: &str, rounds: u32, labels: u32) {
        match self.rounds.iter_mut().find(|p| p.object == object) {
            Some(p) => {
                p.rounds = rounds;
                p.labels = labels;
            }
            None => self.rounds.push(ObjectProgress {
                object: object.to_owned(),
                rounds,
                labels,
                sources: Vec::new(),
            }),
        }
    }
}

impl Progress {
    /// Reads `labels_dir`'s progress.json, if any.
    pub(crate) fn load(labels_dir: &Path) -> anyhow::Result<Option<Self>> {
        let path = labels_dir.join(PROGRESS_FILE);
        match std::fs::read_to_string(&path) {
            Ok(text) => Ok(Some(Self::parse(&text, &path)?)),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(e).with_context(|| format!("reading {}", path.display())),
        }
    }

    /// Writes `labels_dir`'s progress.json atomically.
    pub(crate) fn save(&self, labels_dir: &Path) -> anyhow::Result<()> {
        let mut text = serde_json::to_vec_pretty(self)?;
        text.write_all(b"\n")?;
        write_atomic(&labels_dir.join(PROGRESS_FILE), &text)
    }
}

#[cfg(test)]
mod fuzz {
    use std::path::Path;

    use proptest::prelude::*;

    use crate::data::fuzzing::{check, config, edits, mutate, text};

    fn progress_json() -> String {
        r#"{"schema": "graspmap.label-progress/1", "seed": 0, "source": "scripted",
            "rounds": [{"object": "YcbHammer", "rounds": 14, "labels": 12}]}"#
            .to_owned()
    }

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn fuzz_json_progress(edits in edits()) {
            let input = text(&mutate(progress_json().as_bytes(), &edits));
            check(|| crate::data::progress::Progress::parse(&input, Path::new("progress.json")))?;
        }
    }
}
