//! `graspmap merge`: the shards of one sweep into one result. Trial stores (folders) merge into
//! one store, equal byte for byte to the unsharded `collect`'s (docs/data.md, "Trials"); eval
//! reports (files) merge into one report, equal to the unsharded `eval`'s attempt for attempt,
//! with its summary recomputed over all scenes (docs/cluster.md).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _};

use super::Context;
use crate::data::shard::{self, Shard};
use crate::data::trials::{Manifest, TrialStore, MANIFEST_FILE};
use crate::named::counted;
use crate::present::envelope::{write_report, write_versioned_report};
use crate::present::eval_lines::report_lines;
use crate::present::eval_report::{summarise, EvalReport, SceneRun};

/// What `graspmap merge` runs.
#[derive(Debug, Clone)]
pub(crate) struct MergeConfig {
    /// The shard stores.
    pub(crate) inputs: Vec<PathBuf>,
    /// The merged store's folder; must not exist yet, or be empty.
    pub(crate) out: PathBuf,
    /// Write what is there when shards are missing, marked partial.
    pub(crate) allow_partial: bool,
}

/// Refuses, before any work, inputs that are neither a regular file nor a folder (`/dev/null`,
/// a FIFO, a socket: reading one would block or yield nothing), and inputs that do not exist.
pub(crate) fn check_inputs(inputs: &[PathBuf]) -> anyhow::Result<()> {
    for path in inputs {
        match std::fs::metadata(path) {
            Err(_) => bail!(
                "{}: not found; give the shards' eval reports (files) or trial stores (folders)",
                path.display()
            ),
            Ok(meta) if !meta.is_file() && !meta.is_dir() => bail!(
                "{} is neither a regular file nor a folder (a device, FIFO or socket); give the shards' eval reports (files) or trial stores (folders)",
                path.display()
            ),
            Ok(_) => {}
        }
    }
    Ok(())
}

/// Runs the command: eval reports when the inputs are files, trial stores when they are
/// folders.
pub(crate) fn run(context: &Context, config: MergeConfig) -> anyhow::Result<()> {
    check_inputs(&config.inputs)?;
    let file = config.inputs.iter().find(|p| p.is_file());
    let folder = config.inputs.iter().find(|p| p.is_dir());
    match (file, folder) {
        (Some(file), Some(folder)) => bail!(
            "merge takes either eval reports (files) or trial stores (folders), not both; {} is a file and {} a folder",
            file.display(),
            folder.display()
        ),
        (Some(_), None) => merge_reports(context, &config),
        (None, _) => merge_stores(context, &config),
    }
}

/// One shard's eval report, read and checked.
struct ShardReport {
    report: EvalReport,
    shard: Shard,
}

/// What must agree between the shards of one sweep: the configuration without the parts that
/// are allowed to differ per shard (its number, where its report went, threads, quiet).
fn sweep_identity(config: &serde_json::Value) -> serde_json::Value {
    let mut identity = config.clone();
    if let Some(map) = identity.as_object_mut() {
        map.remove("shard");
        if let Some(global) = map.get_mut("global").and_then(|g| g.as_object_mut()) {
            for key in ["json", "threads", "quiet"] {
                global.remove(key);
            }
        }
    }
    identity
}

/// Reads every eval report, refusing what would not make the unsharded sweep's report.
fn read_reports(inputs: &[PathBuf]) -> anyhow::Result<Vec<ShardReport>> {
    let mut shards: Vec<ShardReport> = Vec::new();
    for path in inputs {
        let report = EvalReport::read(path, "rerun that shard")?;
        let shard = report_shard(&report)?;
        if let Some(first) = shards.first() {
            check_same_sweep(&first.report, &report)?;
        }
        let earlier: Vec<(Shard, &Path)> = shards
            .iter()
            .map(|s| (s.shard, s.report.path.as_path()))
            .collect();
        shard::check_joins(shard, path, &earlier, "sweep")?;
        shards.push(ShardReport { report, shard });
    }
    if shards.is_empty() {
        bail!("merge needs at least one shard report (the --json files of `eval --shard I/N`)");
    }
    Ok(shards)
}

/// The shard a finished report of this build holds.
fn report_shard(report: &EvalReport) -> anyhow::Result<Shard> {
    let path = report.path.display();
    let Some(shard) = &report.config.shard else {
        bail!(
            "{path} is a whole sweep, not a shard; merge joins the reports of `eval --shard I/N`"
        );
    };
    let shard = Shard::parse(shard)
        .map_err(|e| anyhow::anyhow!("{path}: config.shard {e}; rerun that shard"))?;
    if report.results.interrupted {
        bail!(
            "{path} (shard {shard}) is unfinished: it was interrupted; finish it with its eval command and --resume"
        );
    }
    let (commit, ours) = (&report.git_commit, env!("GRASPMAP_GIT_COMMIT"));
    if commit != ours {
        bail!(
            "{path} was written by graspmap at commit {commit}, and this merge is commit {ours}; run the shards and the merge with one build"
        );
    }
    Ok(shard)
}

/// Refuses `report` when it belongs to another sweep than `first`.
fn check_same_sweep(first: &EvalReport, report: &EvalReport) -> anyhow::Result<()> {
    let (a, b) = (&first.config, &report.config);
    let (path, first_path) = (report.path.display(), first.path.display());
    if a.checkpoint_sha256 != b.checkpoint_sha256 {
        bail!(
            "{path} was evaluated with another checkpoint than {first_path} (SHA-256 {} against {}); merge only the shards of one sweep",
            serde_json::json!(b.checkpoint_sha256),
            serde_json::json!(a.checkpoint_sha256)
        );
    }
    if a.objects != b.objects || a.global != b.global {
        bail!(
            "{path} was evaluated on another object set than {first_path}; merge only the shards of one sweep"
        );
    }
    let (a, b) = (
        sweep_identity(&first.config_value),
        sweep_identity(&report.config_value),
    );
    if a != b {
        bail!(
            "{path} was run with another configuration than {first_path} ({}differ); merge only the shards of one sweep",
            differing(&a, &b)
        );
    }
    Ok(())
}

/// Joins eval shard reports into the whole sweep's report.
fn merge_reports(context: &Context, config: &MergeConfig) -> anyhow::Result<()> {
    let shards = read_reports(&config.inputs)?;
    let first = &shards[0].report;
    let count = shards[0].shard.count;
    let given: Vec<Shard> = shards.iter().map(|s| s.shard).collect();
    let missing = shard::missing(count, &given);
    if !missing.is_empty() && !config.allow_partial {
        bail!(
            "shards {} of {count} are missing (run them with eval --shard I/{count}, or pass --allow-partial to merge what is there)",
            names(&missing)
        );
    }
    crate::data::output::check_output_file(&config.out, "--out")?;
    let sweep = &first.config.seeds;
    let mut runs: Vec<SceneRun> = Vec::new();
    let mut total_wall = 0.0;
    let mut workers = 1;
    for ShardReport { report, shard } in &shards {
        let expected: Vec<u64> = (sweep.iter().enumerate())
            .filter(|(i, _)| shard.holds(*i as u64))
            .map(|(_, &s)| s)
            .collect();
        let seeds: Vec<u64> = report.results.runs.iter().map(|r| r.seed).collect();
        if seeds != expected {
            bail!(
                "{} (shard {shard}) holds seeds {seeds:?}, and shard {shard} of --seeds holds {expected:?}; rerun that shard",
                report.path.display(),
            );
        }
        total_wall += report.results.timing.total_wall;
        workers = workers.max(report.results.timing.workers);
        runs.extend(report.results.runs.iter().cloned());
    }
    runs.sort_by_key(|r| sweep.iter().position(|&s| s == r.seed));
    let settings = &first.config;
    let seeds: Vec<u64> = runs.iter().map(|r| r.seed).collect();
    let mut results = summarise(
        settings.task,
        settings.policy,
        seeds,
        &settings.objects,
        runs,
        total_wall,
        false,
    );
    results.timing.workers = workers;
    results.vis_dir = first.results.vis_dir.clone();
    for line in report_lines(&results, settings.suppression.remember) {
        context.say(&line);
    }
    let merged_config = merged_config(first, &config.out, &missing);
    write_versioned_report(&config.out, "eval", 2, sweep[0], &merged_config, &results)?;
    context.say(&format!(
        "merged {} of {count} into {}{}",
        counted(shards.len(), "shard"),
        config.out.display(),
        match missing.is_empty() {
            true => String::new(),
            false => format!(" (partial: shards {} missing)", names(&missing)),
        }
    ));
    Ok(())
}

/// The merged report's config: the first shard's, written to `out`, with no shard of its own
/// and the missing ones named.
fn merged_config(first: &EvalReport, out: &Path, missing: &[Shard]) -> serde_json::Value {
    let mut merged = first.config_value.clone();
    merged["global"]["json"] = serde_json::Value::from(out.display().to_string());
    if let Some(map) = merged.as_object_mut() {
        map.remove("shard");
        if !missing.is_empty() {
            map.insert(
                "missing_shards".to_owned(),
                serde_json::json!(missing.iter().map(Shard::to_string).collect::<Vec<_>>()),
            );
        }
    }
    merged
}

/// "2/4, 3/4".
fn names(shards: &[Shard]) -> String {
    let names: Vec<String> = shards.iter().map(Shard::to_string).collect();
    names.join(", ")
}

/// Joins shard trial stores into one store.
fn merge_stores(context: &Context, config: &MergeConfig) -> anyhow::Result<()> {
    let shards = read_shards(&config.inputs)?;
    let first = &shards[0];
    let count = first.shard.count;
    let given: Vec<Shard> = shards.iter().map(|s| s.shard).collect();
    let missing = shard::missing(count, &given);
    if !missing.is_empty() && !config.allow_partial {
        bail!(
            "shards {} of {count} are missing (collect them with --shard I/{count}, or pass --allow-partial to merge what is there)",
            names(&missing)
        );
    }
    check_output(&config.out)?;
    let staging = staging_dir(&config.out);
    if staging.exists() {
        std::fs::remove_dir_all(&staging)
            .with_context(|| format!("removing the unfinished {}", staging.display()))?;
    }
    let merged = TrialStore::new(&staging);
    let mut scenes = 0;
    let mut trials = 0;
    for shard in &shards {
        let held = shard.store.scenes()?;
        for &scene in &held {
            copy_dir(&shard.store.scene_dir(scene), &merged.scene_dir(scene))?;
        }
        let tally = shard.store.tally(&held)?;
        scenes += tally.scenes;
        trials += tally.trials;
    }
    merged.save_manifest(&Manifest {
        schema: Manifest::SCHEMA.to_owned(),
        settings: first.manifest.settings.clone(),
        shard: None,
        missing_shards: missing.clone(),
    })?;
    if config.out.exists() {
        std::fs::remove_dir(&config.out)
            .with_context(|| format!("replacing the empty {}", config.out.display()))?;
    }
    std::fs::rename(&staging, &config.out).with_context(|| {
        format!(
            "moving the merged store into place at {}",
            config.out.display()
        )
    })?;
    context.say(&format!(
        "merged {} of {count} ({} with {}) into {}{}",
        counted(shards.len(), "shard"),
        counted(scenes, "scene"),
        counted(trials, "trial"),
        config.out.display(),
        match missing.is_empty() {
            true => String::new(),
            false => format!(" (partial: {} missing)", counted(missing.len(), "shard")),
        }
    ));
    if let Some(json) = &context.json {
        let resolved = serde_json::json!({
            "global": context,
            "inputs": config.inputs,
            "out": config.out,
            "allow_partial": config.allow_partial,
        });
        let results = serde_json::json!({
            "out": config.out,
            "shards": shards.len(),
            "of": count,
            "missing": missing.iter().map(Shard::to_string).collect::<Vec<_>>(),
            "scenes": scenes,
            "trials": trials,
        });
        write_report(json, "merge", 0, &resolved, &results)?;
    }
    Ok(())
}

/// One input store with its settings and shard.
struct ShardStore {
    store: TrialStore,
    manifest: Manifest,
    shard: Shard,
}

/// Reads and checks every input: a whole, sound shard store each, all of one run, no two the
/// same shard.
fn read_shards(inputs: &[PathBuf]) -> anyhow::Result<Vec<ShardStore>> {
    let mut shards: Vec<ShardStore> = Vec::new();
    for dir in inputs {
        let store = TrialStore::new(dir);
        let manifest = store.load_manifest()?.with_context(|| {
            format!(
                "{}: missing; {} is not a trial store (give the folders `graspmap collect --shard I/N` wrote)",
                store.manifest_path().display(),
                dir.display()
            )
        })?;
        if let Some(problem) = store.check().into_iter().next() {
            bail!(
                "{} is damaged: {problem} (recollect that shard with the same flags)",
                dir.display()
            );
        }
        let Some(shard) = manifest.shard else {
            bail!(
                "{} holds a whole run, not a shard; merge combines the stores of `collect --shard I/N`",
                dir.display()
            );
        };
        let settings = &manifest.settings;
        let scenes = settings["scenes"].as_u64().with_context(|| {
            format!(
                "{}: settings.scenes is not a number of scenes (recollect that shard with the same flags)",
                store.manifest_path().display()
            )
        })?;
        let expected: Vec<u64> = (0..scenes).filter(|&s| shard.holds(s)).collect();
        let held = store.scenes()?;
        if held != expected {
            let absent: Vec<String> = expected
                .iter()
                .filter(|s| !held.contains(s))
                .map(u64::to_string)
                .collect();
            bail!(
                "{} (shard {shard}) is unfinished: scenes {} are missing; rerun its collect command to finish it",
                dir.display(),
                if absent.is_empty() {
                    "outside the shard are present, and".to_owned()
                } else {
                    absent.join(", ")
                }
            );
        }
        if let Some(first) = shards.first() {
            if first.manifest.settings != *settings {
                let keys = differing(&first.manifest.settings, settings);
                bail!(
                    "{} was collected with other settings than {} ({}differ); merge only the shards of one run",
                    store.manifest_path().display(),
                    first.store.manifest_path().display(),
                    keys
                );
            }
        }
        let earlier: Vec<(Shard, &Path)> =
            shards.iter().map(|s| (s.shard, s.store.dir())).collect();
        shard::check_joins(shard, dir, &earlier, "run")?;
        shards.push(ShardStore {
            store,
            manifest,
            shard,
        });
    }
    if shards.is_empty() {
        bail!("merge needs at least one shard store (the folders `graspmap collect --shard I/N` wrote)");
    }
    Ok(shards)
}

/// "checkpoint seed " — the top-level settings that differ, for the refusal.
fn differing(a: &serde_json::Value, b: &serde_json::Value) -> String {
    let keys = super::collect::differing_keys(a, b);
    keys.iter().map(|k| format!("{k} ")).collect()
}

/// The merged store's folder must be new or empty: a merge never replaces a store.
fn check_output(out: &Path) -> anyhow::Result<()> {
    crate::data::output::check_output_dir(
        out.parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new(".")),
        "the merged store's parent folder",
    )?;
    if out.join(MANIFEST_FILE).exists()
        || out
            .read_dir()
            .map(|mut entries| entries.next().is_some())
            .unwrap_or(false)
    {
        bail!(
            "--out {} is not empty; merge writes a new store: give a new folder, or remove that one",
            out.display()
        );
    }
    Ok(())
}

/// Where the merge is built before one rename moves it into place.
fn staging_dir(out: &Path) -> PathBuf {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "trials".to_owned());
    out.with_file_name(format!(".{name}.merging"))
}

/// Copies a scene's folder (plain files only).
fn copy_dir(from: &Path, to: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(to).with_context(|| format!("creating {}", to.display()))?;
    let mut entries: Vec<_> = std::fs::read_dir(from)
        .with_context(|| format!("reading {}", from.display()))?
        .collect::<Result<_, _>>()
        .with_context(|| format!("reading {}", from.display()))?;
    entries.sort_by_key(|e| e.file_name());
    for entry in entries {
        let target = to.join(entry.file_name());
        std::fs::copy(entry.path(), &target).with_context(|| {
            format!("copying {} to {}", entry.path().display(), target.display())
        })?;
    }
    Ok(())
}
