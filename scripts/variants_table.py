"""The table and summary of scripts/variants.sh: reads OUT/<variant>/{label,train}.json and
OUT/<variant>/eval/*.json, prints the markdown table and writes OUT/summary.json with the
decision rule of issue 14 (docs/departures.md) evaluated against the first variant.

Usage: python3 scripts/variants_table.py OUT input:clutter[:per-object] ...
"""

import json
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "benchmarks"))
from reports import paired_stats, per_seed  # noqa: E402  (shared with the benchmark tables)


def name(v):
    parts = v.split(":")
    return f"{parts[0]}-c{parts[1]}" + (f"-p{parts[2]}" if len(parts) > 2 else "")


def load(path):
    """A report's results; None when it is missing or a signal stopped it half-way."""
    if not os.path.exists(path):
        return None
    results = json.load(open(path))["results"]
    return None if results.get("interrupted") else results


# Each row key (the summary's) and the file variants.sh writes it to, named for what it runs.
FILES = {"train_vt200": "train-seed0", "train_vt0": "train-seed0+verify-top-0", "test_vt200": "test",
         "test_vt0": "test+verify-top-0", "empty_np8_vt200": "empty_bin-np8", "empty_np0_vt200": "empty_bin",
         "empty_np8_vt0": "empty_bin-np8+verify-top-0", "empty_np0_vt0": "empty_bin+verify-top-0"}


def main():
    out, variants = sys.argv[1], sys.argv[2:]
    # A variant that has not been trained yet (a run stopped early) is left out.
    variants = [v for v in variants if os.path.exists(f"{out}/{name(v)}/train.json")]
    names = [name(v) for v in variants]
    rows, reports = {}, {}
    for v, n in zip(variants, names):
        d = f"{out}/{n}"
        train = load(f"{d}/train.json")
        label = load(f"{d}/label.json")
        row = {
            "input": v.split(":")[0],
            "clutter": int(v.split(":")[1]),
            "labels": label["total_labels"],
            "label_rounds": label["total_rounds"],
            "train_seconds": train["wall_seconds"],
            "best_val_loss": train["best_val_loss"],
        }
        for key, file in FILES.items():
            report = load(f"{d}/eval/{file}.json")
            row[key] = None if report is None else per_seed(report)
            reports[(n, key)] = report
        rows[n] = row

    base = rows[names[0]]
    core = ("train_vt200", "test_vt200", "empty_np8_vt200")
    for n in names[1:]:
        r = rows[n]
        if any(r[k] is None or base[k] is None for k in core):
            r["rule"] = None
            continue
        test = paired_stats(reports[(n, "test_vt200")], reports[(names[0], "test_vt200")])
        empty = paired_stats(reports[(n, "empty_np8_vt200")], reports[(names[0], "empty_np8_vt200")])
        r["rule"] = {
            "test_diff_mean": test[0], "test_diff_se": test[1],
            "test_beats": test[0] > test[1] and test[0] > 0,
            "empty_diff_mean": empty[0], "empty_diff_se": empty[1],
            "empty_beats": empty[0] > empty[1] and empty[0] > 0,
            "train_loss": sum(base["train_vt200"]) - sum(r["train_vt200"]),
            "train_ok": sum(r["train_vt200"]) >= sum(base["train_vt200"]) - 1,
            "time_ratio": r["train_seconds"] / base["train_seconds"],
            "time_ok": r["train_seconds"] <= 1.1 * base["train_seconds"],
        }
        rule = r["rule"]
        rule["holds"] = all(rule[k] for k in ("test_beats", "empty_beats", "train_ok", "time_ok"))

    def frac(xs, per):
        return "–" if xs is None else f"{sum(xs)}/{per * len(xs)} = {100 * sum(xs) / (per * len(xs)):.1f} %"

    def moved(xs):
        if xs is None:
            return "–"
        m = sum(xs) / len(xs)
        sd = math.sqrt(sum((x - m) ** 2 for x in xs) / (len(xs) - 1))
        return f"{m:.1f} ± {sd:.1f}"

    print("| variant | labels (rounds) | train s | best val loss | train, seed 0 | test, 0/1000/2000 "
          "| empty_bin np8 | empty_bin np0 | train vt0 | test vt0 | empty_bin np8 vt0 | empty_bin np0 vt0 |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for n in names:
        r = rows[n]
        print(f"| {r['input']}, clutter {r['clutter']} | {r['labels']} ({r['label_rounds']}) "
              f"| {r['train_seconds']:.0f} | {r['best_val_loss']:.5f} "
              f"| {frac(r['train_vt200'], 15)} | {frac(r['test_vt200'], 30)} "
              f"| {moved(r['empty_np8_vt200'])} | {moved(r['empty_np0_vt200'])} "
              f"| {frac(r['train_vt0'], 15)} | {frac(r['test_vt0'], 30)} "
              f"| {moved(r['empty_np8_vt0'])} | {moved(r['empty_np0_vt0'])} |")
    print()
    print(f"Against {names[0]} (per-seed paired differences, mean ± standard error):")
    print()
    print("| variant | test successes per seed | empty_bin np8 moved per seed | train successes lost "
          "| train time ratio | rule holds |")
    print("|---|---|---|---|---|---|")
    for n in names[1:]:
        u = rows[n]["rule"]
        if u is None:
            print(f"| {n} | – | – | – | – | not measured |")
            continue
        print(f"| {n} | {u['test_diff_mean']:+.2f} ± {u['test_diff_se']:.2f} "
              f"{'(beats)' if u['test_beats'] else ''} | {u['empty_diff_mean']:+.2f} ± "
              f"{u['empty_diff_se']:.2f} {'(beats)' if u['empty_beats'] else ''} "
              f"| {u['train_loss']} | {u['time_ratio']:.2f} | {'yes' if u['holds'] else 'no'} |")
    with open(f"{out}/summary.json", "w") as f:
        json.dump({"schema": "graspmap.variants/1", "baseline": names[0], "variants": rows}, f,
                  indent=2)
        f.write("\n")


main()
