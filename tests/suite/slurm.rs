//! A real one-node Slurm (munged, slurmctld, slurmd from scripts/slurm/slurm.conf.in): the job
//! array of scripts/slurm/submit.sh shards an empty_bin sweep, its merge job joins the shards,
//! and the merged report equals the same sweep run in one process; a killed task, resubmitted
//! alone, lets the merge complete.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use crate::common::{assert_ok, graspmap};
use crate::eval::read_json;
use serde_json::Value;

const REPO: &str = env!("CARGO_MANIFEST_DIR");

/// The local cluster, stopped when dropped (whether the test passes or not).
struct Cluster {
    state: PathBuf,
    conf: String,
}

impl Cluster {
    fn start(state: &Path) -> Self {
        // Installs slurm-wlm and munge when they are missing and we are root; otherwise it says
        // which command would, and the start below fails naming it.
        let setup = Command::new(format!("{REPO}/scripts/setup-system.sh"))
            .args(["slurm-wlm", "munge"])
            .output()
            .expect("running scripts/setup-system.sh");
        let out = Command::new(format!("{REPO}/scripts/slurm/local-cluster.sh"))
            .arg("start")
            .arg(state)
            .output()
            .expect("running scripts/slurm/local-cluster.sh");
        assert!(
            out.status.success(),
            "a local Slurm could not start; this test needs root and Debian's slurm-wlm and munge \
             (sudo scripts/setup-system.sh slurm-wlm munge): {}{}",
            String::from_utf8_lossy(&setup.stderr),
            String::from_utf8_lossy(&out.stderr)
        );
        let conf = String::from_utf8_lossy(&out.stdout).trim().to_owned();
        Self {
            state: state.to_path_buf(),
            conf,
        }
    }

    /// A command with this cluster's SLURM_CONF.
    fn command(&self, program: &str) -> Command {
        let mut command = Command::new(program);
        command.env("SLURM_CONF", &self.conf);
        command
    }

    /// Waits for a job to end; its final state (COMPLETED, FAILED, CANCELLED, ...).
    fn wait(&self, job: &str, limit: Duration) -> String {
        let deadline = Instant::now() + limit;
        loop {
            let out = self
                .command("scontrol")
                .args(["show", "job", job, "--oneliner"])
                .output()
                .unwrap();
            let text = String::from_utf8_lossy(&out.stdout).into_owned();
            let state = text
                .split_whitespace()
                .find_map(|f| f.strip_prefix("JobState="))
                .unwrap_or("UNKNOWN")
                .to_owned();
            if !matches!(
                state.as_str(),
                "PENDING" | "RUNNING" | "CONFIGURING" | "COMPLETING"
            ) {
                return state;
            }
            assert!(
                Instant::now() < deadline,
                "job {job} still {state} after {limit:?}"
            );
            std::thread::sleep(Duration::from_millis(250));
        }
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new(format!("{REPO}/scripts/slurm/local-cluster.sh"))
            .arg("stop")
            .arg(&self.state)
            .output();
    }
}

/// The job ids submit.sh and resubmit.sh keep in RUN_DIR/jobs.env.
fn jobs(run_dir: &Path) -> (String, String) {
    let text = std::fs::read_to_string(run_dir.join("jobs.env")).unwrap();
    let get = |key: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(&format!("{key}=")))
            .unwrap()
            .to_owned()
    };
    (get("ARRAY_JOB"), get("MERGE_JOB"))
}

/// A report's scenes and attempts without their timings, and its summary.
fn comparable(report: &Value) -> Value {
    let mut results = report["results"].clone();
    results["timing"] = Value::Null;
    for run in results["runs"].as_array_mut().unwrap() {
        for attempt in run["attempts"].as_array_mut().unwrap() {
            attempt["timing"] = Value::Null;
        }
    }
    let mut config = report["config"].clone();
    for key in ["json", "threads"] {
        config["global"][key] = Value::Null;
    }
    serde_json::json!({ "config": config, "results": results, "seed": report["seed"], "git_commit": report["git_commit"] })
}

#[test]
fn a_sharded_sweep_under_slurm_merges_into_the_one_process_sweep_and_survives_a_killed_task() {
    let dir = tempfile::tempdir().unwrap();
    let cluster = Cluster::start(&dir.path().join("slurm"));
    let data = dir.path().join("data");
    std::fs::create_dir_all(&data).unwrap();
    let split = data.join("split.json");
    std::fs::write(
        &split,
        r#"{"train": ["YcbTomatoSoupCan", "YcbFoamBrick"], "test": ["YcbGelatinBox"]}"#,
    )
    .unwrap();
    let sweep = [
        "eval",
        "--split",
        split.to_str().unwrap(),
        "--task",
        "empty_bin",
        "--policy",
        "oracle",
        "--seeds",
        "1-4",
        "--max-attempts",
        "3",
        "--n-past-action",
        "8",
    ];

    // The same sweep in one process.
    let single = dir.path().join("single.json");
    let mut args = vec![
        "--data",
        data.to_str().unwrap(),
        "--quiet",
        "--json",
        single.to_str().unwrap(),
    ];
    args.extend_from_slice(&sweep);
    assert_ok(&graspmap(&args));
    let single = read_json(&single);

    let run_dir = dir.path().join("run");
    let submit = |script: &str, args: &[&str]| {
        let out = cluster
            .command(&format!("{REPO}/scripts/slurm/{script}"))
            .args(args)
            .env("RUN_DIR", &run_dir)
            .env("DATA", &data)
            .env("SHARDS", "4")
            .env("CPUS_PER_TASK", "1")
            .env("MEM_PER_TASK", "1G")
            .env("TIME_LIMIT", "00:10:00")
            .env("GRASPMAP", env!("CARGO_BIN_EXE_graspmap"))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{script}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    submit("submit.sh", &sweep);
    let (array, merge) = jobs(&run_dir);
    let state = cluster.wait(&merge, Duration::from_secs(150));
    assert_eq!(
        state,
        "COMPLETED",
        "merge job; logs in {}",
        run_dir.join("logs").display()
    );
    let merged = read_json(&run_dir.join("merged.json"));
    assert_eq!(comparable(&merged), comparable(&single));
    for i in 1..=4 {
        let shard = read_json(&run_dir.join(format!("shard_{i}.json")));
        assert_eq!(shard["config"]["shard"], format!("{i}/4"));
        assert_eq!(shard["results"]["seeds"], serde_json::json!([i]));
    }
    assert!(array.parse::<u64>().is_ok(), "{array}");

    // A killed task fails the array, and Slurm drops the merge that waited on it; the task
    // resubmitted alone, the new merge completes with the same report.
    std::fs::remove_file(run_dir.join("merged.json")).unwrap();
    std::fs::remove_file(run_dir.join("shard_2.json")).unwrap();
    submit("submit.sh", &sweep);
    let (array, merge) = jobs(&run_dir);
    let killed = cluster
        .command("scancel")
        .args(["--signal", "KILL", "--full", &format!("{array}_2")])
        .output()
        .unwrap();
    assert!(killed.status.success());
    let state = cluster.wait(&merge, Duration::from_secs(150));
    assert_ne!(state, "COMPLETED", "the merge ran without shard 2");
    // The killed task's shard is not there to merge (or is the unfinished part it wrote).
    submit("resubmit.sh", &["2"]);
    let (_, merge) = jobs(&run_dir);
    let state = cluster.wait(&merge, Duration::from_secs(150));
    assert_eq!(state, "COMPLETED", "the merge after the resubmitted task");
    let merged = read_json(&run_dir.join("merged.json"));
    assert_eq!(comparable(&merged), comparable(&single));
}
