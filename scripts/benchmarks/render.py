"""Renders one table of BENCHMARKS.md as Markdown from the JSON that scripts/benchmarks.sh left in OUT.

Usage: python3 scripts/benchmarks/render.py TABLE OUT

Reads OUT/settings.json (machine, commit, the run's counts and seeds) and the table's reports,
nothing else. A report the table needs that is missing, unreadable or interrupted stops it with
one line naming the file, and exit status 1; a dash stands only for a cell that does not apply
(a run recorded as skipped, a combination the table does not measure).
"""

import statistics
import sys

from reports import (DASH, Unfit, after_carry, bare, count, eval_name, load, load_eval, moved, paired, pct,
                     per_seed, rate, scene, secs, seeds, skipped)


class Page:
    """One table's output, with the run's settings and the reports under OUT."""

    def __init__(self, table, out):
        self.table, self.out, self.lines = table, out, []
        info = load(f"{out}/settings.json")
        self.machine, self.commit, self.quick = info["machine"], info["commit"], info["quick"]
        self.s = info["settings"]

    def path(self, rel):
        return f"{self.out}/{rel}"

    def load(self, rel):
        return load(self.path(rel))

    def ev(self, base, *flags, under="eval"):
        return load_eval(self.path(f"{under}/{eval_name(base, *flags)}.json"))

    def wall(self, rel):
        return self.load(rel)["wall_s"]

    def skipped(self, rel):
        return skipped(self.path(rel))

    def say(self, text=""):
        self.lines.append(text)

    def head(self, title, command):
        mode = " (`--quick`: a smoke run, not comparable)" if self.quick else ""
        self.say(f"### {title}")
        self.say()
        self.say(f"{self.machine}; commit {self.commit}{mode}. {command}")
        self.say()

    def md(self, header, rows):
        self.say("| " + " | ".join(header) + " |")
        self.say("|" + "---|" * len(header))
        for row in rows:
            self.say("| " + " | ".join(str(c) for c in row) + " |")
        self.say()


# ---------------------------------------------------------------------------------------------
# The tables, in scripts/benchmarks.sh's order; each reads the files its run function writes.


def t_objects(p):
    p.head("Bundled objects against the reference's meshes",
           f"`graspmap eval --policy oracle --task T --seeds {p.s['OBJECT_SEEDS']} [--objects-dir assets/ycb-meshes]`.")
    rows, widest = [], 0
    for task in ("train", "test"):
        a, b = p.ev(f"bundled-{task}", under="objects"), p.ev(f"ycb-meshes-{task}", under="objects")
        pb = {o["object"]: o for o in b["per_object"]}
        for o in a["per_object"]:
            other = pb[o["object"]]
            widest = max(widest, abs(o["successes"] - other["successes"]))
            rows.append([task, o["object"], f"{o['successes']}/{o['attempts']}",
                         f"{other['successes']}/{other['attempts']}"])
        rows.append([task, "**all**", rate(a), rate(b)])
        rows.append([task, "sim per attempt", secs(a["timing"]["mean"]["sim"]), secs(b["timing"]["mean"]["sim"])])
    p.md(["task", "object", "bundled primitives", "`--objects-dir assets/ycb-meshes`"], rows)
    p.say(f"Largest difference on one object: {widest} attempts.")
    p.say()


def t_pipeline(p):
    p.head("Pipeline against the Python reference",
           "`./demo.sh`'s steps: label, train, eval train, test, empty_bin --n-past-action 8 --record, report.")
    t = lambda step: secs(p.wall(f"pipeline/times/{step}.json"))
    evals = ", ".join(t(f"eval_{task}") for task in ("train", "test", "empty_bin"))
    p.md(["machine", "commit", "labels", f"training, {p.s['EPOCHS']} epochs",
          "evals: train, test, empty_bin with video", "pipeline"],
         [[p.machine, p.commit, t("label"), t("train"), evals, f"**{t('total')}** (report {t('report')})"],
          ["Python reference", DASH, DASH, DASH, DASH, "851 s on an Intel Xeon without AMX (issue 52's measurement)"]])


def t_threads(p):
    p.head("Two threads in one process against two processes",
           f"`graspmap eval --task empty_bin --seeds {p.s['EMPTY_SEEDS']} --n-past-action 8` with `--threads 2`, "
           "against the same sweep as `--shard 1/2` and `--shard 2/2` with `--threads 1`, both started at once.")
    one, two = p.load("threads/one-process.time.json"), p.load("threads/two-processes.time.json")
    whole = p.ev("one-process", under="threads")
    shards = [p.ev(f"shard-{i}-of-2", under="threads") for i in (1, 2)]
    network = lambda r: secs(r["timing"]["mean"]["network"])
    attempts = sum(s["timing"]["attempts"] for s in shards)
    p.md(["run", "wall", "attempts", "wall per attempt", "network per attempt"], [
        ["one process, `--threads 2`", secs(one["wall_s"]), whole["timing"]["attempts"],
         secs(one["wall_s"] / whole["timing"]["attempts"]), network(whole)],
        ["two processes, `--threads 1` each", secs(two["wall_s"]), attempts, secs(two["wall_s"] / attempts),
         " / ".join(network(s) for s in shards)],
    ])
    p.say(f"Ratio, one process over two: **{one['wall_s'] / two['wall_s']:.2f}**.")
    p.say()


def training_row(p, precision):
    """One precision's row: wall, seconds per epoch after the first, images/s, best loss."""
    reason = p.skipped(f"training/{precision}.skipped.json")
    if reason is not None:
        return [p.machine, p.commit, precision, f"not run: {reason}", DASH, DASH, DASH]
    r = p.load(f"training/{precision}/train.json")
    seconds = p.load(f"training/{precision}/epoch-seconds.json")["seconds"]
    # The first epoch pays for warm-up; a one-epoch run (--quick) has only that one.
    later = seconds[1:] or seconds
    images = r["train_samples"] + r["val_samples"]
    return [p.machine, p.commit, precision, f"{r['wall_seconds']:.1f} s", f"{min(later):.2f}–{max(later):.2f}",
            f"≈ {images / statistics.median(later):.1f}", f"{r['best_val_loss']:.5f} ({r['best_epoch']})"]


def t_training(p):
    p.head("Training", f"`graspmap --data D train --epochs {p.s['EPOCHS']} --precision P` on a copy of the labels.")
    p.md(["machine", "commit", "precision", f"{p.s['EPOCHS']} epochs, wall", "s per epoch after the first",
          "images/s", "best validation loss (epoch)"], [training_row(p, x) for x in ("fp32", "bf16")])


def t_crop(p):
    p.head("Crop training", f"`graspmap train --epochs {p.s['EPOCHS']} --crop 0|64` on a copy of the labels, then `eval`.")
    rows = []
    for crop in ("0", "64"):
        r = p.load(f"crop/{crop}/train.json")
        g = lambda spec: p.ev(spec, under=f"crop/{crop}/eval")
        rows.append([f"`--crop {crop}`", f"{r['wall_seconds']:.1f} s", f"{r['best_val_loss']:.5f}",
                     count(g("train-seed0")), rate(g("test")), moved(g("empty_bin-np8"))])
    p.md(["training", "wall", "best validation loss", "train, seed 0", f"test, {seeds(p.s['TEST_SEEDS'])}",
          f"empty_bin, {seeds(p.s['EMPTY_SEEDS'])}, np8"], rows)


ARGMAX = ("--verify-top 0", "--collision-check off")


def trials_rows(p, i, rounds):
    """Round i's rows (0: the labels-only model): with the vetoes, as the argmax, and each option."""
    name = "labels only" if i == 0 else f"round {i}"
    tag = "start" if i == 0 else f"round_{i:02d}"
    g = lambda spec, *flags: p.ev(f"{tag}-{spec}", *flags, under="trials/eval")
    info = DASH if i == 0 else f"{rounds[i - 1]['trials']} trials, {pct(rounds[i - 1]['collection_success_rate'])} %"
    rows = []
    for flags, label in (((), name), (ARGMAX, name + " argmax")):
        rows.append([label, info, count(g("train-seed0", *flags)), rate(g("test", *flags)),
                     moved(g("empty_bin-np8", *flags)), rate(g("empty_bin-np8", *flags)),
                     rate(g("test-heldout", *flags)), moved(g("empty_bin-heldout-np8", *flags))])
    for flag in ("--give-up-after 6", "--push-unverified false"):
        rows.append([f"{name}, `{flag}`", DASH, DASH, DASH, moved(g("empty_bin-np8", flag)),
                     rate(g("empty_bin-np8", flag)), DASH, moved(g("empty_bin-heldout-np8", flag))])
    if i == int(p.s["ROUNDS"]):
        before = ("--push-unverified false", "--verify-margin 6")
        rows.append([f"round {i}, `{' '.join(before)}`", DASH, DASH, rate(g("test", *before)),
                     moved(g("empty_bin-np8", *before)), rate(g("empty_bin-np8", *before)),
                     rate(g("test-heldout", *before)), moved(g("empty_bin-heldout-np8", *before))])
    return rows


def trials_spread(p):
    """Test rates of consecutive sets of three seeds: how far apart they fall on their own."""
    last = f"round_{int(p.s['ROUNDS']):02d}"
    spread = []
    for label, reports in (
            ("labels only", [p.ev(f"start-{s}", under="trials/eval") for s in ("test", "test-heldout", "test-spread")]),
            (f"round {p.s['ROUNDS']}", [p.ev(f"{last}-{s}", under="trials/eval") for s in ("test", "test-heldout")]
             + [p.ev("last-test-spread", under="trials/eval")]),
            ("the oracle", [p.ev(f"oracle-{s}") for s in ("test", "test-heldout", "test-spread")])):
        counts = [c for r in reports for c in per_seed(r)]
        per_seed_attempts = reports[0]["success"]["trials"] / len(reports[0]["seeds"])
        rates = [100 * sum(counts[i:i + 3]) / (3 * per_seed_attempts) for i in range(0, len(counts) - 2, 3)]
        overall = 100 * sum(counts) / (len(counts) * per_seed_attempts)
        spread.append(f"{label} {overall:.1f} % over all, sets " + ", ".join(f"{x:.1f}" for x in rates)
                      + f" (sd {statistics.stdev(rates):.1f})")
    p.say(f"Test on {seeds(p.s['TEST_SEEDS'])}, then {seeds(p.s['HELD_TEST'])}, then {seeds(p.s['SPREAD_SEEDS'])}, "
          "as consecutive sets of three seeds, in %: " + "; ".join(spread) + ".")
    p.say()


def t_trials(p):
    p.head("Learning from trials", f"`graspmap improve --rounds {p.s['ROUNDS']} --scenes {p.s['SCENES']} --epochs "
           f"{p.s['ROUND_EPOCHS']}` from the labelled model, then `eval --checkpoint` each model, with the default "
           "vetoes and as the plain argmax (`--verify-top 0 --collision-check off`).")
    rounds = p.load("trials/improve.json")
    p.say(f"The loop took {secs(p.wall('trials/improve.time.json'))}.")
    p.say()
    rows = [row for i in range(int(p.s["ROUNDS"]) + 1) for row in trials_rows(p, i, rounds)]
    o = lambda spec, *flags: p.ev(f"oracle-{spec}", *flags)
    rows.append(["oracle (np8 in empty_bin)", DASH, count(o("train-seed0")), rate(o("test")), moved(o("empty_bin-np8")),
                 rate(o("empty_bin-np8")), rate(o("test-heldout")), moved(o("empty_bin-heldout-np8"))])
    g6 = "--give-up-after 6"
    rows.append(["oracle, np8, `--give-up-after 6`", DASH, DASH, DASH, moved(o("empty_bin-np8", g6)),
                 rate(o("empty_bin-np8", g6)), DASH, moved(o("empty_bin-heldout-np8", g6))])
    p.md(["model", "collected", "train", f"test, {seeds(p.s['TEST_SEEDS'])}",
          f"empty_bin, {seeds(p.s['EMPTY_SEEDS'])}, np8", "its picks", f"held out: test, {seeds(p.s['HELD_TEST'])}",
          f"held out: empty_bin, {seeds(p.s['HELD_EMPTY'])}, np8"], rows)
    if p.s["SPREAD_SEEDS"]:
        trials_spread(p)


def t_slurm(p):
    p.head("Sweeps under Slurm", f"`eval --task empty_bin --policy oracle --seeds {p.s['SLURM_SEEDS']} --n-past-action 8` "
           "in one process (`--threads 2`), and as `SHARDS=2 CPUS_PER_TASK=1 scripts/slurm/submit.sh` on the one-node "
           "Slurm, from submission to the merge job's end.")
    single, slurm = p.load("slurm/one-process.time.json"), p.load("slurm/slurm.time.json")
    overhead = slurm["wall_s"] - max(slurm["shard_walls"])
    p.md(["one process", "2 shards under Slurm", "ratio", "each shard's own eval time", "overhead (rest of the wall)",
          "merge job"],
         [[secs(single["wall_s"]), secs(slurm["wall_s"]), f"{slurm['wall_s'] / single['wall_s']:.2f}",
           ", ".join(secs(w) for w in slurm["shard_walls"]), secs(overhead), slurm["state"]]])


def t_pytorch(p):
    p.head("Rust against PyTorch", "`graspmap bench train --precision P` (Rust and the Python peer alternating).")
    rows, ratios = [], []
    for precision in ("bf16", "fp32"):
        reason = p.skipped(f"bench/{precision}.skipped.json")
        if reason is not None:
            rows.append([precision, DASH, f"not run: {reason}", DASH, DASH])
            continue
        r = p.load(f"bench/{precision}.json")
        for side in ("rust", "python"):
            s = r.get(side)
            if s:
                rows.append([precision, "Rust" if side == "rust" else "Python", f"{s['train_step_ms']:.1f}",
                             f"{s['train_images_per_s']:.2f}", f"{s['infer_8_rotations_ms']:.1f}"])
        if r.get("train_ratio") is not None:
            ratios.append(f"{precision}: training {r['train_ratio']:.2f}×, inference {r['infer_ratio']:.2f}×")
    p.md(["precision", "side", "train ms/step", "train images/s", "8-rotation inference ms"], rows)
    p.say("Rust/Python: " + ("; ".join(ratios) if ratios else "no peer run") + ".")
    p.say()


def t_latency(p):
    p.head("Attempt latency", "`results.timing` of the model's evaluations.")
    rows = []
    for spec, what in (("empty_bin-np8", f"empty_bin, model, np8, {seeds(p.s['EMPTY_SEEDS'])}"),
                       ("train-seed0", "train, model"), ("test", "test, model")):
        t = p.ev(f"model-{spec}")["timing"]
        m = t["mean"]
        rows.append([p.machine, p.commit, f"{what}, mean of {t['attempts']}", f"{m['wall']:.2f} s",
                     f"{m['sim']:.2f} s", f"{m['render']:.3f} s", f"{m['network']:.2f} s",
                     str(t.get("workers", 1)), f"{t['total_wall'] / max(t['attempts'], 1):.2f} s"])
    p.md(["machine", "commit", "attempt", "wall", "sim", "render", "network", "at once", "run's wall / attempts"], rows)


def criterion(p, bench):
    """Criterion's estimates of one workcell benchmark, in ms: (median, mean)."""
    e = p.load(f"workcell/criterion/workcell/{bench}/new/estimates.json")
    return e["median"]["point_estimate"] / 1e6, e["mean"]["point_estimate"] / 1e6


def t_workcell(p):
    p.head("Workcell speed", "`cargo bench --bench workcell` (criterion), and one whole `graspmap grasp` process.")
    facts = p.load("workcell/criterion/workcell/facts.json")
    frame, _ = criterion(p, "top_down_frame")
    median, mean = criterion(p, "pick_attempt")
    sim = facts["sim_s_per_attempt"]
    p.md(["what", "figure"], [
        [f"one 128 × 128 top-down frame, {facts['drawables']} drawables", f"{frame:.2f} ms, median"],
        [f"one single-object pick attempt, {facts['objects']} objects × seeds {facts['seeds']} in turn",
         f"{median:.0f} ms median, {mean:.0f} ms mean"],
        ["simulated time per attempt", f"{sim:.1f} s (≈ {sim / (mean / 1e3):.0f}× faster than real time)"],
        ["`graspmap grasp --object YcbPowerDrill --seed 2 --oracle`, whole process",
         f"{secs(p.wall('workcell/grasp.time.json'))} wall"],
        ["the Python reference, one single-object pick attempt", "about 1.6 s (quoted in BENCHMARKS.md)"],
    ])


def t_quality(p):
    p.head("Quality: model, random and oracle", "`graspmap eval --task T --seeds S [--n-past-action 8] [--policy P]`.")
    m, r, o = (lambda s: p.ev("model-" + s)), (lambda s: p.ev("random-" + s)), (lambda s: p.ev("oracle-" + s))
    e, h = seeds(p.s["EMPTY_SEEDS"]), seeds(p.s["HELD_EMPTY"])
    p.md(["task", "model", "random", "oracle", "reference (best student runs)"], [
        ["train, seed 0", rate(m("train-seed0"), True), rate(r("train-seed0")), rate(o("train-seed0")),
         "> 70 % (93 %)"],
        [f"test, {seeds(p.s['TEST_SEEDS'])}", rate(m("test"), True), rate(r("test")), rate(o("test"), True),
         "≈ 50 % (68 %; 100 % with retries)"],
        ["empty_bin, seed 2, np8", scene(m("empty_bin-seed2-np8")), DASH, DASH, "at least 8 of 15 moved (15/15)"],
        [f"empty_bin, {e}", moved(m("empty_bin")), bare(r("empty_bin")), moved(o("empty_bin")), DASH],
        [f"empty_bin, {e}, np8", f"**{moved(m('empty_bin-np8'))}**", DASH, moved(o("empty_bin-np8")), DASH],
        [f"held out: test, {seeds(p.s['HELD_TEST'])}", rate(m("test-heldout")), DASH, DASH, DASH],
        [f"held out: empty_bin, {h}, np8", moved(m("empty_bin-heldout-np8")), DASH,
         moved(o("empty_bin-heldout-np8")), DASH],
    ])


def t_yardstick(p):
    p.head("Oracle yardstick in clutter",
           "`graspmap eval --task empty_bin --policy oracle --seeds S [--n-past-action N]`.")
    a, b = seeds(p.s["EMPTY_SEEDS"]), seeds(p.s["HELD_EMPTY"])
    both = lambda r: [moved(r, lost=False), count(r)]
    o, m = (lambda s: p.ev("oracle-" + s)), (lambda s: p.ev("model-" + s))
    p.md(["policy", f"empty_bin, {a}", "pick success", f"empty_bin, {b}", "pick success"], [
        ["oracle, no memory"] + both(o("empty_bin")) + both(o("empty_bin-heldout")),
        ["oracle, np8"] + both(o("empty_bin-np8")) + both(o("empty_bin-heldout-np8")),
        ["oracle, `--n-past-action 25` (the whole episode)"] + both(o("empty_bin-np25")) + [DASH, DASH],
        ["model, np8"] + both(m("empty_bin-np8")) + both(m("empty_bin-heldout-np8")),
    ])
    p.say(f"Oracle np8 minus model np8, paired per seed: {paired(o('empty_bin-np8'), m('empty_bin-np8'))} ({a}), "
          f"{paired(o('empty_bin-heldout-np8'), m('empty_bin-heldout-np8'))} ({b}).")
    p.say()


# VPG's own figures for its method on its eleven cases: Zeng et al., IROS 2018, Table II
# ("simulation results on challenging arrangements", mean %), on V-REP with its own robot.
VPG_TABLE_II = [
    ("Grasping-only", "40.6", "51.7", "51.7"),
    ("P+G Reactive", "48.2", "59.0", "46.4"),
    ("VPG", "82.7", "77.2", "60.1"),
]


def t_scenes(p):
    p.head("VPG's challenging arrangements",
           "`graspmap --objects-dir assets/blocks eval --task scenes --scenes tests/fixtures/vpg --seeds S "
           "--n-past-action 8 [--verify-margin 10] [--policy oracle]`; the demo model (default labels, which "
           "never show a block).")
    cell = lambda v: DASH if v is None else f"{pct(v)} %"
    rows = []
    for name, label in (("model", "model"), ("model+verify-margin-10", "model, `--verify-margin 10`"),
                        ("oracle", "oracle")):
        r = load_eval(p.path(f"scenes/{name}.json"))
        # Each case for the headline setting; the means for the others.
        cases = r["cases"] if name == "model+verify-margin-10" else r["cases"][-1:]
        for case in cases:
            mean = case["scene"] == "mean"
            first = [f"**{label}**" if mean else label, "**mean**" if mean else case["scene"],
                     f"{case['completed']}/{case['runs']}"]
            rows.append(first + [cell(v) for v in (case["completion"], case["grasp_success"],
                                                    case["action_efficiency"], case["grasp_share"])])
    # VPG's rows are its own method on all eleven of its cases, in its own simulator.
    rows += [[f"{method} (VPG's paper, Table II)", "its 11 cases, V-REP", DASH, f"{c} %", f"{g} %", f"{e} %", DASH]
             for method, c, g, e in VPG_TABLE_II]
    p.md(["policy", "case", "runs cleared", "completion", "grasp success", "action efficiency",
          "grasps among actions"], rows)
    p.say("The last rows are VPG's published means (Zeng et al., IROS 2018, Table II, \"simulation results on "
          "challenging arrangements\") on all eleven of its cases in its own simulator (V-REP, its own arm, "
          "gripper and blocks' physics): a different simulator, not a run of graspmap.")
    p.say()


def t_sweep(p):
    p.head("Oracle sweep", "`scripts/grasp-sweep.sh oracle|random` (one `graspmap grasp` per object and seed).")
    rows = []
    for policy in ("oracle", "random"):
        r = p.load(f"sweep/{policy}.json")
        rows.append([policy, f"{r['successes']}/{r['attempts']}", f"{100 * r['successes'] / r['attempts']:.1f} %",
                     f"{p.machine}, {p.commit}"])
    p.md(["policy", "successes", "rate", "machine, commit"], rows)


def t_placing(p):
    p.head("Objects that stay in bin 2",
           "`graspmap eval --task empty_bin --seeds S --n-past-action 8 [--policy oracle] [--objects-dir MESH_OBJECTS]`.")
    rows = []
    for policy in ("model", "oracle"):
        for flags, objects in (((), "bundled"), (("--objects-dir",), "MESH_OBJECTS")):
            if flags and not p.s["MESH_OBJECTS"]:
                rows.append([policy, objects, "not run: no MESH_OBJECTS", DASH, DASH])
                continue
            e, t = p.ev(f"{policy}-empty_bin-np8", *flags), p.ev(f"{policy}-train-seeds1-3", *flags)
            rows.append([policy, objects, moved(e, lost=False), after_carry(e), rate(t)])
    p.md(["policy", "objects", f"empty_bin, {seeds(p.s['EMPTY_SEEDS'])}, np8: moved", "lost per scene",
          "train, seeds 1–3"], rows)


def t_collision(p):
    p.head("Collision check", "`graspmap eval ... --verify-top 0 --collision-check off|walls|full`.")
    rows = []
    for check, label in (("off", "`off` (the plain argmax)"), ("walls", "`walls`"), ("full", "`full` (default)")):
        flags = ("--verify-top 0",) + (() if check == "full" else (f"--collision-check {check}",))
        g = lambda s: p.ev(f"model-{s}", *flags)
        rows.append([label, count(g("train-seed0")), rate(g("test")), bare(g("empty_bin")), bare(g("empty_bin-np8"))])
    p.md(["setting", "train, seed 0", f"test, {seeds(p.s['TEST_SEEDS'])}", f"empty_bin, {seeds(p.s['EMPTY_SEEDS'])}",
          f"empty_bin, {seeds(p.s['EMPTY_SEEDS'])}, np8"], rows)


VERIFICATION = (
    ("--verify-rejected 0", "`--verify-rejected 0`"),
    ("--verify-floor 0.25", "`--verify-floor 0.25`"),
    ("--verify-square 0", "`--verify-square 0`"),
    ("--verify-strips 2 --verify-square 0", "`--verify-strips 2 --verify-square 0` (the planner's rule)"),
    ("--verify-margin 6", "`--verify-margin 6` (the planner's margin)"),
    ("--push-unverified false", "`--push-unverified false`"),
    ("--verify-top 0", "`--verify-top 0` (no verification)"),
)


def split_flags(text):
    """'--a 1 --b 2' -> ('--a 1', '--b 2')."""
    return tuple("--" + f.strip() for f in text.split("--") if f.strip())


def t_verification(p):
    p.head("Verification", "`graspmap eval` with the defaults and one check changed: "
           + ", ".join(f"`{flags}`" for flags, _ in VERIFICATION) + ".")
    base = lambda s: p.ev(f"model-{s}")
    specs = ("train-seed0", "test", "empty_bin-np8", "empty_bin-heldout-np8")
    rows, notes = [], []
    for flags, label in ((None, "defaults"),) + VERIFICATION:
        g = (lambda s: p.ev(f"model-{s}", *split_flags(flags))) if flags else base
        rows.append([label, count(g(specs[0])), rate(g(specs[1])), bare(g(specs[2])), bare(g(specs[3]))])
        if flags:
            notes.append(f"`{flags}`: test {paired(g('test'), base('test'))}, empty_bin "
                         f"{paired(g(specs[2]), base(specs[2]))} and {paired(g(specs[3]), base(specs[3]))}")
    p.md(["setting", "train, seed 0", f"test, {seeds(p.s['TEST_SEEDS'])}", f"empty_bin, {seeds(p.s['EMPTY_SEEDS'])}, np8",
          f"empty_bin, {seeds(p.s['HELD_EMPTY'])}, np8"], rows)
    p.say("Paired per seed against the defaults: " + "; ".join(notes) + ".")
    p.say()


def t_centring(p):
    p.head("Centring", "`graspmap eval ... --verify-top 0 [--centring]`.")
    rows = []
    for flags, label in ((("--verify-top 0",), "`--verify-top 0`"),
                         (("--verify-top 0", "--centring"), "`--verify-top 0 --centring`")):
        g = lambda s: p.ev(f"model-{s}", *flags)
        rows.append([label, count(g("train-seed0")), rate(g("test")), bare(g("empty_bin-np8"))])
    p.md(["setting", "train, seed 0", f"test, {seeds(p.s['TEST_SEEDS'])}", f"empty_bin, {seeds(p.s['EMPTY_SEEDS'])}, np8"],
         rows)


def t_suppression(p):
    p.head("Failure suppression", "`graspmap eval --task empty_bin --n-past-action 8` with one parameter changed.")
    base = p.ev("model-empty_bin-np8")
    rows = [["defaults", bare(base), DASH]]
    for flag in ("--suppress-rotation-reach 1", "--suppress-rotation-reach 4", "--suppression-sigma 6",
                 "--suppress-successes"):
        r = p.ev("model-empty_bin-np8", flag)
        rows.append([f"`{flag}`", bare(r), paired(r, base)])
    off = p.ev("model-empty_bin")
    rows.append(["`--n-past-action 0` (off)", bare(off), paired(off, base)])
    p.md(["setting", f"empty_bin, {seeds(p.s['EMPTY_SEEDS'])}", "paired against the defaults"], rows)


def variant_row(p, v):
    """One variant's row, and its reports for the paired notes."""
    e = f"variants/{v['name']}/eval"
    if not v["floor"]:
        get = {"train": p.ev("train-seed0", under=e), "test": p.ev("test", under=e),
               "np8": p.ev("empty_bin-np8", under=e), "htest": None, "hnp8": None}
        # Only the rows BENCHMARKS.md shows have held-out seeds.
        if v["heldout"]:
            get.update(htest=p.ev("test-heldout", under=e), hnp8=p.ev("empty_bin-heldout-np8", under=e))
        lab, tr = p.load(f"variants/{v['name']}/label.json"), p.load(f"variants/{v['name']}/train.json")
        first = [f"{lab['total_labels']} ({lab['total_rounds']})", f"{tr['wall_seconds']:.0f}", f"{tr['best_val_loss']:.5f}"]
    else:
        floor = "--verify-floor 0.25"
        get = {k: p.ev(spec, floor, under=e) for k, spec in (
            ("train", "train-seed0"), ("test", "test"), ("np8", "empty_bin-np8"), ("htest", "test-heldout"),
            ("hnp8", "empty_bin-heldout-np8"))}
        first = ["(the same model)", "", ""]
    held = [rate(get["htest"]), bare(get["hnp8"])] if get["htest"] else [DASH, DASH]
    return [v["label"]] + first + [count(get["train"]), rate(get["test"]), bare(get["np8"])] + held, get


def t_variants(p):
    p.head("Input and label variants", "`scripts/variants.sh`, then the floor and the held-out seeds per variant.")
    rows, notes, base = [], [], None
    for v in p.load("variants/rows.json"):
        row, get = variant_row(p, v)
        rows.append(row)
        if base is None:
            base = get
        else:
            notes.append(f"{v['label']} {paired(get['test'], base['test'])}, {paired(get['np8'], base['np8'])}")
    short = lambda text: text.replace("-", "–").replace(",", "/")
    p.md(["variant", "labels (rounds)", "train s", "best val loss", "train, seed 0", f"test, {short(p.s['TEST_SEEDS'])}",
          f"empty_bin np8, {short(p.s['EMPTY_SEEDS'])}", f"test, {short(p.s['HELD_TEST'])}",
          f"empty_bin np8, {short(p.s['HELD_EMPTY'])}"], rows)
    p.say("Paired per seed against the default (test successes, empty_bin objects moved): "
          + ("; ".join(notes) or DASH) + ".")
    p.say()


def t_labelling(p):
    p.head("Labelling", f"`graspmap --data D [--threads 1] label --per-object {p.s['PER_OBJECT']}` from an empty data dir.")
    one, default = p.load("labelling/one-thread.json"), p.load("labelling/default-threads.json")
    rerun = "byte-identical" if p.load("labelling/rerun.json")["identical"] else "different (see diff.txt)"
    p.md(["machine", "commit", "labels (rounds)", "wall, `--threads 1`", "wall, default `--threads`", "rerun"],
         [[p.machine, p.commit, f"{one['total_labels']} ({one['total_rounds']})", secs(one["wall_seconds"]),
           secs(default["wall_seconds"]), rerun]])


SOAK_CHECKS = (("panics", "panics"), ("no_reason", "attempts without a reason"),
               ("nonfinite", "a NaN or infinite pose or velocity"),
               ("sunk", "attempts with an object more than 5 mm inside the ground or a tote"))


def t_soak(p):
    p.head("Physics soak", "`GRASPMAP=... DATA=... scripts/soak.sh N M 4242`.")
    s = p.load("soak/summary.json")["policies"]
    cell = lambda policy, key: f"{s[policy][key]} of {s[policy]['attempts']:,}" if key == "sunk" else s[policy][key]
    p.md(["check", f"random policy, {s['random']['scenes']} scenes", f"model, {s['model']['scenes']} scenes"],
         [[label, cell("random", key), cell("model", key)] for key, label in SOAK_CHECKS])
    p.say(f"Wall: {secs(p.wall('soak/soak.time.json'))}.")
    p.say()


def fuzz_rows(p):
    passes = p.load("faults/fuzz.json")["passes"]
    ok = [f for f in passes if f["ok"]]
    json_passes = [f for f in ok if f["filter"] == "fuzz_json_"]
    binary = [f for f in ok if f["filter"] != "fuzz_json_"]
    rows = []
    if json_passes:
        rows.append(["fuzzing labels.json, clicks, split.json, progress.json, checkpoint state", "`scripts/fuzz.sh`",
                     f"{json_passes[0]['cases']:,} each",
                     f"0 panics, every input under 5 s and 2 GiB ({json_passes[0]['seconds']} s)"])
    if binary:
        rows.append(["fuzzing " + ", ".join(f["filter"].removeprefix("fuzz_") for f in binary), "`scripts/fuzz.sh`",
                     f"{binary[0]['cases']:,} each",
                     f"0 panics, every input under 5 s and 2 GiB ({sum(f['seconds'] for f in binary)} s)"])
    if len(ok) < len(passes):
        rows.append(["fuzzing", "`scripts/fuzz.sh`", DASH,
                     f"{len(passes) - len(ok)} of {len(passes)} passes failed (see fuzz.err)"])
    return rows


def kill_rows(p):
    k = p.load("faults/kill-resume.json")
    rows = []
    for what in ("label", "train"):
        kills = [x for x in k["kills"] if x["what"] == what]
        delays = [x["delay_s"] for x in kills]
        at = f"{min(delays)}–{max(delays)}" if len(set(delays)) > 1 else f"{delays[0]}" if delays else ""
        span = f"{len(kills)} kill{'s' * (len(kills) != 1)} at {at} s" if delays else DASH
        note = f" ({sum(x['resume'] for x in kills)} with `--resume`)" if what == "train" else ""
        rows.append([f"SIGKILL during `{what}`", "`scripts/kill-resume.sh`", span,
                     f"{len(kills)} resumed byte-identical{note}" + ("" if k["ok"] else "; the run failed (see kill.err)")])
    return rows


def t_faults(p):
    p.head("Faults", "`scripts/fuzz.sh SCALE` and `scripts/kill-resume.sh K 7`.")
    p.md(["check", "command", "cases", "result"], fuzz_rows(p) + kill_rows(p))
    p.say(f"The fuzz pass took {secs(p.wall('faults/fuzz.time.json'))}.")
    p.say()


def t_tests(p):
    p.head("Test suite and build", "`./test.sh` and `scripts/install-check.sh` (= `bash .ci/run`) in a fresh clone.")
    c = p.load("tests/cargo-test.json")
    total = p.wall("tests/test.time.json")
    install_skip, build_skip = p.skipped("tests/install.skipped.json"), p.skipped("tests/build.skipped.json")
    install = None if install_skip else p.wall("tests/install.time.json")
    build = None if build_skip else p.load("tests/build.time.json")
    tests = c["unit"] + c["suite"] + c["other"]
    p.md(["measure", "figure", "commit"], [
        ["`bash .ci/run` (`./test.sh`, then `scripts/install-check.sh`)",
         f"not run: {install_skip}" if install_skip else secs(total + install), p.commit],
        ["… building the test binaries", c["build"] or DASH, p.commit],
        ["… tests", f"{tests} passed: {c['unit']} unit, {c['suite']} in the suite"
         + (f" ({c['suite_s']:.1f} s)" if c["suite_s"] is not None else ""), p.commit],
        ["`scripts/install-check.sh` after `./test.sh`", f"not run: {install_skip}" if install_skip else secs(install),
         p.commit],
        ["clean `cargo build --release --locked` (`git archive`, empty target dir)",
         f"not run: {build_skip}" if build_skip else f"{build['wall_s']:.1f} s wall, {build['user_s']:.1f} s user CPU",
         p.commit]])


def t_webpage(p):
    p.head("Labelling page", "The browser test through `./test.sh`; `target/browser/label-timings.json`.")
    t = p.load("webpage/label-timings.json")
    times = [r["confirm_to_outcome_s"] for r in t["rounds"]]
    ok = sum(r["reason"] == "success" for r in t["rounds"])
    p.md(["measure", "figure"], [
        ["first load (navigation start to `load`)", f"{t['first_load_ms']:.0f} ms"],
        [f"confirm (`Enter`) to the outcome on the page, median of {len(times)} rounds",
         f"{statistics.median(times):.2f} s"],
        [f"confirm to the outcome, slowest of {len(times)} rounds", f"{t['slowest_confirm_to_outcome_s']:.2f} s"],
        [f"the whole dataset, {len(times)} rounds, {ok} successes", f"{t['wall_s']:.1f} s"]])


def video_row(p, kind, label):
    t = p.load(f"video/{kind}.time.json")
    r = p.ev(kind, under="video")
    size = frames = encoding = DASH
    if kind != "none":
        probe = p.load(f"video/{kind}.probe.json")
        n = int(probe["format"]["size"])
        size = f"{n:,} B ({n / 2 ** 20:.2f} MiB)"
        streams = probe.get("streams") or [{}]
        if streams[0].get("nb_read_frames"):
            frames = f"{streams[0]['nb_read_frames']}, {float(streams[0].get('duration') or 0):.1f} s"
        if r.get("video_encode_s") is None:
            raise Unfit(f"{p.path(f'video/{kind}.json')} records no video_encode_s")
        encoding = f"{r['video_encode_s']:.2f} s"
    return [label, size, frames, secs(t["wall_s"]), secs(t["user_s"]), encoding]


def t_video(p):
    p.head("Videos and the report", "`graspmap --data D eval --task empty_bin --seeds 1 [--record ep.gif|ep.mp4]`, "
           "then `graspmap report`.")
    rows = [video_row(p, kind, label)
            for kind, label in (("none", "no `--record`"), ("gif", "`.gif`"), ("mp4", "`.mp4` (H.264)"))]
    p.md(["run", "size", "frames (ffprobe)", "wall", "user CPU", "encoding"], rows)
    report = p.load("video/report.json")
    p.say(f"`graspmap report`: {secs(p.wall('video/report.time.json'))}, the page and "
          f"{len(report.get('files', []))} files.")
    p.say()


TABLES = {name.removeprefix("t_"): f for name, f in list(globals().items()) if name.startswith("t_")}


def render(table, out):
    """The table's Markdown; `Unfit` or `KeyError` when a report it needs is not fit."""
    page = Page(table, out)
    TABLES[table](page)
    return "\n".join(page.lines) + "\n"


def main(argv):
    if len(argv) != 3 or argv[1] not in TABLES:
        sys.exit(f"usage: render.py TABLE OUT   (TABLE: {', '.join(TABLES)})")
    table, out = argv[1], argv[2]
    try:
        text = render(table, out)
    except Unfit as e:
        sys.exit(f"render: table {table}: {e}")
    except (KeyError, TypeError, IndexError, ValueError, ZeroDivisionError) as e:
        sys.exit(f"render: table {table}: a report under {out} is not of the shape it expects "
                 f"({type(e).__name__}: {e})")
    sys.stdout.write(text)


if __name__ == "__main__":
    main(sys.argv)
