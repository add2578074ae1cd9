//! `--precision auto` by measurement: bf16 and fp32 timed once on this machine, under the ISA
//! oneDNN will really use, and the faster kept per CPU and ISA cap.
//!
//! The CPU's flags alone mislead: AVX-512 BF16 without AMX runs oneDNN's bf16 convolutions
//! slower than its fp32 ones, and a cap such as `ONEDNN_MAX_CPU_ISA=AVX2` leaves bf16 emulated
//! on a CPU that has it. So the choice is measured on the network's own training step and
//! 8-rotation inference, and a later run reads it back instead of measuring again. The
//! figures: BENCHMARKS.md, "Precision by measurement".

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use anyhow::Context as _;
use tch::{nn, Device, Kind, Tensor};

use super::config::DEFAULT_CROP;
use super::train::{loss, Adam};
use super::unet::{MiniUNet, Precision};
use crate::grasp::{BINS, IMAGE_SIZE};
use crate::named::Named;

/// The cache's file format.
const SCHEMA: &str = "graspmap.precision/2";
/// Timed repetitions of each workload and precision, after one warm-up.
const REPS: usize = 3;
/// A precision whose warm-up took this many times the other's median is timed once more, not
/// [`REPS`] times: bf16 emulated under an AVX2 cap is ten times slower, and timing it fully
/// would cost half a minute to learn nothing.
const HOPELESS: f64 = 3.0;
/// bf16, or fp32 training in channels_last, is chosen only when it is this much faster: each
/// changes the bits of the results, and timings of near-equal choices would otherwise pick one
/// or the other from machine to machine of the same kind.
const MARGIN: f64 = 0.95;

/// Whether the announcement of a measurement is printed (`--quiet` turns it off).
static ANNOUNCE: AtomicBool = AtomicBool::new(true);

/// `--quiet`: measure without saying so.
pub(crate) fn set_quiet(quiet: bool) {
    ANNOUNCE.store(!quiet, Ordering::Relaxed);
}

/// What the precision is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Workload {
    /// Training steps (`train`, improve's retraining).
    Train,
    /// The 8-rotation inference (`eval`, `collect`, `predict`).
    Infer,
}

/// What makes one measurement hold for another run: the CPU and the ISA oneDNN and ATen may
/// use. The thread count is not part of it; both precisions scale alike with it.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub(crate) struct MachineKey {
    /// `lscpu`'s model name (/proc/cpuinfo's `model name`).
    pub(crate) cpu_model: String,
    /// The CPU's flags that decide which kernels oneDNN has (several CPUs share a model name).
    pub(crate) cpu_flags: Vec<String>,
    /// `ONEDNN_MAX_CPU_ISA`, when set.
    pub(crate) onednn_max_cpu_isa: Option<String>,
    /// `ATEN_CPU_CAPABILITY`, when set.
    pub(crate) aten_cpu_capability: Option<String>,
    /// The graspmap release (its libtorch is pinned with it).
    pub(crate) graspmap: String,
}

/// The flags oneDNN's kernel choice turns on, as /proc/cpuinfo spells them.
const DECIDING_FLAGS: [&str; 7] = [
    "avx2",
    "avx512f",
    "avx512_vnni",
    "avx512_bf16",
    "avx512_fp16",
    "amx_bf16",
    "amx_tile",
];

impl MachineKey {
    /// This process's machine and caps, read once: neither changes while it runs.
    pub(crate) fn here() -> Self {
        static HERE: std::sync::OnceLock<MachineKey> = std::sync::OnceLock::new();
        HERE.get_or_init(Self::read).clone()
    }

    fn read() -> Self {
        let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
        let field = |name: &str| {
            cpuinfo.lines().find_map(|line| {
                let (key, value) = line.split_once(':')?;
                (key.trim() == name).then(|| value.trim().to_owned())
            })
        };
        let flags = field("flags").unwrap_or_default();
        let present: Vec<&str> = flags.split_whitespace().collect();
        let env = |name: &str| std::env::var(name).ok().filter(|v| !v.is_empty());
        Self {
            cpu_model: field("model name").unwrap_or_else(|| std::env::consts::ARCH.to_owned()),
            cpu_flags: (DECIDING_FLAGS.iter())
                .filter(|f| present.contains(f))
                .map(|f| f.to_string())
                .collect(),
            onednn_max_cpu_isa: env("ONEDNN_MAX_CPU_ISA"),
            aten_cpu_capability: env("ATEN_CPU_CAPABILITY"),
            graspmap: env!("CARGO_PKG_VERSION").to_owned(),
        }
    }

    /// The caps in words, for messages.
    pub(crate) fn caps(&self) -> String {
        let cap = |name: &str, value: &Option<String>| match value {
            Some(v) => format!("{name}={v}"),
            None => format!("no {name}"),
        };
        format!(
            "{}, {}",
            cap("ONEDNN_MAX_CPU_ISA", &self.onednn_max_cpu_isa),
            cap("ATEN_CPU_CAPABILITY", &self.aten_cpu_capability)
        )
    }
}

/// Median milliseconds of one precision's two workloads.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Timing {
    /// One training step: batch 8 of RGB crops at the default crop size, forward, backward
    /// and Adam.
    pub(crate) train_step_ms: f64,
    /// One 8-rotation inference: 8 RGB 128 × 128 images, forward and sigmoid.
    pub(crate) infer_ms: f64,
}

impl Timing {
    fn of(&self, workload: Workload) -> f64 {
        match workload {
            Workload::Train => self.train_step_ms,
            Workload::Infer => self.infer_ms,
        }
    }
}

/// One machine's measurement and the choice it makes.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Measured {
    /// Where it holds.
    pub(crate) machine: MachineKey,
    /// libtorch's threads while timing.
    pub(crate) threads: i32,
    /// fp32's figures.
    pub(crate) fp32: Timing,
    /// bf16's figures.
    pub(crate) bf16: Timing,
    /// The precision `--precision auto` trains in.
    pub(crate) train: Precision,
    /// The precision `--precision auto` predicts in.
    pub(crate) infer: Precision,
    /// fp32's training step with its batches in channels_last layout.
    pub(crate) fp32_train_channels_last_ms: f64,
    /// Whether fp32 training runs its batches in channels_last (oneDNN then keeps the whole
    /// step in that layout): faster with AVX-512 on one machine, slower on an AVX2-only one.
    pub(crate) fp32_train_channels_last: bool,
}

impl Measured {
    /// The choice for `workload`.
    pub(crate) fn choice(&self, workload: Workload) -> Precision {
        match workload {
            Workload::Train => self.train,
            Workload::Infer => self.infer,
        }
    }
}

/// The faster of the two for `workload`, bf16 only when it is faster by [`MARGIN`].
pub(crate) fn faster(fp32: &Timing, bf16: &Timing, workload: Workload) -> Precision {
    match bf16.of(workload) < MARGIN * fp32.of(workload) {
        true => Precision::Bf16,
        false => Precision::Fp32,
    }
}

#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
struct CacheFile {
    schema: String,
    machines: Vec<Measured>,
}

/// Where the measurements are kept: `$XDG_CACHE_HOME/graspmap/precision.json`, else
/// `~/.cache/graspmap/precision.json`.
pub(crate) fn cache_path() -> Option<PathBuf> {
    let var = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty());
    let base = var("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| var("HOME").map(|home| PathBuf::from(home).join(".cache")))?;
    Some(base.join("graspmap").join("precision.json"))
}

/// The cache's entries; an unreadable or foreign file reads as empty (it is measured again
/// and rewritten).
fn read_cache(path: &Path) -> CacheFile {
    std::fs::read(path)
        .ok()
        .and_then(|bytes| serde_json::from_slice::<CacheFile>(&bytes).ok())
        .filter(|cache| cache.schema == SCHEMA)
        .unwrap_or_default()
}

/// Replaces `measured.machine`'s entry of the cache, atomically.
fn write_cache(path: &Path, measured: &Measured) -> anyhow::Result<()> {
    let mut cache = read_cache(path);
    cache.schema = SCHEMA.to_owned();
    cache.machines.retain(|m| m.machine != measured.machine);
    cache.machines.push(measured.clone());
    let dir = path.parent().expect("the cache path has a folder");
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let tmp = dir.join(format!(".precision.json.tmp-{}", std::process::id()));
    let mut bytes = serde_json::to_vec_pretty(&cache).expect("the cache serialises");
    bytes.push(b'\n');
    std::fs::write(&tmp, &bytes).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))
}

/// The measurement of this machine that `path` keeps, if any.
fn cached_in(path: &Path) -> Option<Measured> {
    let machine = MachineKey::here();
    read_cache(path)
        .machines
        .into_iter()
        .find(|m| m.machine == machine)
}

/// `--precision auto` for `workload`: the cached choice, or one measured now and cached.
pub(crate) fn auto(workload: Workload) -> Precision {
    auto_in(cache_path(), workload)
}

/// Whether fp32 training should run in channels_last here, by the same measurement.
pub(crate) fn fp32_trains_channels_last() -> bool {
    measured_in(cache_path()).fp32_train_channels_last
}

fn auto_in(path: Option<PathBuf>, workload: Workload) -> Precision {
    measured_in(path).choice(workload)
}

/// The measurement `path` keeps for this machine, or one taken now and kept there. One
/// process measures at a time; another waits for it and reads its result.
fn measured_in(path: Option<PathBuf>) -> Measured {
    let Some(path) = path else {
        return measure_and_announce(None);
    };
    if let Some(measured) = cached_in(&path) {
        return measured;
    }
    let lock = lock_cache(&path);
    if let Some(measured) = lock.is_some().then(|| cached_in(&path)).flatten() {
        return measured;
    }
    let measured = measure_and_announce(Some(&path));
    if let Err(e) = write_cache(&path, &measured) {
        eprintln!("warning: --precision auto could not keep its measurement ({e:#}); the next run measures again");
    }
    measured
}

/// Takes the cache's lock, waiting for another measuring process; `None` where it cannot.
fn lock_cache(path: &Path) -> Option<std::fs::File> {
    let dir = path.parent()?;
    std::fs::create_dir_all(dir).ok()?;
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(dir.join(".precision.lock"))
        .ok()?;
    file.lock().ok()?;
    Some(file)
}

fn measure_and_announce(path: Option<&Path>) -> Measured {
    let announce = ANNOUNCE.load(Ordering::Relaxed);
    let machine = MachineKey::here();
    if announce {
        let kept = match path {
            Some(p) => format!("kept in {}", p.display()),
            None => "not kept: no HOME or XDG_CACHE_HOME".to_owned(),
        };
        eprintln!(
            "--precision auto: timing fp32 and bf16 once on this CPU ({}, {}); {kept}",
            machine.cpu_model,
            machine.caps()
        );
    }
    let measured = measure(machine);
    if announce {
        eprintln!("{}", describe(&measured));
    }
    measured
}

/// One line on the choice and its figures.
fn describe(m: &Measured) -> String {
    let line = |workload: Workload, what: &str| {
        let (chosen, other) = match m.choice(workload) {
            Precision::Fp32 => (&m.fp32, (&m.bf16, Precision::Bf16)),
            Precision::Bf16 => (&m.bf16, (&m.fp32, Precision::Fp32)),
        };
        format!(
            "{} for {what} ({:.0} ms against {:.0} ms in {})",
            m.choice(workload).name(),
            chosen.of(workload),
            other.0.of(workload),
            other.1.name()
        )
    };
    format!(
        "--precision auto: {}, {}; fp32 trains in {} layout",
        line(Workload::Train, "a training step"),
        line(Workload::Infer, "8 rotations"),
        match m.fp32_train_channels_last {
            true => "channels_last",
            false => "the default",
        }
    )
}

/// Times both precisions on both workloads with libtorch's current threads, fp32 first; a
/// precision hopelessly slower after its warm-up is timed once.
pub(crate) fn measure(machine: MachineKey) -> Measured {
    let vs = nn::VarStore::new(Device::Cpu);
    let net = tch::no_grad(|| {
        let net = MiniUNet::new(&vs.root());
        // Fixed weights and inputs, so that the figures do not depend on libtorch's RNG state
        // (the layers' initialisation draws from it; every command that uses it seeds it).
        let sorted: std::collections::BTreeMap<String, Tensor> =
            vs.variables().into_iter().collect();
        for (k, mut var) in sorted.into_values().enumerate() {
            let n = var.numel() as i64;
            let values = Tensor::arange(n, (Kind::Float, Device::Cpu))
                .g_mul_scalar(0.37 + k as f64)
                .sin()
                .g_mul_scalar(0.05)
                .view(var.size().as_slice());
            var.copy_(&values);
        }
        net
    });
    let mut adam = Adam::new(&vs, 1e-4);
    let crop = i64::from(DEFAULT_CROP);
    let pattern = |shape: &[i64]| {
        let n: i64 = shape.iter().product();
        (Tensor::arange(n, (Kind::Float, Device::Cpu)).g_mul_scalar(0.013))
            .sin()
            .abs()
            .view(shape)
    };
    let crops = pattern(&[8, 3, crop, crop]);
    let target = Tensor::zeros([8, 1, crop, crop], (Kind::Float, Device::Cpu));
    let _ = target
        .narrow(2, crop / 2, 1)
        .narrow(3, crop / 2, 1)
        .fill_(1.0);
    let side = i64::from(IMAGE_SIZE);
    let rotations = pattern(&[BINS as i64, 3, side, side]);

    let crops_channels_last = super::unet::channels_last(&crops);
    let mut train = |precision: Precision, input: &Tensor| {
        let l = loss(&net, input, &target, precision);
        l.backward();
        adam.step();
    };
    let fp32_train = timed(|| train(Precision::Fp32, &crops), None);
    let fp32_train_channels_last_ms = timed(|| train(Precision::Fp32, &crops_channels_last), None);
    let bf16_train = timed(|| train(Precision::Bf16, &crops), Some(fp32_train));
    let infer = |precision: Precision| {
        tch::no_grad(|| {
            let batch = super::inference::network_layout(&rotations, precision);
            let _ = net.forward_with(&batch, precision).sigmoid();
        })
    };
    let fp32_infer = timed(|| infer(Precision::Fp32), None);
    let bf16_infer = timed(|| infer(Precision::Bf16), Some(fp32_infer));
    let fp32 = Timing {
        train_step_ms: fp32_train,
        infer_ms: fp32_infer,
    };
    let bf16 = Timing {
        train_step_ms: bf16_train,
        infer_ms: bf16_infer,
    };
    Measured {
        machine,
        threads: tch::get_num_threads(),
        train: faster(&fp32, &bf16, Workload::Train),
        infer: faster(&fp32, &bf16, Workload::Infer),
        fp32,
        bf16,
        fp32_train_channels_last_ms,
        fp32_train_channels_last: fp32_train_channels_last_ms < MARGIN * fp32_train,
    }
}

/// Median milliseconds of `step` after one warm-up; once only when the warm-up alone took
/// [`HOPELESS`] times `rival`'s median.
fn timed(mut step: impl FnMut(), rival: Option<f64>) -> f64 {
    let clock = |step: &mut dyn FnMut()| {
        let start = Instant::now();
        step();
        start.elapsed().as_secs_f64() * 1e3
    };
    let warmup = clock(&mut step);
    let reps = match rival {
        Some(rival) if warmup > HOPELESS * rival => 1,
        _ => REPS,
    };
    let mut times: Vec<f64> = (0..reps).map(|_| clock(&mut step)).collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// `graspmap bench precision`: a fresh measurement, kept as this machine's entry; returns it
/// with where it was kept.
pub(crate) fn remeasure() -> anyhow::Result<(Measured, Option<PathBuf>)> {
    let measured = measure(MachineKey::here());
    let path = cache_path();
    if let Some(path) = &path {
        let _lock = lock_cache(path);
        write_cache(path, &measured)?;
    }
    Ok((measured, path))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn timing(train: f64, infer: f64) -> Timing {
        Timing {
            train_step_ms: train,
            infer_ms: infer,
        }
    }

    #[test]
    fn the_faster_precision_wins_and_bf16_needs_a_margin() {
        let fp32 = timing(100.0, 300.0);
        assert_eq!(
            faster(&fp32, &timing(40.0, 400.0), Workload::Train),
            Precision::Bf16
        );
        assert_eq!(
            faster(&fp32, &timing(40.0, 400.0), Workload::Infer),
            Precision::Fp32
        );
        // 2 % faster is within the timings' noise: fp32 stays.
        assert_eq!(
            faster(&fp32, &timing(98.0, 294.0), Workload::Train),
            Precision::Fp32
        );
    }

    #[test]
    fn the_cache_keeps_one_entry_per_machine_and_ignores_a_foreign_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("graspmap").join("precision.json");
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, b"{not json").unwrap();
        assert!(read_cache(&path).machines.is_empty());
        let here = MachineKey::here();
        let capped = MachineKey {
            onednn_max_cpu_isa: Some("AVX2".to_owned()),
            ..here.clone()
        };
        let entry = |machine: MachineKey, train: Precision| Measured {
            machine,
            threads: 2,
            fp32: timing(1.0, 1.0),
            bf16: timing(1.0, 1.0),
            train,
            infer: Precision::Fp32,
            fp32_train_channels_last_ms: 1.0,
            fp32_train_channels_last: false,
        };
        write_cache(&path, &entry(here.clone(), Precision::Fp32)).unwrap();
        write_cache(&path, &entry(capped.clone(), Precision::Fp32)).unwrap();
        write_cache(&path, &entry(here.clone(), Precision::Bf16)).unwrap();
        let cache = read_cache(&path);
        assert_eq!(cache.machines.len(), 2);
        let mine = cache.machines.iter().find(|m| m.machine == here).unwrap();
        assert_eq!(
            mine.train,
            Precision::Bf16,
            "the newer measurement replaced it"
        );
        assert!(cache.machines.iter().any(|m| m.machine == capped));
        // What auto answers is the kept entry's choice, even where its figures would choose
        // otherwise, and nothing is measured again (a measurement rewrites the file).
        let kept = std::fs::read(&path).unwrap();
        assert_eq!(
            auto_in(Some(path.clone()), Workload::Train),
            Precision::Bf16
        );
        assert_eq!(
            auto_in(Some(path.clone()), Workload::Infer),
            Precision::Fp32
        );
        assert_eq!(std::fs::read(&path).unwrap(), kept);
    }
}
