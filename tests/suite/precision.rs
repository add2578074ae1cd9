//! `--precision auto` by measurement: under an ISA cap the kept choice is the faster of its own
//! timings, and a later run reads it back instead of timing again.

use std::path::Path;
use std::process::{Command, Output};

use crate::common::assert_ok;

/// `graspmap ARGS` with oneDNN and ATen capped at AVX2 and the cache under `cache`.
fn capped(cache: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_graspmap"))
        .args(args)
        .env("XDG_CACHE_HOME", cache)
        .env("ONEDNN_MAX_CPU_ISA", "AVX2")
        .env("ATEN_CPU_CAPABILITY", "avx2")
        .env_remove("GRASPMAP_LOG")
        .output()
        .expect("running graspmap")
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

#[test]
fn under_an_avx2_cap_auto_keeps_the_faster_precision_and_reuses_it() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let report = dir.path().join("bench.json");
    let bench = [
        "--threads",
        "2",
        "--json",
        report.to_str().unwrap(),
        "bench",
        "train",
        "--no-peer",
        "--steps",
        "1",
        "--rounds",
        "1",
    ];
    assert_ok(&capped(&cache, &bench));
    let kept_path = cache.join("graspmap").join("precision.json");
    let kept = json(&kept_path);
    let machines = kept["machines"].as_array().unwrap();
    assert_eq!(machines.len(), 1, "{kept}");
    let entry = &machines[0];
    assert_eq!(entry["machine"]["onednn_max_cpu_isa"], "AVX2");
    assert_eq!(entry["machine"]["aten_cpu_capability"], "avx2");
    for (workload, field) in [("train", "train_step_ms"), ("infer", "infer_ms")] {
        let fp32 = entry["fp32"][field].as_f64().unwrap();
        let bf16 = entry["bf16"][field].as_f64().unwrap();
        assert!(fp32 > 0.0 && bf16 > 0.0, "{entry}");
        // bf16 is chosen when it is more than 5 % faster (src/model/autotune.rs).
        let expected = if bf16 < 0.95 * fp32 { "bf16" } else { "fp32" };
        assert_eq!(
            entry[workload], expected,
            "{workload}: fp32 {fp32} ms, bf16 {bf16} ms"
        );
    }
    let plain = entry["fp32"]["train_step_ms"].as_f64().unwrap();
    let channels_last = entry["fp32_train_channels_last_ms"].as_f64().unwrap();
    assert_eq!(
        entry["fp32_train_channels_last"],
        channels_last < 0.95 * plain,
        "fp32 training: {plain} ms, {channels_last} ms in channels_last"
    );
    // The bench ran in the kept training choice.
    assert_eq!(json(&report)["results"]["precision"], entry["train"]);

    // A second run reads the choice back: the file is not rewritten.
    let bytes = std::fs::read(&kept_path).unwrap();
    let modified = std::fs::metadata(&kept_path).unwrap().modified().unwrap();
    assert_ok(&capped(&cache, &bench));
    assert_eq!(std::fs::read(&kept_path).unwrap(), bytes);
    assert_eq!(
        std::fs::metadata(&kept_path).unwrap().modified().unwrap(),
        modified
    );
}
