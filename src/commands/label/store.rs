//! The dataset outside the rounds: clearing and repairing it before they start, where to resume,
//! and the `--delete` and `--check` modes.

use anyhow::bail;

use super::clicks::{check_enough_clicks, Clicker};
use super::config::LabelConfig;
use crate::commands::Context;
use crate::data::depth_files::check_depth_files;
use crate::data::labels::{LabelStore, Labels};
use crate::data::progress::Progress;
use crate::named::counted;
use crate::present::envelope::write_report;

/// Clears or repairs the store before the rounds: the labels and progress to continue from.
pub(super) fn prepare(
    store: &LabelStore,
    args: &LabelConfig,
    clicker: &Clicker,
    train: &[String],
) -> anyhow::Result<(Labels, Progress)> {
    if args.force {
        store.clear()?;
    }
    store.remove_stale_temporaries()?;
    store.remove_stale_staging()?;
    let mut labels = store.load()?;
    let mut progress = resume_point(store, &labels, args, clicker.name(), train)?;
    if let Clicker::File { clicks } = clicker {
        check_enough_clicks(clicks, &labels, &progress, args, train)?;
    }
    labels.arrange(train);
    for object in train {
        let (rounds, recorded) = progress.entry(object);
        progress.set_rounds(object, rounds, recorded);
    }
    // A run stopped between writing labels.json and progress.json left the round uncounted on
    // disk; record the repaired count now, in case no later round writes it. A new dataset
    // gets its progress.json before the first label, so a run killed right after that label
    // is resumed as this run, not mistaken for a dataset from elsewhere.
    if store.load_progress()?.as_ref() != Some(&progress) {
        store.save_progress(&progress)?;
    }
    Ok((labels, progress))
}

/// Whether new labels get depth files: yes unless the dataset already holds labels without
/// them (made before depth files existed), which would leave it half with, half without.
pub(super) fn writes_depth(store: &LabelStore, labels: &Labels) -> bool {
    let all = labels
        .iter()
        .all(|(object, list)| (1..=list.len()).all(|k| store.depth_path(object, k).exists()));
    if !all {
        tracing::warn!(
            "{} has labels without depth images; new labels get none either (run `graspmap label --backfill-depth` first to add them)",
            store.dir().display()
        );
    }
    all
}

/// What a labelling run would refuse in progress.json, against the stored labels: a file that
/// does not parse, another schema, or label counts that differ by more than the one label a
/// kill between the two writes leaves uncounted.
fn progress_problems(store: &LabelStore) -> Vec<String> {
    let path = store.dir().join(crate::data::progress::PROGRESS_FILE);
    let progress = match store.load_progress() {
        Ok(Some(progress)) => progress,
        Ok(None) => return Vec::new(),
        Err(e) => return vec![format!("{e:#}")],
    };
    let mut problems = Vec::new();
    if progress.schema != Progress::SCHEMA {
        problems.push(format!(
            "{}: schema '{}', expected '{}' (label --force starts over)",
            path.display(),
            progress.schema,
            Progress::SCHEMA
        ));
    }
    let Ok(labels) = store.load() else {
        return problems;
    };
    let objects: std::collections::BTreeSet<&str> = labels
        .iter()
        .map(|(object, _)| object)
        .chain(progress.rounds.iter().map(|p| p.object.as_str()))
        .collect();
    for object in objects {
        let (rounds, recorded) = progress.entry(object);
        let stored = labels.of(object).len() as u32;
        if stored != recorded && stored != recorded + 1 {
            problems.push(format!(
                "{}: {object} has {stored} labels but progress.json records {recorded} (label --force starts over)",
                store.dir().display()
            ));
        }
        if rounds < recorded {
            problems.push(format!(
                "{}: {object} records {recorded} labels from only {rounds} rounds (label --force starts over)",
                path.display()
            ));
        }
    }
    problems
}

/// Where to continue: the rounds already run per object, from progress.json.
fn resume_point(
    store: &LabelStore,
    labels: &Labels,
    args: &LabelConfig,
    source: &str,
    train: &[String],
) -> anyhow::Result<Progress> {
    let mut fresh = Progress::new(args.seed);
    fresh.clutter = args.clutter;
    let Some(mut progress) = store.load_progress()? else {
        if !labels.is_empty() {
            // A dataset from elsewhere (e.g. the reference tool): its rounds are unknown, so
            // continue as if every earlier round had succeeded.
            tracing::warn!(
                "{} has labels but no progress file; continuing as if each label took one round",
                store.dir().display()
            );
            let mut progress = fresh;
            for object in train {
                let n = labels.of(object).len() as u32;
                progress.set_rounds(object, n, n);
                progress.record_sources(object, "imported");
            }
            return Ok(progress);
        }
        return Ok(fresh);
    };
    if progress.schema != Progress::SCHEMA {
        bail!(
            "{} has schema '{}', expected '{}' (rerun with --force to start over)",
            store
                .dir()
                .join(crate::data::progress::PROGRESS_FILE)
                .display(),
            progress.schema,
            Progress::SCHEMA
        );
    }
    // Any click source may top a dataset up (scripted first, then fixed by hand): each
    // label records its own. The seed and the clutter decide every round's drop, so they must
    // match.
    if progress.seed != args.seed || progress.clutter != args.clutter {
        bail!(
            "the labels in {} were made with --seed {} --clutter {}; rerun with those settings to resume, or with --force to start over",
            store.dir().display(),
            progress.seed,
            progress.clutter
        );
    }
    // A run killed between writing labels.json and progress.json: the label is there, its
    // round is not counted yet.
    for object in train {
        let (rounds, recorded) = progress.entry(object);
        let stored = labels.of(object).len() as u32;
        if stored == recorded + 1 {
            progress.set_rounds(object, rounds + 1, stored);
            // Its run stopped before it could record which source made it; the run that
            // resumes is almost always the same command, so it is credited with it (and a
            // resumed dataset is byte-identical to an uninterrupted one).
            progress.record_sources(object, source);
        } else if stored != recorded {
            bail!(
                "{}: {object} has {stored} labels but progress.json records {recorded}; rerun with --force to start over",
                store.dir().display()
            );
        }
    }
    Ok(progress)
}

/// `label --delete OBJECT:K`, under the writer lock.
pub(super) fn delete(
    context: &Context,
    store: &LabelStore,
    object: &str,
    k: usize,
) -> anyhow::Result<()> {
    store.remove_stale_temporaries()?;
    store.remove_stale_staging()?;
    let mut labels = store.load()?;
    // A dataset without progress.json (e.g. the reference tool's) stays without one.
    let mut progress = store.load_progress()?;
    store.delete_label(&mut labels, progress.as_mut(), object, k)?;
    context.say(&format!(
        "deleted {object} label {k} in {}; {} left for {object}, numbered 1..{}; the next `graspmap label` refills it",
        store.dir().display(),
        labels.of(object).len(),
        labels.of(object).len()
    ));
    if let Some(json) = &context.json {
        let resolved = serde_json::json!({ "global": context, "delete": [object, k] });
        let results = serde_json::json!({ "labels_dir": store.dir(), "object": object, "deleted": k, "left": labels.of(object).len() });
        write_report(json, "label", 0, &resolved, &results)?;
    }
    Ok(())
}

/// `label --check`: every problem on stdout, then exit 2 if there was any.
pub(super) fn check(context: &Context, store: &LabelStore, known: &[String]) -> anyhow::Result<()> {
    // The split is what a labelling run reads first: check it as that run would.
    context.split()?;
    let mut problems = store.check(known);
    problems.extend(check_depth_files(store));
    problems.extend(progress_problems(store));
    for problem in &problems {
        context.say(problem);
    }
    if let Some(json) = &context.json {
        let resolved = serde_json::json!({ "global": context, "check": true });
        let results = serde_json::json!({ "labels_dir": store.dir(), "problems": problems });
        write_report(json, "label", 0, &resolved, &results)?;
    }
    if !problems.is_empty() {
        bail!(
            "{} problem(s) in {}; fix or remove the listed files, or relabel with --force",
            problems.len(),
            store.dir().display()
        );
    }
    let labels = store.load()?;
    context.say(&format!(
        "{}: {} for {}, no problems",
        store.dir().display(),
        counted(labels.len(), "label"),
        counted(labels.iter().count(), "object")
    ));
    Ok(())
}
