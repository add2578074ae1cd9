"""Reading graspmap's JSON reports and the statistics the benchmark tables share.

Every reader here fails with `Unfit`, naming the file, instead of returning a placeholder: a
table whose run did not leave its report must not quietly print a dash.
"""

import json
import math
import os
import statistics


class Unfit(Exception):
    """A report a table needs is missing, unreadable, cut short or of another shape."""


class Fields(dict):
    """A JSON object that names its file when a table asks it for a field it lacks."""

    def __init__(self, pairs, path):
        super().__init__(pairs)
        self.path = path

    def __missing__(self, key):
        raise Unfit(f"{self.path} has no field '{key}'")


def read_json(path):
    """The parsed file, or `Unfit` naming it."""
    try:
        with open(path) as f:
            return json.load(f, object_pairs_hook=lambda pairs: Fields(pairs, path))
    except FileNotFoundError:
        raise Unfit(f"{path} is missing") from None
    except (OSError, ValueError) as e:
        raise Unfit(f"{path} is unreadable: {e}") from None


def load(path):
    """The `results` of a versioned graspmap report, or the whole file for other JSON."""
    data = read_json(path)
    if isinstance(data, dict) and "results" in data and "schema" in data:
        return data["results"]
    return data


def load_eval(path):
    """An eval report's results; a run a signal stopped half-way is as good as missing."""
    r = load(path)
    if not isinstance(r, dict) or "success" not in r or "runs" not in r:
        raise Unfit(f"{path} is not an eval report")
    if r.get("interrupted"):
        raise Unfit(f"{path} is an interrupted report (a signal stopped it after {len(r['runs'])} runs): "
                    "rerun the table")
    return r


def skipped(path):
    """The reason in a `*.skipped.json` a run leaves when it does not apply here; None if absent."""
    if not os.path.exists(path):
        return None
    return read_json(path)["reason"]


def eval_name(base, *flags):
    """The file an evaluation is stored under: its base name, then each extra flag spelt out.

    scripts/benchmarks.sh names its runs through this too: ("model-test", "--verify-top 0") is
    model-test+verify-top-0; a flag whose value is a path keeps only its name.
    """
    parts = [base]
    for flag in flags:
        words = flag.split()
        name = words[0].removeprefix("--")
        if len(words) > 1 and "/" not in words[1]:
            name += "-" + words[1]
        parts.append(name)
    return "+".join(parts)


def per_seed(r):
    """Successes (train/test) or objects moved (empty_bin) per base seed, in seed order."""
    counts = {s: 0 for s in r["seeds"]}
    for run in r["runs"]:
        if run.get("bin") is not None:
            counts[run["seed"]] = run["bin"]["moved"]
        else:
            counts[run["seed"]] += sum(a["success"] for a in run["attempts"])
    return [counts[s] for s in r["seeds"]]


def paired_stats(a, b):
    """Mean and standard error of the per-seed differences a − b of two eval reports' results.

    Pairing only means something on the same scenes, so reports over other seeds are an error.
    """
    if a["seeds"] != b["seeds"]:
        raise Unfit(f"paired reports cover other seeds: {a['seeds']} against {b['seeds']}")
    d = [x - y for x, y in zip(per_seed(a), per_seed(b))]
    mean = sum(d) / len(d)
    se = statistics.stdev(d) / math.sqrt(len(d)) if len(d) > 1 else 0.0
    return mean, se


# Cells: how the tables print a report's figures.

DASH = "–"


def seeds(text):
    return "seeds " + text.replace("-", "–").replace(",", ", ")


def pct(x):
    return f"{100 * x:.1f}"


def signed(x):
    return f"{x:+.2f}".replace("-", "−")


def rate(r, ci=False):
    s = r["success"]
    text = f"{s['successes']}/{s['trials']} = {pct(s['rate'])} %"
    return text + (f" (CI {pct(s['wilson_low'])}–{pct(s['wilson_high'])})" if ci else "")


def count(r):
    s = r["success"]
    return f"{s['successes']}/{s['trials']}"


def moved(r, span=True, lost=True):
    m = r["moved"]
    if m is None:
        raise Unfit(f"a {r['task']} report where an empty_bin one belongs")
    text = f"{m['mean']:.1f} ± {m['std']:.1f}"
    if span and m["count"] > 1:
        text += f" ({m['min']:.0f}–{m['max']:.0f})"
    if lost:
        text += f", {r['lost']['mean']:.1f} lost"
    return text


def bare(r):
    return moved(r, span=False, lost=False)


def scene(r):
    """One empty_bin scene: k/n moved, l lost."""
    b = r["runs"][0]["bin"]
    return f"{b['moved']}/{len(b['locations'])} moved, {b['lost']} lost"


def paired(a, b):
    """Mean ± standard error of the per-seed differences a − b."""
    mean, se = paired_stats(a, b)
    return f"{signed(mean)} ± {se:.2f}"


def secs(x):
    return DASH if x is None else f"{x:.2f} s" if x < 10 else f"{x:.1f} s"


def after_carry(r):
    """Per scene: objects lost, and those lost after a successful carry (placed outside bin 2)."""
    carried = [a for run in r["runs"] for a in run["attempts"] if a.get("success")]
    outside = sum(1 for a in carried if a.get("placed") != "bin2")
    return f"{r['lost']['mean']:.1f} lost, {outside / len(r['runs']):.1f} after a carry"
