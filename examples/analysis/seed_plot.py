#!/usr/bin/env python3
"""Final success per seed, a column per method: each seed a point (its number beside it), the
methods' means with their 95% intervals (Student's t over the seeds) as bars.

    seed_plot.py --title TITLE --output OUT.png FINALS.csv

FINALS.csv: results_table.py --finals (columns series, seed, success_rate). Seeds are
categories, not an axis: a picture of runs paired by seed, not of a trend over seeds. Drawn
with matplotlib (Debian's python3-matplotlib), with no font or style from outside it.
"""
import argparse
import csv
import math
import statistics
from collections import defaultdict

import results_table


def columns(path):
    """series -> [(seed, success_rate)], in the file's order of series, seeds sorted."""
    by_series = defaultdict(list)
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            by_series[row["series"]].append((int(row["seed"]), float(row["success_rate"])))
    return {series: sorted(points) for series, points in by_series.items()}


def mean_interval(rates):
    """Mean and the half-width of its 95% t-interval (0 for one seed)."""
    mean = statistics.mean(rates)
    if len(rates) < 2:
        return mean, 0.0
    return mean, results_table.t_quantile(0.975, len(rates) - 1) * statistics.stdev(rates) / math.sqrt(len(rates))


def draw(series, title, output):
    import matplotlib
    matplotlib.use("Agg")  # no display
    import matplotlib.pyplot as plt

    names = list(series)
    fig, ax = plt.subplots(figsize=(max(4.0, 1.6 * len(names) + 1.5), 4.2), dpi=100)
    seeds = sorted({seed for points in series.values() for seed, _ in points})
    where = defaultdict(list)  # (task, seed) -> its points, column by column: a faint line pairs them
    for x, name in enumerate(names):
        points = series[name]
        for seed, rate in points:
            k = seeds.index(seed)  # a seed keeps its place in every column
            dx = 0.25 * (k - (len(seeds) - 1) / 2) / max(1, len(seeds) - 1)
            where[(name.split(" ")[0], seed)].append((x - 0.15 + dx, rate))
            ax.plot(x - 0.15 + dx, rate, "o", color=f"C{x}", alpha=0.75, markersize=5)
            ax.annotate(str(seed), (x - 0.15 + dx, rate), textcoords="offset points", xytext=(0, 5),
                        ha="center", fontsize=6, color="0.35")
        mean, half = mean_interval([rate for _, rate in points])
        ax.errorbar(x + 0.2, mean, yerr=half, fmt="s", color="black", capsize=4, markersize=5)
        ax.annotate(f"{mean:.2f}", (x + 0.2, mean), textcoords="offset points", xytext=(8, -3), fontsize=8)
    for line in where.values():
        ax.plot([p[0] for p in line], [p[1] for p in line], "-", color="0.6", alpha=0.35, linewidth=0.8)
    ax.set_xticks(range(len(names)))
    ax.set_xticklabels([name.replace(" ", "\n") for name in names], fontsize=8)
    ax.set_xlim(-0.7, len(names) - 0.3)
    ax.set_ylim(-0.02, 1.05)
    ax.set_ylabel("final success rate (50 held-out scenes)")
    ax.set_title(title + "\npoints: seeds (numbered; a line joins a seed's runs of a task); squares: mean and 95% interval",
                 fontsize=9)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(output, metadata={"Software": None})  # no version stamp: same CSV, same bytes
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--title", default="")
    parser.add_argument("--output", required=True)
    parser.add_argument("finals")
    args = parser.parse_args()
    draw(columns(args.finals), args.title, args.output)


if __name__ == "__main__":
    main()
