"""Tests of the benchmark tables' renderer, on real reports from earlier runs (fixtures/).

fixtures/out is an OUT tree with every table's own files; fixtures/evals holds one real report
per kind of evaluation, which `filled_out` files under every evaluation name a table asks for.
Run: python3 -m unittest discover -s scripts/benchmarks -q
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import helpers  # noqa: E402
import render  # noqa: E402
from reports import Unfit, paired_stats, rate  # noqa: E402

FIXTURES = os.path.join(HERE, "fixtures")
ROOT = os.path.dirname(os.path.dirname(HERE))
# The kinds of evaluation fixtures/evals has a report for, longest first so the most specific wins.
KINDS = ("empty_bin-heldout-np8", "empty_bin-heldout", "empty_bin-seed2-np8", "empty_bin-np25", "empty_bin-np8",
         "empty_bin", "test-heldout", "train-seeds1-3", "train-seed0", "test")
SAME_SCENES = {"empty_bin": "empty_bin-np8", "empty_bin-np25": "empty_bin-np8",
               "empty_bin-heldout": "empty_bin-heldout-np8"}


def eval_fixture(path):
    """The fixture report for an evaluation file: the kind its name spells out; its
    `--verify-top 0` run where the fixtures have one."""
    base, *flags = os.path.basename(path)[:-len(".json")].split("+")
    kind = next(k for k in KINDS if base.endswith(k))
    kind = SAME_SCENES.get(kind, kind)
    vt0 = os.path.join(FIXTURES, "evals", f"{kind}+verify-top-0.json")
    if "verify-top-0" in flags and os.path.exists(vt0):
        return vt0
    return os.path.join(FIXTURES, "evals", f"{kind}.json")


def filled_out(table, out):
    """Copies fixtures/out to OUT and files an evaluation report under every name the table
    reads, learning the names from the renderer's own failures; returns the Markdown."""
    shutil.copytree(os.path.join(FIXTURES, "out"), out, dirs_exist_ok=True)
    for _ in range(500):
        try:
            return render.render(table, out)
        except Unfit as e:
            path = str(e).split(" is missing")[0]
            if " is missing" not in str(e) or "/eval/" not in path:
                raise
            os.makedirs(os.path.dirname(path), exist_ok=True)
            shutil.copy(eval_fixture(path), path)
    raise AssertionError(f"{table} kept asking for reports")


def rows(markdown):
    return [line for line in markdown.splitlines() if line.startswith("|")]


class Tables(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp()
        self.out = os.path.join(self.dir, "out")

    def tearDown(self):
        shutil.rmtree(self.dir)

    def table(self, name):
        return filled_out(name, self.out)

    def test_every_table_renders_a_header_a_rule_and_rows_of_its_width(self):
        for name in render.TABLES:
            with self.subTest(table=name):
                text = filled_out(name, os.path.join(self.dir, name))
                lines = rows(text)
                self.assertGreaterEqual(len(lines), 3, text)
                width = lines[0].count("|")
                self.assertEqual(lines[1], "|" + "---|" * (width - 1))
                for line in lines[2:]:
                    self.assertEqual(line.count("|"), width, line)
                self.assertIn("commit 311a1c9", text)

    def test_verification_columns_and_cells(self):
        text = self.table("verification")
        lines = rows(text)
        self.assertEqual(lines[0], "| setting | train, seed 0 | test, seeds 0, 1000, 2000 | empty_bin, seeds 1–10, np8 "
                                   "| empty_bin, seeds 11–20, np8 |")
        self.assertIn("| defaults | 15/15 | 84/90 = 93.3 % | 14.2 ± 0.9 | 14.6 ± 0.5 |", lines)
        self.assertIn("| `--verify-top 0` (no verification) | 13/15 | 78/90 = 86.7 % | 13.4 ± 1.1 | 13.3 ± 1.3 |", lines)
        # Test successes per seed 25, 26, 27 against 27, 29, 28: −2, −3, −1, sd 1; moved, seeds 1–10:
        # 12 13 13 15 14 14 12 13 15 13 against 13 15 13 15 15 15 14 13 15 14, mean −0.8, sd 0.789.
        self.assertIn("`--verify-top 0`: test −2.00 ± 0.58, empty_bin −0.80 ± 0.25 and −1.30 ± 0.42", text)
        self.assertIn("`--verify-margin 6`: test +0.00 ± 0.00", text)

    def test_quality_has_the_wilson_interval_of_the_model(self):
        lines = rows(self.table("quality"))
        self.assertEqual(lines[0], "| task | model | random | oracle | reference (best student runs) |")
        self.assertTrue(lines[3].startswith("| test, seeds 0, 1000, 2000 | 84/90 = 93.3 % (CI 86.2–96.9) |"), lines[3])
        self.assertIn("| empty_bin, seed 2, np8 | ", lines[4])

    def test_timings(self):
        self.assertIn("| Intel(R) Xeon(R) Processor (AVX2, AVX-512, AVX-512 BF16, AMX BF16), 2 cores | 311a1c9 | 7.16 s "
                      "| 13.2 s | 2.73 s, 4.55 s, 16.3 s | **45.0 s** (report 0.23 s) |", rows(self.table("pipeline")))
        threads = rows(self.table("threads"))
        self.assertIn("| one process, `--threads 2` | 49.0 s | 216 | 0.23 s | 0.10 s |", threads)
        training = rows(self.table("training"))
        self.assertTrue(training[2].endswith("| fp32 | 42.0 s | 1.23–1.42 | ≈ 46.2 | 0.00122 (30) |"), training[2])

    def test_workcell_reads_criterion_estimates(self):
        lines = rows(self.table("workcell"))
        self.assertEqual(lines[0], "| what | figure |")
        # Criterion's point estimates: median 1,720,120 ns; 193,101,325 ns median, 192,434,793 ns mean.
        self.assertIn("| one 128 × 128 top-down frame, 86 drawables | 1.72 ms, median |", lines)
        self.assertIn("| one single-object pick attempt, 15 objects × seeds 1–3 in turn | 193 ms median, 192 ms mean |",
                      lines)
        # 17.40 simulated seconds in 0.1924 s of wall.
        self.assertIn("| simulated time per attempt | 17.4 s (≈ 90× faster than real time) |", lines)

    def test_video_reads_the_encoding_time_from_the_eval_report(self):
        lines = rows(self.table("video"))
        self.assertEqual(lines[0], "| run | size | frames (ffprobe) | wall | user CPU | encoding |")
        self.assertIn("| `.gif` | 25,284,082 B (24.11 MiB) | 2932, 293.2 s | 25.0 s | 30.5 s | 3.42 s |", lines)
        self.assertTrue(lines[2].startswith("| no `--record` | – | – |"), lines[2])

    def test_scripts_summaries(self):
        self.assertIn("| oracle | 15/15 | 100.0 % |", rows(self.table("sweep"))[2])
        faults = rows(self.table("faults"))
        self.assertIn("1,000 each | 0 panics, every input under 5 s and 2 GiB (32 s) |", faults[2])
        # The six binary passes: 31 + 32 + 31 + 31 + 34 + 32 s.
        self.assertIn("100 each | 0 panics, every input under 5 s and 2 GiB (191 s) |", faults[3])
        self.assertIn("| SIGKILL during `train` | `scripts/kill-resume.sh` | 1 kill at 0.95 s "
                      "| 1 resumed byte-identical (1 with `--resume`) |", faults)
        soak = rows(self.table("soak"))
        self.assertEqual(soak[0], "| check | random policy, 2 scenes | model, 1 scenes |")
        self.assertIn("| attempts with an object more than 5 mm inside the ground or a tote | 0 of 50 | 0 of 25 |", soak)
        tests = rows(self.table("tests"))
        self.assertIn("| … tests | 297 passed: 181 unit, 116 in the suite (181.5 s) | 311a1c9 |", tests)
        self.assertIn("| `bash .ci/run` (`./test.sh`, then `scripts/install-check.sh`) | 534.0 s | 311a1c9 |", tests)

    def test_variants_without_held_out_seeds_show_dashes_there(self):
        lines = rows(self.table("variants"))
        self.assertEqual(lines[0], "| variant | labels (rounds) | train s | best val loss | train, seed 0 | test, 0/1000/2000 "
                                   "| empty_bin np8, 1–10 | test, 3000/4000/5000 | empty_bin np8, 11–20 |")
        self.assertEqual(lines[2], "| rgb, clutter 1 (default) | 60 (60) | 42 | 0.00122 | 15/15 | 84/90 = 93.3 % | 14.2 ± 0.9 "
                                   "| 83/90 = 92.2 % | 14.6 ± 0.5 |")
        self.assertEqual(lines[4], "| rgbd, clutter 1 | 60 (60) | 42 | 0.00122 | 15/15 | 84/90 = 93.3 % | 14.2 ± 0.9 | – | – |")

    def test_failed_fault_runs_say_so(self):
        shutil.copytree(os.path.join(FIXTURES, "out"), self.out)
        fuzz = os.path.join(self.out, "faults", "fuzz.json")
        with open(fuzz) as f:
            summary = json.load(f)
        summary["passes"][1]["ok"] = False
        with open(fuzz, "w") as f:
            json.dump(summary, f)
        kill = os.path.join(self.out, "faults", "kill-resume.json")
        with open(kill, "w") as f:
            json.dump({"k": 1, "seed": 7, "ok": False, "kills": [{"what": "label", "delay_s": 2.08, "resume": False}]}, f)
        lines = rows(render.render("faults", self.out))
        self.assertIn("| fuzzing | `scripts/fuzz.sh` | – | 1 of 7 passes failed (see fuzz.err) |", lines)
        self.assertIn("| SIGKILL during `train` | `scripts/kill-resume.sh` | – "
                      "| 0 resumed byte-identical (0 with `--resume`); the run failed (see kill.err) |", lines)

    def test_a_run_recorded_as_skipped_is_a_dash_not_a_failure(self):
        shutil.copytree(os.path.join(FIXTURES, "out"), self.out)
        shutil.rmtree(os.path.join(self.out, "training", "bf16"))
        helpers.skip(os.path.join(self.out, "training", "bf16.skipped.json"), "no native bf16 on this CPU")
        bf16 = rows(render.render("training", self.out))[3]
        self.assertTrue(bf16.endswith("| bf16 | not run: no native bf16 on this CPU | – | – | – |"), bf16)


class Failures(unittest.TestCase):
    """A report that should be there and is not stops the table, naming the file."""

    def setUp(self):
        self.dir = tempfile.mkdtemp()
        self.out = os.path.join(self.dir, "out")
        filled_out("verification", self.out)

    def tearDown(self):
        shutil.rmtree(self.dir)

    def run_main(self, table):
        return subprocess.run([sys.executable, os.path.join(HERE, "render.py"), table, self.out],
                              capture_output=True, text=True)

    def test_a_missing_report_fails_loudly_with_its_name(self):
        gone = os.path.join(self.out, "eval", "model-test+verify-square-0.json")
        os.remove(gone)
        done = self.run_main("verification")
        self.assertEqual(done.returncode, 1)
        self.assertEqual(done.stdout, "")
        self.assertEqual(done.stderr, f"render: table verification: {gone} is missing\n")

    def test_an_unreadable_report_names_the_file(self):
        path = os.path.join(self.out, "eval", "model-empty_bin-np8.json")
        with open(path, "r+") as f:
            f.truncate(100)
        done = self.run_main("verification")
        self.assertEqual(done.returncode, 1)
        self.assertIn(f"render: table verification: {path} is unreadable", done.stderr)
        self.assertEqual(len(done.stderr.splitlines()), 1)

    def test_an_interrupted_report_is_refused(self):
        path = os.path.join(self.out, "eval", "model-test.json")
        with open(path) as f:
            report = json.load(f)
        report["results"]["interrupted"] = True
        report["results"]["runs"] = report["results"]["runs"][:4]
        with open(path, "w") as f:
            json.dump(report, f)
        done = self.run_main("verification")
        self.assertEqual(done.returncode, 1)
        self.assertIn(f"render: table verification: {path} is an interrupted report", done.stderr)

    def test_missing_settings_fail_too(self):
        os.remove(os.path.join(self.out, "settings.json"))
        done = self.run_main("quality")
        self.assertEqual(done.returncode, 1)
        self.assertIn("settings.json is missing", done.stderr)

    def test_a_report_without_a_field_names_the_file_and_the_field(self):
        path = os.path.join(self.out, "sweep", "oracle.json")
        with open(path, "w") as f:
            json.dump({"policy": "oracle", "attempts": 15}, f)
        done = self.run_main("sweep")
        self.assertEqual(done.returncode, 1)
        self.assertEqual(done.stderr, f"render: table sweep: {path} has no field 'successes'\n")


def report(seeds, per_seed, task="test"):
    """A minimal eval report: `per_seed` successes (test) or objects moved (empty_bin) per seed."""
    if task == "empty_bin":
        runs = [{"seed": s, "bin": {"moved": n}, "attempts": []} for s, n in zip(seeds, per_seed)]
    else:
        # Two objects per seed, so that a seed's successes are summed over its runs.
        runs = [{"seed": s, "attempts": [{"success": i < n} for i in range(5)]}
                for s, n in zip(seeds, per_seed) for _ in range(2)]
    return {"seeds": list(seeds), "runs": runs}


class Paired(unittest.TestCase):
    def test_mean_and_standard_error_of_the_per_seed_differences(self):
        # Differences 1, 3, 0: mean 4/3, sd sqrt(7/3), se sqrt(7/9) = 0.882.
        a, b = report([1, 2, 3], [3, 5, 4], "empty_bin"), report([1, 2, 3], [2, 2, 4], "empty_bin")
        mean, se = paired_stats(a, b)
        self.assertAlmostEqual(mean, 4 / 3)
        self.assertAlmostEqual(se, (7 / 9) ** 0.5)
        self.assertEqual(render.paired(a, b), "+1.33 ± 0.88")
        self.assertEqual(render.paired(b, a), "−1.33 ± 0.88")

    def test_train_and_test_count_successes_over_every_run_of_a_seed(self):
        # 3 of 5 in each of two runs per seed: 6 and 6 against 2 and 4; differences 4 and 2.
        a, b = report([0, 1000], [3, 3]), report([0, 1000], [1, 2])
        self.assertEqual(render.paired(a, b), "+3.00 ± 1.00")

    def test_one_seed_has_no_spread(self):
        self.assertEqual(render.paired(report([2], [9], "empty_bin"), report([2], [7], "empty_bin")), "+2.00 ± 0.00")

    def test_other_seeds_are_an_error(self):
        with self.assertRaises(Unfit) as e:
            paired_stats(report([1, 2], [1, 1]), report([1, 3], [1, 1]))
        self.assertIn("other seeds", str(e.exception))


class Cells(unittest.TestCase):
    def test_wilson_interval_text(self):
        # 84 of 90: p 0.9333, z 1.96; centre (p + z²/2n) / (1 + z²/n), half-width z √(p(1−p)/n + z²/4n²) / (1 + z²/n).
        n, k, z = 90, 84, 1.959964
        p = k / n
        centre = (p + z * z / (2 * n)) / (1 + z * z / n)
        half = z * (p * (1 - p) / n + z * z / (4 * n * n)) ** 0.5 / (1 + z * z / n)
        r = {"success": {"successes": k, "trials": n, "rate": p, "wilson_low": centre - half,
                         "wilson_high": centre + half}}
        self.assertEqual(rate(r, ci=True), "84/90 = 93.3 % (CI 86.2–96.9)")
        self.assertEqual(rate(r), "84/90 = 93.3 %")
        with open(os.path.join(FIXTURES, "evals", "test.json")) as f:
            s = json.load(f)["results"]["success"]
        self.assertAlmostEqual(s["wilson_low"], centre - half, places=6)
        self.assertAlmostEqual(s["wilson_high"], centre + half, places=6)

    def test_eval_names_match_the_runner(self):
        """benchmarks.sh's words and render.py's flags spell an evaluation's file name alike."""
        helpers = os.path.join(ROOT, "scripts", "benchmarks", "helpers.py")
        args = ["model-test", "--verify-top", "0", "--objects-dir", "/some/meshes", "--centring",
                "--verify-floor", "0.25"]
        runner = subprocess.run([sys.executable, helpers, "eval-name", *args], capture_output=True, text=True,
                                check=True)
        python = render.eval_name("model-test", "--verify-top 0", "--objects-dir /some/meshes", "--centring",
                                  "--verify-floor 0.25")
        self.assertEqual(runner.stdout.strip(), python)
        self.assertEqual(python, "model-test+verify-top-0+objects-dir+centring+verify-floor-0.25")


class Adapters(unittest.TestCase):
    def test_cargo_test_output_becomes_counts_per_target(self):
        log = """    Finished `release` profile [optimized] target(s) in 2m 49s
     Running unittests src/lib.rs (target/release/deps/graspmap-1)
test result: ok. 180 passed; 0 failed; 0 ignored; 0 measured; 0 filtered out; finished in 20.01s
     Running unittests src/main.rs (target/release/deps/graspmap-2)
test result: ok. 1 passed; 0 failed; 0 ignored; 0 measured; 0 filtered out; finished in 0.00s
     Running tests/suite/main.rs (target/release/deps/suite-3)
test result: ok. 116 passed; 0 failed; 0 ignored; 0 measured; 0 filtered out; finished in 181.50s
   Doc-tests graspmap
test result: ok. 2 passed; 0 failed; 0 ignored; 0 measured; 0 filtered out; finished in 0.10s
"""
        self.assertEqual(helpers.cargo_test_summary(log),
                         {"build": "2m 49s", "unit": 181, "suite": 116, "other": 2, "suite_s": 181.5})

    def test_text_that_is_not_cargo_test_output_is_refused(self):
        with self.assertRaises(ValueError):
            helpers.cargo_test_summary("error: could not compile `graspmap`\n")


if __name__ == "__main__":
    unittest.main()
