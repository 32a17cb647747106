#!/usr/bin/env python3
"""docs/results.md is what examples/results_report.py makes of the committed CSVs (so no number
in it is typed by hand, and a CSV committed without `make -C examples paper-report` fails
here), and examples/seed_plot.py draws seeds as categories: each method's mean and 95%
interval as computed here, the same picture twice for the same CSV."""
import csv
import math
import os
import statistics
import subprocess
import sys
import tempfile

SOURCE = os.environ.get("QTE_SOURCE") or os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
EXAMPLES = os.path.join(SOURCE, "examples")
sys.path.insert(0, EXAMPLES)
import seed_plot  # noqa: E402


def main():
    made = subprocess.run([sys.executable, os.path.join(EXAMPLES, "results_report.py"),
                           os.path.join(EXAMPLES, "results")], capture_output=True, text=True, check=True).stdout
    with open(os.path.join(SOURCE, "docs", "results.md")) as f:
        committed = f.read()
    if made != committed:
        for n, (a, b) in enumerate(zip(made.splitlines(), committed.splitlines()), 1):
            if a != b:
                sys.exit(f"docs/results.md line {n} differs from the CSVs' (run make -C examples paper-report):\n"
                         f"  committed: {b}\n  from CSVs: {a}")
        sys.exit("docs/results.md and the CSVs' document differ in length (run make -C examples paper-report)")
    # Every takeaway directory has its section, with its table where it has runs.
    for name in sorted(os.listdir(os.path.join(EXAMPLES, "results"))):
        if name.startswith("takeaway"):
            assert f"`examples/results/{name}/`" in made or "No runs are committed yet" in made, name

    with tempfile.TemporaryDirectory() as d:
        finals = os.path.join(d, "finals.csv")
        rates = {"reach_prism c2farm-k1-t0": [0.4, 0.6, 0.5], "reach_prism qte-k10-t10": [0.7, 0.9, 0.8]}
        with open(finals, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["series", "seed", "success_rate"])
            for series, values in rates.items():
                for seed, rate in reversed(list(enumerate(values))):
                    w.writerow([series, seed, rate])
        columns = seed_plot.columns(finals)
        assert list(columns) == list(rates), columns
        assert columns["reach_prism c2farm-k1-t0"] == [(0, 0.4), (1, 0.6), (2, 0.5)], columns  # seeds in order
        mean, half = seed_plot.mean_interval(rates["reach_prism qte-k10-t10"])
        assert math.isclose(mean, 0.8) and math.isclose(half, 4.3026527 * statistics.stdev([0.7, 0.9, 0.8]) / math.sqrt(3),
                                                         rel_tol=1e-5), (mean, half)  # t(0.975, 2 df)
        pictures = []
        for k in range(2):
            out = os.path.join(d, f"seeds{k}.png")
            subprocess.run([sys.executable, os.path.join(EXAMPLES, "seed_plot.py"), "--title", "t", "--output", out, finals],
                           check=True)
            with open(out, "rb") as f:
                pictures.append(f.read())
        assert pictures[0].startswith(b"\x89PNG") and pictures[0] == pictures[1], "not the same PNG twice"
    print("docs/results.md matches the CSVs; seed_plot's means, intervals and bytes as expected")


if __name__ == "__main__":
    main()
