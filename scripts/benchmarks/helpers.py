"""The small jobs scripts/benchmarks.sh hands to Python: timing a command, the runs that start
processes side by side, and the adapters that turn a tool's text output into the JSON the
renderer reads (it reads nothing else).

Usage: python3 scripts/benchmarks/helpers.py COMMAND ARGS...
  timed FILE CMD...            run CMD; FILE gets its wall and CPU seconds and exit status
  shards DIR BIN SWEEP...      the sweep as two 1-thread shard processes at once, into DIR
  slurm DIR CONF BIN SWEEP...  the sweep as 2 shards on the one-node Slurm, into DIR
  cargo-test LOG FILE          cargo test's output: build time and tests passed per target
  epoch-seconds CSV FILE       a training run's losses.csv: seconds per epoch
  file-size PATH FILE          the size of PATH, in ffprobe's shape (no ffprobe here)
  skip FILE REASON...          a run that does not apply here, and why
  eval-name BASE ARGS...       the file name of an evaluation: BASE, then ARGS' flags spelt out
  settings OUT QUICK KEY...     OUT/machine.txt, and OUT/settings.json: the machine, commit, mode
                               and each KEY's value from the environment
"""

import csv
import json
import os
import re
import resource
import subprocess
import sys
import time

import reports


def write(path, data):
    with open(path, "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")


def timed(path, *cmd):
    start = time.monotonic()
    status = subprocess.call(cmd)
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    write(path, {"cmd": list(cmd), "wall_s": time.monotonic() - start, "user_s": usage.ru_utime,
                 "sys_s": usage.ru_stime, "status": status})
    return status


def shards(d, binary, *sweep):
    logs = [open(f"{d}/shard-{i}-of-2.log", "w") for i in (1, 2)]
    start = time.monotonic()
    procs = [subprocess.Popen([binary, "--data", f"{d}/two-processes", "--quiet", "--threads", "1", "--json",
                               f"{d}/shard-{i}-of-2.json", *sweep, "--shard", f"{i}/2"],
                              stdout=log, stderr=log) for i, log in zip((1, 2), logs)]
    ends = []
    for i, p in enumerate(procs, 1):
        if p.wait() != 0:
            sys.exit(f"threads: shard {i}/2 failed with status {p.returncode} (see {d}/shard-{i}-of-2.log)")
        ends.append(time.monotonic() - start)
    write(f"{d}/two-processes.time.json", {"wall_s": max(ends), "shard_walls": ends})
    return 0


def slurm(d, conf, binary, *sweep):
    env = dict(os.environ, SLURM_CONF=conf, RUN_DIR=f"{d}/run", DATA=f"{d}/data", SHARDS="2",
               CPUS_PER_TASK="1", MEM_PER_TASK="2G", GRASPMAP=binary)
    start = time.monotonic()
    subprocess.run(["scripts/slurm/submit.sh", *sweep], env=env, check=True, stdout=subprocess.DEVNULL)
    with open(f"{d}/run/jobs.env") as f:
        jobs = dict(word.split("=", 1) for word in f.read().split())
    while True:
        out = subprocess.run(["scontrol", "show", "job", jobs["MERGE_JOB"], "--oneliner"], env=env,
                             capture_output=True, text=True).stdout
        state = next((f.split("=", 1)[1] for f in out.split() if f.startswith("JobState=")), "UNKNOWN")
        if state not in ("PENDING", "RUNNING", "CONFIGURING", "COMPLETING"):
            break
        time.sleep(0.2)
    wall = time.monotonic() - start
    walls = []
    for i in (1, 2):
        with open(f"{d}/run/shard_{i}.json") as f:
            walls.append(json.load(f)["results"]["timing"]["total_wall"])
    write(f"{d}/slurm.time.json", {"state": state, "wall_s": wall, "shard_walls": walls})
    return 0


def cargo_test_summary(text):
    """Tests passed per kind of target (the lib's unit tests, tests/suite, the rest), the suite's
    own time, and cargo's build time as it prints it ("2m 49s")."""
    built = re.search(r"Finished `release` profile .*? in (.+)", text)
    unit = suite = other = 0
    suite_s, target = None, ""
    for line in text.splitlines():
        m = re.match(r"\s*(Running|Doc-tests) (\S+)", line)
        if m:
            target = m.group(2)
        m = re.match(r"test result: \w+\. (\d+) passed.*finished in ([\d.]+)s", line)
        if m:
            n = int(m.group(1))
            if "tests/suite" in target:
                suite, suite_s = suite + n, float(m.group(2))
            elif target.startswith("unittests"):
                unit += n
            else:
                other += n
    if not built and not (unit or suite or other):
        raise ValueError("no cargo test output in it")
    return {"build": built.group(1).strip() if built else None, "unit": unit, "suite": suite, "other": other,
            "suite_s": suite_s}


def cargo_test(log, path):
    with open(log) as f:
        write(path, cargo_test_summary(f.read()))
    return 0


def epoch_seconds(csv_path, path):
    with open(csv_path, newline="") as f:
        write(path, {"seconds": [float(row["seconds"]) for row in csv.DictReader(f)]})
    return 0


def file_size(target, path):
    write(path, {"format": {"size": str(os.path.getsize(target))}, "streams": [], "note": "no ffprobe"})
    return 0


def skip(path, *reason):
    write(path, {"reason": " ".join(reason)})
    return 0


def machine():
    """lscpu's model name and flags, the flags that matter here named, and whether bf16 is native."""
    try:
        text = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
    except OSError:
        text = ""
    field = lambda name: next((line.split(":", 1)[1].strip() for line in text.splitlines()
                               if line.startswith(name + ":")), "")
    model, flags = field("Model name"), set(field("Flags").split())
    named = [n for f, n in (("avx2", "AVX2"), ("avx512f", "AVX-512"), ("avx512_bf16", "AVX-512 BF16"),
                            ("amx_bf16", "AMX BF16")) if f in flags]
    named += [] if "avx512f" in flags else ["no AVX-512"]
    return model, flags, ", ".join(named), bool(flags & {"avx512_bf16", "amx_bf16"})


def settings(out, quick, *keys):
    """OUT/machine.txt and OUT/settings.json (the machine with its ISA cap); prints 1 when the CPU
    has native bf16, else 0."""
    model, flags, named, bf16 = machine()
    git = lambda *args: subprocess.run(["git", *args], capture_output=True, text=True).stdout.strip()
    changed = subprocess.run(["git", "diff", "--quiet", "HEAD", "--", "src", "benches", "build.rs", "Cargo.toml",
                              "Cargo.lock"]).returncode != 0
    dirty = " (with uncommitted changes to the code)" if changed else ""
    # oneDNN's and ATen's ISA caps: each table's machine column says which one it ran under.
    caps = [f"{k}={os.environ[k]}" for k in ("ONEDNN_MAX_CPU_ISA", "ATEN_CPU_CAPABILITY") if os.environ.get(k)]
    cap = f", under {' '.join(caps)}" if caps else ", no ISA cap"
    with open(f"{out}/machine.txt", "w") as f:
        f.write(f"model name: {model}\ncores: {len(os.sched_getaffinity(0))}\nrelevant flags: {named}\n"
                f"flags: {' '.join(sorted(flags))}\nisa cap: {cap[2:]}\ncommit: {git('rev-parse', 'HEAD')}{dirty}\n"
                f"date: {time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime())}\n"
                f"mode: {'quick' if quick == '1' else 'full'}\n")
    write(f"{out}/settings.json", {
        "machine": f"{model or 'unknown CPU'} ({named}), {len(os.sched_getaffinity(0))} cores{cap}",
        "commit": git("rev-parse", "--short", "HEAD") + dirty, "quick": quick == "1",
        "settings": {k: os.environ.get(k, "") for k in keys}})
    print(int(bf16))
    return 0


def eval_name(base, *words):
    """Groups a command line's words into flags (a flag, then its value when one follows) for
    reports.eval_name, the one place that spells an evaluation's file name."""
    flags = []
    for word in words:
        if word.startswith("--") or not flags:
            flags.append(word)
        else:
            flags[-1] += " " + word
    print(reports.eval_name(base, *flags))
    return 0


COMMANDS = {"timed": timed, "eval-name": eval_name, "shards": shards, "slurm": slurm, "cargo-test": cargo_test,
            "epoch-seconds": epoch_seconds, "file-size": file_size, "skip": skip, "settings": settings}

if __name__ == "__main__":
    if len(sys.argv) < 2 or sys.argv[1] not in COMMANDS:
        sys.exit(__doc__)
    sys.exit(COMMANDS[sys.argv[1]](*sys.argv[2:]))
