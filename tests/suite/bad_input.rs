//! Every bad input a user can give, in one table: the command line, the exit status it must end
//! with, a phrase its one-line message must hold (and one it must not), run against one small
//! real workspace (the reference fixture's labels and a one-epoch model). The HTTP cases of the
//! labelling page close the file, with the status they must get.
//!
//! Read-only folders are read-only for root too: as root the command runs under `setpriv` with
//! CAP_DAC_OVERRIDE dropped from its bounding set, as an ordinary user would run it.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use crate::common::{assert_ok, graspmap};

const BIN: &str = env!("CARGO_BIN_EXE_graspmap");

/// How a case runs.
#[derive(Clone, Copy, PartialEq)]
enum How {
    /// As is.
    Plain,
    /// Without the right to write read-only folders (dropped as root).
    Unprivileged,
    /// SIGINT once the output (stdout or stderr) holds this phrase: the command is past its
    /// checks and at work, however loaded the machine.
    InterruptOnceSaid(&'static str),
    /// The reader of stdout goes away after the first line (`| head -1`).
    FirstLineOnly,
    /// While this process holds the labels' writer lock, as a running `label` would.
    LabelsLocked,
    /// And this file of the data dir must be left byte for byte as it was.
    Keeps(&'static str),
}

/// One row: the arguments (`{data}`, `{fresh}`, `{ro}`, `{tmp}` filled in), the exit status,
/// a phrase the output must hold, one it must not ("" for none), and how it runs.
struct Case {
    args: &'static str,
    code: i32,
    phrase: &'static str,
    absent: &'static str,
    how: How,
}

const fn case(args: &'static str, code: i32, phrase: &'static str) -> Case {
    Case {
        args,
        code,
        phrase,
        absent: "",
        how: How::Plain,
    }
}

impl Case {
    const fn without(mut self, absent: &'static str) -> Self {
        self.absent = absent;
        self
    }

    const fn how(mut self, how: How) -> Self {
        self.how = how;
        self
    }
}

/// The rows, in the order they run (a few build on the one before: the resume reads what the
/// interrupted sweep kept).
const CASES: &[Case] = &[
    // Nothing trained is replaced silently.
    case(
        "--data {data} train --epochs 2 --batch-size 2 --lr 0.002",
        2,
        "already holds a trained model",
    )
    .without("--checkpoint"),
    case(
        "--data {data} train --epochs 2 --batch-size 2 --lr 0.002",
        2,
        "--force",
    ),
    case(
        "--data {data} train --epochs 1 --batch-size 2",
        0,
        "already trained 1 epoch (",
    ),
    case("--data {data} train --resume --force", 2, "--force"),
    case(
        "--data {data} train --epochs 1 --batch-size 2",
        2,
        "wait for it to finish",
    )
    .how(How::LabelsLocked),
    case(
        "--data {fresh} train --epochs 1 --batch-size 2 --force",
        0,
        "best.prev.safetensors",
    ),
    case(
        "--data {truncated} train --resume --batch-size 2",
        2,
        "--force",
    )
    .without("--checkpoint"),
    case(
        "--data {fresh} train --epochs 1 --batch-size 2 --force",
        0,
        "trained 1 epoch on 4 labels",
    )
    .without("1 epochs"),
    case("--help", 0, "Usage: graspmap"),
    case("train --help", 0, "[default: 30]").without("--split"),
    // Each command's --help lists only the flags it takes.
    case("train --help", 0, "--data <DIR>").without("--objects-dir"),
    case("predict --help", 0, "--threads <N>").without("--split"),
    case("report --help", 0, "--data <DIR>").without("--objects-dir"),
    case("scene --help", 0, "--objects-dir <DIR>").without("--split"),
    case("merge --help", 0, "--allow-partial").without("--objects-dir"),
    case("eval --help", 0, "--split <FILE>"),
    // The advice of a refusal is a command that works: --resume would meet the same difference.
    case(
        "--data {data} train --epochs 2 --batch-size 2 --lr 0.002",
        2,
        "--out-dir DIR",
    )
    .without("--resume"),
    case(
        "--data {data} train --trials {tmp}/trials --epochs 1 --batch-size 2",
        2,
        "already holds a trained model",
    )
    .without("--resume"),
    case(
        "--data {data} train --trials {tmp}/trials --epochs 1 --batch-size 2 --out-dir {tmp}/tuned",
        0,
        "trained 1 epoch on 4 labels and",
    ),
    case(
        "--data {data} improve --rounds 1 --scenes 1 --epochs 1 --max-attempts 2 --clutter 1 --policy oracle",
        0,
        "the improved model is",
    ),
    case(
        "--data {data} improve --rounds 1 --scenes 1 --epochs 1 --max-attempts 3 --clutter 1 --policy oracle",
        2,
        "give improve another --out folder",
    )
    .without("--force"),
    // Every global flag means something, or is refused.
    case(
        "--data {data} --split {tmp}/split_both.json train",
        2,
        "--split is not used by `graspmap train`",
    ),
    case(
        "--data {data} --objects-dir {tmp}/empty train",
        2,
        "--objects-dir is not used",
    ),
    case(
        "--data {data} --split {tmp}/split_both.json report",
        2,
        "--split is not used",
    ),
    case(
        "--data {data} --split {tmp}/split_both.json predict --image {tmp}/grey.png",
        2,
        "--split is not used",
    ),
    case(
        "--split {tmp}/split_both.json scene --objects YcbPear --out {tmp}/s.png",
        2,
        "--split is not used",
    ),
    case(
        "--split {tmp}/split_both.json bench train --no-peer",
        2,
        "--split is not used",
    ),
    case(
        "--data {data} train --split {tmp}/split_both.json",
        2,
        "unexpected argument '--split'",
    ),
    case(
        "--objects-dir {tmp}/empty scene --objects YcbPear --out {tmp}/s9.png --objects-dir {tmp}/empty",
        2,
        "--objects-dir is given twice",
    ),
    case(
        "--data {data} label --check --split {tmp}/split_truncated.json",
        2,
        "split_truncated.json",
    ),
    case(
        "--data {data} --split {tmp}/split_truncated.json label --check",
        2,
        "split_truncated.json",
    ),
    case(
        "--data {data} --split {tmp}/split_truncated.json eval --task test --policy random",
        2,
        "split_truncated.json",
    ),
    case(
        "--data {data} --split {tmp}/split_both.json eval --task test --policy random",
        2,
        "in both the train and the test list",
    ),
    case(
        "--data {data} --split {tmp}/split_twice.json eval --task train --policy random",
        2,
        "listed twice",
    ),
    case(
        "--data {data} --split {tmp}/split_unknown.json eval --task test --policy random",
        2,
        "'YcbRubberDuck', which is not an object",
    ),
    // Outputs are checked before the work starts, and each OS error is said once.
    case(
        "--data {ro} eval --task test --policy random",
        2,
        "cannot write",
    )
    .how(How::Unprivileged)
    .without("objects moved"),
    case(
        "--data {ro} --json {tmp}/out.json eval --task test --policy random",
        2,
        "reports",
    )
    .how(How::Unprivileged),
    case("--data {ro} label", 2, "make it writable")
        .how(How::Unprivileged)
        .without(".lock"),
    case("--data {ro} train --epochs 1", 2, "cannot write")
        .how(How::Unprivileged)
        .without("denied (os error"),
    case(
        "--json {tmp}/missing_json/r.json grasp --object YcbPear --oracle",
        0,
        "YcbPear seed 0",
    ),
    case("--data {data} --json {tmp} train", 2, "is a directory"),
    case(
        "scene --objects YcbPear --out {tmp}/missing_scene/s.png",
        0,
        "wrote",
    ),
    case("scene --objects YcbPear --out {tmp}", 2, "is a directory"),
    case(
        "scene --objects YcbPear --out {tmp}/s8.png --depth {tmp}/missing_depth/d.png",
        0,
        "wrote",
    ),
    case(
        "grasp --object YcbPear --oracle --image {tmp}/missing_grasp/g.png",
        0,
        "YcbPear seed 0",
    ),
    case(
        "--data {data} predict --image {tmp}/photo.png --out {tmp}/missing_predict/p.png",
        0,
        "wrote",
    ),
    case(
        "--data {data} report --out {tmp}/missing_report/new/r.html",
        0,
        "wrote",
    ),
    case(
        "--data {data} eval --task empty_bin --policy random --max-attempts 1 --record {tmp}/missing_eval/e.mp4",
        0,
        "wrote the episode video",
    ),
    // No output replaces an input (even with --force), another output, a kept report, or an
    // existing file that is not an earlier output of its kind (without --force).
    case(
        "merge --out {tmp}/shard_a.json {tmp}/shard_a.json {tmp}/shard_b.json --force",
        2,
        "is also the input",
    ),
    case(
        "merge --out {tmp}/taken.json {tmp}/shard_a.json {tmp}/shard_b.json",
        2,
        "already exists; pass --force",
    ),
    case(
        "merge --out {tmp}/m2.json --json {tmp}/m2.json {tmp}/shard_a.json {tmp}/shard_b.json",
        2,
        "both name",
    ),
    case(
        "merge --force --out {tmp}/merged_store {tmp}/empty",
        2,
        "leave --force out",
    ),
    case(
        "--data {data} predict --image {tmp}/photo.png --out {tmp}/photo.png --force",
        2,
        "is also the --image",
    ),
    case(
        "--data {data} predict --image {tmp}/photo.png --out {tmp}/taken.png",
        2,
        "already exists; pass --force",
    ),
    case(
        "scene --objects YcbPear --out {tmp}/taken.png",
        2,
        "already exists",
    ),
    case(
        "grasp --object YcbPear --oracle --image {tmp}/taken.png",
        2,
        "already exists",
    ),
    case(
        "--data {data} report --out {tmp}/mine.html",
        2,
        "is not an earlier graspmap report page",
    ),
    case(
        "--data {data} --json {tmp}/notes.txt report",
        2,
        "is not an earlier graspmap report",
    ),
    // --json replaces only an earlier report of the same command, and nothing that graspmap
    // reads as state: not with --force, not outside the data directory.
    case(
        "--data {data} --json {tmp}/train_report.json eval --task test --policy random",
        2,
        "is not an earlier graspmap eval report",
    )
    .without("--force"),
    case(
        "--data {data} --json {data}/labels/labels.json eval --task test --policy random",
        2,
        "part of the labelled dataset",
    )
    .how(How::Keeps("labels/labels.json")),
    case(
        "--data {data} --json {data}/affordance/best.json eval --task test --policy random",
        2,
        "part of the model",
    )
    .how(How::Keeps("affordance/best.json")),
    case(
        "--data {data} --json {tmp}/trials/collect.json predict --image {tmp}/photo.png --force",
        2,
        "(schema graspmap.trials/1), which graspmap reads",
    ),
    case(
        "--data {data} predict --image {tmp}/photo.png --out {data}/labels/YcbHammer_1_rgb.png --force",
        2,
        "which graspmap reads",
    )
    .how(How::Keeps("labels/YcbHammer_1_rgb.png")),
    case(
        "--data {tmp}/user_page report",
        2,
        "is not an earlier graspmap report page",
    ),
    case(
        "--data {fresh} label --clicks {tmp}/clicks_test.json --json {tmp}/clicks_test.json",
        2,
        "is also the --clicks file",
    ),
    case("--data {ro} report --out {ro}/r.html", 2, "cannot write").how(How::Unprivileged),
    // Finite numbers only, within their documented range.
    case(
        "grasp --object YcbPear --pixel 64,64 --angle 1e40",
        2,
        "from -360 to 360",
    ),
    case(
        "grasp --object YcbPear --pixel 64,64 --angle nan",
        2,
        "--angle",
    ),
    case(
        "grasp --object YcbPear --pixel 64,64 --angle inf",
        2,
        "--angle",
    ),
    case(
        "grasp --object YcbPear --pixel 64,64 --angle -400",
        2,
        "from -360 to 360",
    ),
    case(
        "--data {fresh} label --clicks {tmp}/clicks_huge.json",
        2,
        "from -360 to 360",
    ),
    case("--data {data} train --lr 1e40", 2, "--lr"),
    case("--data {data} train --lr nan", 2, "--lr"),
    case(
        "--data {data} eval --task test --suppression-sigma 1e40",
        2,
        "--suppression-sigma",
    ),
    case(
        "grasp --object YcbPear --oracle --grip-force 1e30",
        2,
        "--grip-force",
    ),
    case("grasp --object YcbPear --oracle --grip-force -3", 2, "-3"),
    case(
        "--data {fresh} label --click-noise-px 1e9",
        2,
        "--click-noise-px",
    ),
    case(
        "--data {fresh} label --angle-noise-deg inf",
        2,
        "--angle-noise-deg",
    ),
    case(
        "--data {data} eval --task test --verify-floor 1.5",
        2,
        "fraction from 0 to 1",
    ),
    // label --check checks everything label reads.
    case("--data {bad_progress} label --check", 2, "progress.json"),
    case("--data {short_progress} label --check", 2, "records"),
    case("--data {png_cut} label --check", 2, "truncated"),
    case("--data {png16} label --check", 2, "Rgb16"),
    // Long runs say how long, and an interrupted sweep keeps its scenes.
    case(
        "--data {data} eval --task empty_bin --policy random --seeds 1-100000 --max-attempts 1",
        130,
        "100000 attempts in all",
    )
    .how(How::InterruptOnceSaid("attempts in all")),
    case(
        "--data {data} eval --task empty_bin --policy random --seeds 1-100000 --max-attempts 1 --resume",
        130,
        "scenes already in",
    )
    .how(How::InterruptOnceSaid("scenes already in")),
    // A smaller or different run keeps its report beside the larger one's, never over it.
    case(
        "--data {data} eval --task empty_bin --policy random",
        0,
        "report kept in",
    ),
    case(
        "--data {data} eval --task empty_bin --policy random --max-attempts 1",
        0,
        "beside, never over",
    )
    .how(How::Keeps("reports/eval_empty_bin_random.json")),
    case(
        "--data {data} eval --task empty_bin --policy random --seeds 2,3 --max-attempts 2",
        0,
        "beside, never over",
    )
    .how(How::Keeps("reports/eval_empty_bin_random.json")),
    case(
        "--data {data} --json {data}/reports/eval_empty_bin_random.json train --epochs 1",
        2,
        "a report that eval keeps",
    )
    .how(How::Keeps("reports/eval_empty_bin_random.json")),
    // Every flag applies, or is refused naming it.
    case("grasp --object YcbPear --oracle --angle 30", 2, "--angle"),
    case("grasp --object YcbPear --random --angle 30", 2, "--angle"),
    case("--data {data} train --trial-weight 0.5", 2, "--trial-weight"),
    case("--data {data} train --trial-sigma 2", 2, "--trial-sigma"),
    case(
        "--data {data} train --trials {tmp}/trials --trials {tmp}/trials",
        2,
        "given twice",
    ),
    case(
        "--data {data} eval --task train --give-up-after 3",
        2,
        "--give-up-after applies to --task empty_bin or scenes only",
    ),
    case(
        "--data {data} eval --task test --max-attempts 3",
        2,
        "--max-attempts applies to --task empty_bin or scenes only",
    ),
    case(
        "--data {data} eval --task train --n-past-action 8",
        2,
        "--n-past-action",
    ),
    case(
        "--data {data} eval --task train --policy random --verify-top 10 --checkpoint /nonexistent",
        2,
        "applies to --policy model only",
    ),
    case(
        "--data {data} eval --task empty_bin --policy oracle --suppression-sigma 3",
        2,
        "--suppression-sigma",
    ),
    case(
        "--data {data} eval --task empty_bin --policy random --n-past-action 8",
        2,
        "--n-past-action applies to --policy model and oracle only",
    ),
    case(
        "--data {data} collect --policy oracle --explore 0.9",
        2,
        "--explore applies to --policy model and mix only",
    ),
    case(
        "--data {data} collect --policy model --oracle-share 0.2",
        2,
        "--oracle-share",
    ),
    case(
        "--data {data} improve --policy random --n-past-action 4",
        2,
        "--n-past-action",
    ),
    case("--data {data} collect --check --scenes 3", 2, "--scenes"),
    case(
        "--data {fresh} label --web --click-noise-px 1",
        2,
        "--click-noise-px",
    ),
    case("--data {data} label --check --per-object 3", 2, "--per-object"),
    case(
        "--data {data} label --delete YcbHammer:1 --seed 3",
        2,
        "--seed",
    ),
    // Inputs that are not files or folders, seeds whose derived seeds would wrap, and global
    // flags a command never reads.
    case("merge --out {tmp}/m3.json /dev/null", 2, "/dev/null").without("panicked"),
    case(
        "--data {data} eval --task test --policy random --seeds 18446744073709551615",
        2,
        "give a seed of at most",
    ),
    case(
        "--data {tmp}/huge_seed label --seed 18446744073709551615",
        2,
        "give a seed of at most",
    ),
    case(
        "--data {data} improve --seed 18446744073709551615",
        2,
        "give a seed of at most",
    ),
    case(
        "--data {data} scene --objects YcbPear --out {tmp}/s_data.png",
        2,
        "--data is not used by `graspmap scene`",
    ),
    case(
        "grasp --data {data} --object YcbPear --oracle",
        2,
        "--data is not used by `graspmap grasp`",
    ),
    case(
        "--threads 2 scene --objects YcbPear --out {tmp}/s_threads.png",
        2,
        "--threads is not used",
    ),
    // --quiet: the results, not the scene's progress.
    case(
        "--data {data} --quiet eval --task empty_bin --policy oracle --max-attempts 1",
        0,
        "objects moved: ",
    )
    .without("/15 objects moved"),
    // The smaller slips.
    case("--data {data} train --epochs -1", 2, "--epochs"),
    case(
        "--data {data} eval --task test --max-attempts -3",
        2,
        "--max-attempts",
    ),
    case("", 2, "no command given: choose one of scene"),
    case("label --help", 0, "Collect verified grasp labels").how(How::FirstLineOnly),
    case("--version", 0, "graspmap").how(How::FirstLineOnly),
    case(
        "--data {data} eval --task empty_bin --policy oracle --max-attempts 3",
        0,
        "objects moved",
    )
    .how(How::FirstLineOnly)
    .without("panicked"),
    case(
        "--data {data} report --serve --port 0",
        130,
        "server stopped",
    )
    .how(How::InterruptOnceSaid("Ctrl-C stops the server")),
    case(
        "--data {data} eval --task test --checkpoint {tmp}",
        2,
        "is a directory",
    ),
    case(
        "--data {data} predict --image {tmp}/photo.png --checkpoint {tmp}",
        2,
        "is a directory",
    ),
    case(
        "--data {data} predict --image {tmp}/grey.png",
        2,
        "8-bit greyscale",
    )
    .without("L8"),
    case(
        "--objects-dir {tmp}/empty scene --objects YcbPear --out {tmp}/s.png",
        2,
        "holds no objects",
    ),
    case("grasp --object Foo --oracle", 2, "unknown object 'Foo'").without("bundled:"),
    case(
        "--data {fresh} label --clicks {tmp}/clicks_test.json",
        2,
        "is a test object",
    ),
    case("eval --help", 0, "--n-past-action <N>"),
    case(
        "--data {data} eval --task test --n_past_action x",
        2,
        "--n-past-action",
    ),
    // Cases that worked before, kept working.
    case(
        "grasp --object YcbPear --pixel 128,3 --angle 0",
        2,
        "outside",
    ),
    case(
        "grasp --object YcbPear --pixel 3 --angle 0",
        2,
        "two integers",
    ),
    case(
        "--data {fresh} label --clicks {tmp}/missing.json",
        2,
        "missing.json",
    ),
    case("--data {data} predict --image {tmp}/small.png", 2, "64×64"),
    case(
        "--data {data} predict --image {tmp}/missing.png",
        2,
        "missing.png",
    ),
    case(
        "--data {data} eval --task test --checkpoint {tmp}/corrupt.safetensors",
        2,
        "corrupt.safetensors",
    ),
    case("--data {tmp}/nothing eval --task test", 2, "not found"),
    case(
        "scene --objects YcbRubberDuck --out {tmp}/s.png",
        2,
        "unknown object 'YcbRubberDuck'",
    ),
    case(
        "--threads 0 scene --objects YcbPear --out {tmp}/s.png",
        2,
        "--threads",
    ),
    case("--data {data} eval --task nope", 2, "nope"),
    case("--data {data} train --batch-size 0", 2, "--batch-size"),
    case("--data {fresh} label --per-object 0", 2, "--per-object"),
    case(
        "--objects-dir {tmp}/nowhere scene --objects YcbPear --out {tmp}/s.png",
        2,
        "not a directory",
    ),
    case(
        "--data {data} eval --task test --verify-top 0 --verify-floor 0.25",
        2,
        "--verify-top 0",
    ),
    case(
        "--data {data} eval --task test --verify-top 0 --verify-rejected 50",
        2,
        "--verify-top 0",
    ),
    case(
        "--data {data} eval --task test --centring --collision-check walls",
        2,
        "--centring",
    ),
    case(
        "--data {data} label --delete YcbHammer:99",
        2,
        "does not exist",
    ),
    case("--data {data} train --input rgbd", 2, "depth"),
    // Trials, crops, shards and merges.
    case("--data {data} train --crop 30", 2, "multiple of 4"),
    case("--data {data} train --trial-weight 0", 2, "--trial-weight"),
    case("--data {data} train --no-labels", 2, "--trials"),
    case(
        "--data {data} train --trials {tmp}/nothing --epochs 1",
        2,
        "not a trial store",
    ),
    case("--data {data} collect --shard 5/4", 2, "5/4"),
    case("--data {data} collect --shard x", 2, "I/N"),
    case(
        "--data {data} collect --clutter 9 --scenes 1",
        2,
        "--clutter 9",
    ),
    case("--data {data} collect --explore 1.5", 2, "--explore"),
    case(
        "--data {data} collect --check --out {tmp}/nothing",
        2,
        "problem(s)",
    ),
    case(
        "--data {data} collect --scenes 1 --checkpoint {tmp}/none.safetensors",
        2,
        "none.safetensors",
    ),
    case(
        "--data {data} eval --task test --seeds 1-2 --shard 3/3",
        2,
        "--shard 3/3",
    ),
    case(
        "--data {data} eval --task empty_bin --shard 1/2 --record {tmp}/x.mp4",
        2,
        "--record",
    ),
    case(
        "merge --out {tmp}/m.json {tmp}/missing.json",
        2,
        "missing.json",
    ),
    case("merge --out {tmp}/m.json", 2, "SHARD_DIR"),
    case("--data {data} improve --rounds 0", 2, "--rounds"),
    case("--data {data} improve --lr nan", 2, "--lr"),
    case(
        "--data {data} collect --policy oracle --checkpoint {tmp}/m.safetensors",
        2,
        "--policy oracle",
    ),
    case(
        "--data {tmp}/empty improve --rounds 1 --scenes 1",
        2,
        "graspmap train",
    ),
];

/// The workspace the rows run in.
struct Workspace {
    tmp: tempfile::TempDir,
    fresh: std::cell::Cell<u32>,
}

impl Workspace {
    fn path(&self, name: &str) -> PathBuf {
        self.tmp.path().join(name)
    }

    /// The reference fixture's four labels and a one-epoch model, plus every bad file a row
    /// names.
    fn new() -> Self {
        let tmp = tempfile::tempdir().unwrap();
        let ws = Workspace {
            tmp,
            fresh: std::cell::Cell::new(0),
        };
        let data = ws.path("data");
        copy_labels(&data);
        let data_text = data.to_str().unwrap();
        assert_ok(&graspmap(&[
            "--data",
            data_text,
            "--threads",
            "2",
            "train",
            "--epochs",
            "1",
            "--batch-size",
            "2",
        ]));
        let write = |name: &str, text: &str| std::fs::write(ws.path(name), text).unwrap();
        write(
            "split_both.json",
            r#"{"train": ["YcbHammer"], "test": ["YcbHammer", "YcbPear"]}"#,
        );
        write(
            "split_twice.json",
            r#"{"train": ["YcbHammer", "YcbHammer"], "test": []}"#,
        );
        write(
            "split_unknown.json",
            r#"{"train": ["YcbHammer"], "test": ["YcbRubberDuck"]}"#,
        );
        write("split_truncated.json", r#"{"train": ["YcbHammer", "#);
        write(
            "clicks_huge.json",
            r#"[{"object": "YcbHammer", "x": 64, "y": 64, "angle": 1e40}]"#,
        );
        write(
            "clicks_test.json",
            r#"[{"object": "YcbBanana", "x": 64, "y": 64, "angle": 0}]"#,
        );
        write("corrupt.safetensors", "not a checkpoint");
        // Files that outputs must not replace: existing ones that graspmap did not write, and
        // two "shards" (only their names matter: the outputs are checked first).
        write("taken.json", "{}");
        write("notes.txt", "my notes");
        write("mine.html", "<p>my page</p>");
        std::fs::create_dir_all(ws.path("user_page")).unwrap();
        write("user_page/report.html", "<p>my page</p>");
        write(
            "train_report.json",
            r#"{"schema": "graspmap.train/1", "results": {}}"#,
        );
        write("shard_a.json", "{}");
        write("shard_b.json", "{}");
        std::fs::create_dir_all(ws.path("empty")).unwrap();
        image::GrayImage::from_pixel(128, 128, image::Luma([90]))
            .save(ws.path("grey.png"))
            .unwrap();
        image::RgbImage::from_pixel(64, 64, image::Rgb([90, 20, 20]))
            .save(ws.path("small.png"))
            .unwrap();
        image::RgbImage::from_pixel(128, 128, image::Rgb([90, 20, 20]))
            .save(ws.path("photo.png"))
            .unwrap();
        std::fs::copy(ws.path("photo.png"), ws.path("taken.png")).unwrap();
        // A small trial store.
        assert_ok(&graspmap(&[
            "--data",
            data_text,
            "--threads",
            "2",
            "collect",
            "--scenes",
            "1",
            "--policy",
            "oracle",
            "--max-attempts",
            "2",
            "--clutter",
            "1",
            "--out",
            ws.path("trials").to_str().unwrap(),
        ]));
        // A read-only data dir holding labels and a model.
        let ro = ws.path("ro");
        copy_tree(&data, &ro);
        set_read_only(&ro);
        // A model whose resume state was cut short.
        let truncated = ws.path("truncated");
        copy_tree(&data, &truncated);
        let last = truncated.join("affordance/last.safetensors");
        let bytes = std::fs::read(&last).unwrap();
        std::fs::write(&last, &bytes[..bytes.len() / 3]).unwrap();
        // A label image cut short, and one in 16-bit RGB: both decode to no training image.
        for (name, damage) in [("png_cut", 0), ("png16", 1)] {
            let dir = ws.path(name);
            copy_labels(&dir);
            let image = dir.join("labels/YcbHammer_1_rgb.png");
            if damage == 0 {
                let bytes = std::fs::read(&image).unwrap();
                std::fs::write(&image, &bytes[..bytes.len() * 2 / 3]).unwrap();
            } else {
                image::ImageBuffer::<image::Rgb<u16>, _>::from_pixel(
                    128,
                    128,
                    image::Rgb([9000, 300, 300]),
                )
                .save(&image)
                .unwrap();
            }
        }
        // progress.json that does not parse, and one whose counts disagree with the labels.
        for (name, text) in [
            (
                "bad_progress",
                "{\"schema\": \"graspmap.label-progress/2\", \"seed\": ",
            ),
            (
                "short_progress",
                r#"{"schema": "graspmap.label-progress/2", "seed": 0, "rounds": [{"object": "YcbHammer", "rounds": 9, "labels": 5, "sources": []}]}"#,
            ),
        ] {
            let dir = ws.path(name);
            copy_labels(&dir);
            std::fs::write(dir.join("labels/progress.json"), text).unwrap();
        }
        ws
    }

    /// A fresh copy of the base data dir, for a row that changes it.
    fn fresh(&self) -> PathBuf {
        let n = self.fresh.get() + 1;
        self.fresh.set(n);
        let dir = self.path(&format!("fresh{n}"));
        copy_tree(&self.path("data"), &dir);
        dir
    }

    /// The row's arguments with the workspace's paths filled in.
    fn args(&self, row: &str) -> Vec<String> {
        row.split_whitespace()
            .map(|word| {
                let mut word = word.replace("{tmp}", self.tmp.path().to_str().unwrap());
                for name in [
                    "data",
                    "ro",
                    "truncated",
                    "bad_progress",
                    "short_progress",
                    "png_cut",
                    "png16",
                ] {
                    word = word.replace(&format!("{{{name}}}"), self.path(name).to_str().unwrap());
                }
                if word.contains("{fresh}") {
                    word = word.replace("{fresh}", self.fresh().to_str().unwrap());
                }
                word
            })
            .collect()
    }
}

/// The reference fixture's labels as `dir/labels`.
fn copy_labels(dir: &Path) {
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/reference-labels");
    copy_tree(&fixture, &dir.join("labels"));
}

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap().flatten() {
        let target = to.join(entry.file_name());
        if entry.path().is_dir() {
            copy_tree(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}

fn set_read_only(dir: &Path) {
    use std::os::unix::fs::PermissionsExt;
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        if entry.path().is_dir() {
            set_read_only(&entry.path());
        }
    }
    std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o555)).unwrap();
}

/// The command for a row: as root and unprivileged, under setpriv without CAP_DAC_OVERRIDE.
fn command(args: &[String], how: How) -> Command {
    // SAFETY: geteuid only reads the process's effective user id.
    let root = unsafe { libc::geteuid() } == 0;
    let mut command = if how == How::Unprivileged && root {
        assert!(
            Path::new("/usr/bin/setpriv").exists(),
            "the read-only cases need setpriv as root: apt-get install util-linux"
        );
        let mut c = Command::new("/usr/bin/setpriv");
        c.args(["--bounding-set=-dac_override,-dac_read_search", "--", BIN]);
        c
    } else {
        Command::new(BIN)
    };
    command.args(args).env_remove("GRASPMAP_LOG");
    command
}

/// Runs one row and returns its output.
fn run(ws: &Workspace, case: &Case) -> Output {
    let args = ws.args(case.args);
    let mut command = command(&args, case.how);
    match case.how {
        How::Plain | How::Unprivileged | How::Keeps(_) => command.output().unwrap(),
        How::LabelsLocked => {
            let _held =
                graspmap::data::lock::StoreLock::acquire(&ws.path("data").join("labels"), "label")
                    .unwrap();
            command.output().unwrap()
        }
        How::InterruptOnceSaid(phrase) => interrupt_once_said(command, phrase),
        How::FirstLineOnly => {
            let mut child = command
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap();
            let mut first = String::new();
            BufReader::new(child.stdout.take().unwrap())
                .read_line(&mut first)
                .unwrap();
            // The reader is gone: stdout is closed before the rest is written.
            let mut stderr = Vec::new();
            child
                .stderr
                .take()
                .unwrap()
                .read_to_end(&mut stderr)
                .unwrap();
            let status = child.wait().unwrap();
            Output {
                status,
                stdout: first.into_bytes(),
                stderr,
            }
        }
    }
}

/// Runs `command`, sends it SIGINT as soon as its output holds `phrase`, and returns all of its
/// output. Fails when it ends, or a minute passes, without saying it.
fn interrupt_once_said(mut command: Command, phrase: &str) -> Output {
    let mut child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let said = std::sync::Arc::new(std::sync::Mutex::new(Vec::<u8>::new()));
    let readers: Vec<_> = [
        Box::new(child.stdout.take().unwrap()) as Box<dyn Read + Send>,
        Box::new(child.stderr.take().unwrap()),
    ]
    .into_iter()
    .map(|mut pipe| {
        let said = std::sync::Arc::clone(&said);
        std::thread::spawn(move || {
            let mut own = Vec::new();
            let mut chunk = [0u8; 4096];
            while let Ok(n @ 1..) = pipe.read(&mut chunk) {
                own.extend_from_slice(&chunk[..n]);
                said.lock().unwrap().extend_from_slice(&chunk[..n]);
            }
            own
        })
    })
    .collect();
    let what = format!("saying {phrase:?}");
    crate::common::poll_until(&mut child, &what, Duration::from_secs(60), || {
        let text = String::from_utf8_lossy(&said.lock().unwrap()).into_owned();
        match text.contains(phrase) {
            true => Ok(()),
            false => Err(text),
        }
    });
    crate::common::send_signal(&child, libc::SIGINT);
    let status = child.wait().unwrap();
    let mut outputs = readers.into_iter().map(|r| r.join().unwrap());
    Output {
        status,
        stdout: outputs.next().unwrap(),
        stderr: outputs.next().unwrap(),
    }
}

#[test]
fn every_bad_input_gets_one_line_that_names_it_and_the_status_it_should() {
    assert!(CASES.len() >= 60, "{} rows", CASES.len());
    let ws = Workspace::new();
    let mut failures = Vec::new();
    for case in CASES {
        let kept = match case.how {
            How::Keeps(file) => Some((file, std::fs::read(ws.path("data").join(file)).ok())),
            _ => None,
        };
        let out = run(&ws, case);
        let stdout = String::from_utf8_lossy(&out.stdout);
        let stderr = String::from_utf8_lossy(&out.stderr);
        let both = format!("{stdout}{stderr}");
        let code = out.status.code().unwrap_or(-1);
        let mut wrong = Vec::new();
        if code != case.code {
            wrong.push(format!("exit {code}, expected {}", case.code));
        }
        if !both.contains(case.phrase) {
            wrong.push(format!("no {:?}", case.phrase));
        }
        if !case.absent.is_empty() && both.contains(case.absent) {
            wrong.push(format!("holds {:?}", case.absent));
        }
        if both.contains("panicked") {
            wrong.push("panicked".into());
        }
        if let Some((file, before)) = kept {
            let after = std::fs::read(ws.path("data").join(file)).ok();
            if before.is_none() || after != before {
                wrong.push(format!("{file} was not kept as it was"));
            }
        }
        if case.code == 2 && stderr.trim_end().lines().count() != 1 {
            wrong.push("the error is not one line".into());
        }
        if !wrong.is_empty() {
            failures.push(format!(
                "`graspmap {}`: {}\n  stdout: {}\n  stderr: {}",
                case.args,
                wrong.join("; "),
                stdout.trim_end(),
                stderr.trim_end()
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_labelling_page_refuses_a_confirm_without_its_round_and_times_out_a_short_body() {
    let web = crate::web::WebLabeller::start(&["YcbTomatoSoupCan"], &["--per-object", "1"]);
    web.wait_state(|s| s["round"].is_object());
    // Rows: the request, the status it must get, a phrase of its message.
    let rows: [(&str, u16, &str); 2] = [
        ("{}", 400, "round_id"),
        (r#"{"round_id": "x"}"#, 409, "not the round on show"),
    ];
    for (body, status, phrase) in rows {
        let (got, text) = web.request("POST", "/api/confirm", Some(body));
        assert_eq!(got, status, "{body}: {text}");
        assert!(text.contains(phrase), "{body}: {text}");
    }
    // A Content-Length that the body never reaches, for a small body and a large one: 408
    // within the server's timeout, not a connection held open, and the server answers everyone
    // else meanwhile.
    let stalled = |length: usize| {
        let mut stream = std::net::TcpStream::connect(&web.address).unwrap();
        stream
            .set_read_timeout(Some(Duration::from_secs(30)))
            .unwrap();
        write!(
            stream,
            "POST /api/confirm HTTP/1.1\r\nHost: {}\r\nContent-Type: application/json\r\nContent-Length: {length}\r\n\r\n{{}}",
            web.address
        )
        .unwrap();
        stream
    };
    let start = Instant::now();
    let mut streams = [stalled(100), stalled(5000)];
    assert_eq!(web.request("GET", "/api/state", None).0, 200);
    for stream in &mut streams {
        let mut reply = String::new();
        let _ = stream.read_to_string(&mut reply);
        assert!(reply.starts_with("HTTP/1.1 408"), "{reply:?}");
        assert!(
            reply.contains("stopped short of its Content-Length"),
            "{reply:?}"
        );
    }
    let took = start.elapsed();
    assert!(took < Duration::from_secs(15), "{took:?}");
}
