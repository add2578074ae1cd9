//! The files each command reads and writes, listed for one check before the work starts
//! (data::output::RunFiles): no output replaces an input (even with `--force`), another output
//! of the run or a kept eval report; an existing file is replaced only when it is an earlier
//! output of the same kind (a graspmap JSON report, a video, a report page) or with the
//! command's `--force`; missing folders are created.

use std::path::Path;

use anyhow::bail;

use crate::commands::collect::{CollectConfig, CollectPolicy};
use crate::commands::eval::EvalConfig;
use crate::commands::grasp::GraspConfig;
use crate::commands::improve::ImproveConfig;
use crate::commands::label::{ClickSource, LabelConfig};
use crate::commands::merge::MergeConfig;
use crate::commands::predict::PredictConfig;
use crate::commands::report::ReportConfig;
use crate::commands::scene::{SceneConfig, SceneSource};
use crate::commands::train::TrainOptions;
use crate::commands::Context;
use crate::data::output::{identity, Existing, Kind, RunFiles};
use crate::policy::PolicyKind;
use crate::present::report_page::files_dir;

/// What every command writes: `--json`; and the kept eval reports, which no named output may
/// replace. `force`: the command's `--force` for its outputs, where it has one.
pub(super) fn base(context: &Context, force: Option<bool>) -> RunFiles {
    let mut files = RunFiles {
        force,
        data: Some(context.data.clone()),
        ..RunFiles::default()
    };
    files.protect_kept_reports(&context.data);
    files.output(
        context.json.as_deref(),
        "--json",
        Existing::Earlier(Kind::JsonReport(context.command)),
    );
    files
}

pub(super) fn scene(context: &Context, config: &SceneConfig, force: bool) -> RunFiles {
    let mut files = base(context, Some(force));
    files.output(Some(&config.out), "--out", Existing::Force);
    files.output(config.depth.as_deref(), "--depth", Existing::Force);
    files.output(config.save.as_deref(), "--save", Existing::Force);
    if let SceneSource::Load(file) = &config.source {
        files.input("the --load scene file this command reads", Some(file));
    }
    files
}

pub(super) fn grasp(context: &Context, config: &GraspConfig, force: bool) -> RunFiles {
    let mut files = base(context, Some(force));
    files.output(
        config.record.as_deref(),
        "--record",
        Existing::Own(Kind::Video),
    );
    files.output(config.image.as_deref(), "--image", Existing::Force);
    files
}

pub(super) fn label(context: &Context, config: &LabelConfig) -> RunFiles {
    let mut files = base(context, None);
    match &config.source {
        ClickSource::File(path) => files.input("the --clicks file this command reads", Some(path)),
        ClickSource::Interactive { preview } => {
            files.output(Some(preview), "--preview", Existing::Own(Kind::Preview))
        }
        _ => {}
    }
    files
}

pub(super) fn train(context: &Context, options: &TrainOptions) -> RunFiles {
    let mut files = base(context, None);
    files.input(
        "the --start-from checkpoint this command reads",
        options.start_from.as_deref(),
    );
    files
}

pub(super) fn eval(context: &Context, config: &EvalConfig) -> RunFiles {
    let mut files = base(context, None);
    if config.policy == PolicyKind::Model {
        files.input(
            "the --checkpoint this command reads",
            Some(&config.checkpoint),
        );
    }
    files.output(
        config.record.as_deref(),
        "--record",
        Existing::Own(Kind::Video),
    );
    files
}

pub(super) fn collect(context: &Context, config: &CollectConfig) -> RunFiles {
    let mut files = base(context, None);
    if matches!(config.policy, CollectPolicy::Model | CollectPolicy::Mix) {
        files.input(
            "the --checkpoint this command reads",
            Some(&config.checkpoint),
        );
    }
    files
}

pub(super) fn improve(context: &Context, config: &ImproveConfig) -> RunFiles {
    let mut files = base(context, None);
    files.input("the --checkpoint this command reads", Some(&config.start));
    files
}

/// `merge`: a merged report file is replaced only with --force, and never when it is one of the
/// shards; a merged store always goes to a new or empty folder (the merge checks it).
pub(super) fn merge(
    context: &Context,
    config: &MergeConfig,
    force: bool,
) -> anyhow::Result<RunFiles> {
    crate::commands::merge::check_inputs(&config.inputs)?;
    let mut files = base(context, Some(force));
    for input in &config.inputs {
        files.input(&format!("the input {}", input.display()), Some(input));
    }
    if config.inputs.iter().all(|p| p.is_file()) {
        files.output(Some(&config.out), "--out", Existing::Force);
    } else if force {
        bail!(
            "--force replaces a merged report file, and these inputs are trial stores, which merge into a new or empty --out folder; leave --force out"
        );
    }
    Ok(files)
}

/// `predict`: the default visualisation (under DATA) is the command's own; a named `--out` is
/// replaced only with --force.
pub(super) fn predict(
    context: &Context,
    config: &PredictConfig,
    force: bool,
    named: bool,
) -> RunFiles {
    let mut files = base(context, Some(force));
    files.input("the --image this command reads", Some(&config.image));
    files.input("the --depth this command reads", config.depth.as_deref());
    files.input(
        "the --checkpoint this command reads",
        Some(&config.checkpoint),
    );
    let existing = if named {
        Existing::Force
    } else {
        Existing::Replace
    };
    files.output(Some(&config.out), "--out", existing);
    files
}

/// `report`: the page replaces an earlier report page (or anything with --force), and its
/// `<stem>_files/` folder, whose other files it deletes, must belong to that page and must not
/// hold the data directory.
pub(super) fn report(
    context: &Context,
    config: &ReportConfig,
    force: bool,
    named: bool,
) -> anyhow::Result<RunFiles> {
    let mut files = base(context, Some(force));
    // The default page too: DATA/report.html may be a page the user wrote.
    files.output(Some(&config.out), "--out", Existing::Own(Kind::ReportPage));
    let folder = files_dir(&config.out);
    let data = identity(&context.data);
    if identity(&folder) == data || data.starts_with(identity(&folder)) {
        bail!(
            "--out {}: its files folder {} would hold the data directory {}, and the report empties that folder; choose another --out",
            config.out.display(),
            folder.display(),
            context.data.display()
        );
    }
    let holds_files = folder.read_dir().is_ok_and(|mut e| e.next().is_some());
    // The default page's folder is the command's own; a named page's folder is, when that
    // page is an earlier report.
    if holds_files && !force && named && !report_page_at(&config.out) {
        bail!(
            "--out {}: the folder {} beside it already holds files that no graspmap report page there wrote, and the report deletes what it does not write there; choose another --out, or pass --force",
            config.out.display(),
            folder.display()
        );
    }
    Ok(files)
}

/// Whether `path` holds a page that `graspmap report` wrote.
fn report_page_at(path: &Path) -> bool {
    std::fs::read_to_string(path).is_ok_and(|t| t.contains("<title>graspmap run report</title>"))
}
