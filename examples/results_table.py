#!/usr/bin/env python3
"""Final success per method over seeds, from learn.sh's eval.csv files (one per run).

    results_table.py [--markdown] RUN.csv...

One row per label (method): the runs' final evaluations (the last eval_point of each run),
their mean and sample standard deviation, each run's successes with its Wilson 95% interval,
and the mean training wall-clock (train_s) where the CSVs have it. Standard library only.
"""
import argparse
import csv
import statistics
import sys
from collections import defaultdict


def final_rows(paths):
    runs = defaultdict(list)  # label -> final row of each run
    for path in paths:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        if not rows:
            sys.exit(f"{path}: no evaluation rows (expected learn.sh's eval.csv)")
        last = max(rows, key=lambda r: float(r["eval_point"]))
        runs[last["label"]].append(last)
    return runs


def summary(label, rows):
    rates = [float(r["success_rate"]) for r in rows]
    times = [float(r["train_s"]) for r in rows if r.get("train_s")]
    per_run = " ".join(
        f"s{r['seed']}:{r['successes']}/{r['episodes']} [{float(r['ci95_low']):.2f},{float(r['ci95_high']):.2f}]"
        for r in sorted(rows, key=lambda r: int(r["seed"])))
    return {
        "label": label,
        "runs": len(rows),
        "eval_point": rows[0]["eval_point"],
        "mean_success": f"{statistics.mean(rates):.3f}",
        "std_success": f"{statistics.stdev(rates):.3f}" if len(rates) > 1 else "",
        "mean_train_min": f"{statistics.mean(times) / 60:.1f}" if times else "",
        "per_run": per_run,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--markdown", action="store_true", help="a Markdown table instead of CSV")
    parser.add_argument("runs", nargs="+")
    args = parser.parse_args()
    table = [summary(label, rows) for label, rows in sorted(final_rows(args.runs).items())]
    columns = list(table[0].keys())
    if args.markdown:
        print("| " + " | ".join(columns) + " |")
        print("|" + "---|" * len(columns))
        for row in table:
            print("| " + " | ".join(str(row[c]) for c in columns) + " |")
    else:
        writer = csv.DictWriter(sys.stdout, fieldnames=columns, lineterminator="\n")
        writer.writeheader()
        writer.writerows(table)


if __name__ == "__main__":
    main()
