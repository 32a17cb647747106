#!/usr/bin/env python3
"""Final success per method over seeds, from learn.sh's eval.csv files (one per run).

    results_table.py [--markdown | --finals | --k-ablation] RUN.csv...
    results_table.py --tasks RUN.csv...
    results_table.py --curves --task TASK RUN.csv...
    results_table.py --failures FAILURES.csv...
    results_table.py --lookalikes FAILURES.csv...
    results_table.py --paired BASELINE [--markdown] RUN.csv...
    results_table.py --acting FAILURES.csv...
    results_table.py --acting-paired BASELINE [--markdown] FAILURES.csv...
    results_table.py --reasons FAILURES.csv...
    results_table.py --depths DEPTHS.csv...

One row per task and label (method): the runs' final evaluations (the last eval_point of each run):
the environment and learner steps they had taken (means), their success's mean and sample
standard deviation, each run's successes with its Wilson 95% interval,
and the mean training wall-clock (train_s) where the CSVs have it. --finals prints each run's
final row instead (for a picture of final success per seed); --k-ablation the final rows of the
runs that expand the same K when acting and in the target (labels qte-kK-tK), with K as a
column (for a picture of success against K). The task comes from the file's name as
examples/Makefile writes it, TASK_LABEL-seedN.csv (empty for other names, such as eval.csv);
--finals adds `series`, "TASK LABEL", for a picture of several tasks. --tasks lists the runs'
tasks; --curves every evaluation of TASK's runs, with the task, for a picture of learning curves
(mean +- std over seeds at each eval_point). --failures joins the
runs' failure_reasons CSVs (results/<takeaway>/failures/, named the same way) into one with the
task as first column; --lookalikes sums them per task and label: of the episodes that went for an
object (success, target or distractor), the share that went for the right one (success or
target), to set beside the chance of picking among the task's lookalikes. --paired BASELINE
compares every other label with the label BASELINE, paired by seed (the seeds both have): the
mean difference in final success, its 95% interval (Student's t over the paired differences),
and the two-sided p-value of the exact sign-flip permutation test (all 2^n sign assignments of
the n differences; the test makes no assumption about their distribution), and how many of the
pairs were made on one processor (pairs_one_processor: both runs' machines/ files, learn.sh's
record copied beside the CSVs, name the same model and vector width; under a processor-time
budget a faster processor buys more learner steps). A label compared on several tasks gets a
further row, "all N tasks", of all its (task, seed) pairs pooled: the question of a suite ("no
loss across Task Set 1") rather than of one task (every pair weighing the same). --acting sums
failure_reasons CSVs per task, label (how the networks were trained) and the K they acted with:
from the name's _act-kK suffix (learn.sh's ALSO_ACT_K), else the label's own (LABEL = ...-kK-...).
--acting-paired BASELINE compares those cells paired by seed, with --paired's statistics: each
network acting with its larger K against the same network with its smaller (what acting with
tree expansion adds), and at each acting K every label's networks against BASELINE's (what
training with a method adds).
--reasons sums the episodes' reasons (why each failed: failure_reasons.py's columns) the same
way, leaving out CSVs written before the reasons; `pushed` is blank where a run's CSV predates it
(its pushes are among its grasp_missed). --depths sums depth_decisions.py's
tables (which depth decided, results/<takeaway>/depths/) per task, label, K and row over runs,
the shares from the sums. --failures keeps every file's columns (an
older file's reason columns are empty).
Standard library only.
"""
import argparse
import csv
import itertools
import math
import os
import re
import statistics
import sys
from collections import Counter, defaultdict
from fractions import Fraction


def label_settings(label):
    """(METHOD, ACT_K, TARGET_K) of a run's label as examples/common.sh's run_label writes it,
    METHOD-kACT_K-tTARGET_K; None for other labels (adaptive K's, an analysis's own)."""
    m = re.fullmatch(r"(.+)-k(\d+)-t(\d+)", label)
    return (m.group(1), int(m.group(2)), int(m.group(3))) if m else None


def task_of(path, row):
    """TASK of TASK_LABEL-seedN.csv (examples/Makefile's results, LABEL the row's) or of
    TASK_LABEL.csv (an analysis without a seed, as ceiling.sh's), else ''."""
    m = re.fullmatch(rf"(.*)_{re.escape(row['label'])}(-seed\d+)?\.csv", os.path.basename(path))
    return m.group(1) if m else ""


def failures(paths):
    """Every run's failure_reasons rows under one header, each with its run's task: the columns
    of all of them in the order first seen (older files, without the reason columns, leave them
    empty)."""
    rows, columns = [], ["task"]
    for path in paths:
        with open(path, newline="") as f:
            for row in csv.DictReader(f):
                columns += [c for c in row if c not in columns]
                rows.append({"task": task_of(path, row), **row})
    if rows:
        writer = csv.DictWriter(sys.stdout, fieldnames=columns, restval="", lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)


# failure_reasons.py's reasons, the columns after failed_actions (success has its own column);
# those added later (LATER_REASONS) count 0 in the CSVs written before them, but for those that
# split an older reason (SPLIT_REASONS), which are left blank.
REASONS = ["wrong_object", "pushed", "grasp_missed", "dropped", "goal_in_collision", "ik_failed", "no_path",
           "start_in_collision", "outside_workspace", "invalid_pose", "approach_blocked", "trajectory_refused",
           "collision", "other_failure", "out_of_steps"]
LATER_REASONS = {"approach_blocked", "pushed"}
# Later reasons that split an older one (a push was a grasp_missed before): summed only where
# every run has them, else left blank.
SPLIT_REASONS = {"pushed"}


def reasons(paths):
    """Per task, label and acting K (as --acting), the episodes' reasons summed over runs; the
    runs whose CSVs predate the reasons are left out."""
    sums = defaultdict(lambda: defaultdict(int))
    for path in paths:
        suffix = re.search(r"_act-k(\d+)\.csv$", path)
        with open(path, newline="") as f:
            for row in csv.DictReader(f):
                if not all(row.get(r) for r in REASONS if r not in LATER_REASONS):
                    continue
                own = label_settings(row["label"])
                act_k = suffix.group(1) if suffix else str(own[1]) if own else ""
                total = sums[(task_of(re.sub(r"_act-k\d+\.csv$", ".csv", path), row), row["label"], act_k)]
                total["runs"] += 1
                for column in ["episodes", "success"] + REASONS:
                    total[column] += int(row.get(column) or 0)
                for column in SPLIT_REASONS:
                    total["without " + column] += not row.get(column)
    return [{"task": task, "label": label, "acting_k": k, **{c: t[c] for c in ["runs", "episodes", "success"] + REASONS},
             **{c: "" for c in SPLIT_REASONS if t["without " + c]}}
            for (task, label, k), t in sorted(sums.items(), key=lambda kv: (kv[0][0], kv[0][1], int(kv[0][2] or 0)))]


def lookalikes(paths):
    """Per task and label, the failure kinds summed over runs and the share of tries at an
    object that went for the right one (rows of dicts)."""
    sums = defaultdict(lambda: defaultdict(int))
    for path in paths:
        with open(path, newline="") as f:
            for row in csv.DictReader(f):
                total = sums[(task_of(path, row), row["label"])]
                total["runs"] += 1
                for kind in ("episodes", "success", "target", "distractor", "elsewhere"):
                    total[kind] += int(row[kind])
    table = []
    for (task, label), t in sorted(sums.items()):
        tries = t["success"] + t["target"] + t["distractor"]
        table.append({"task": task, "label": label, **{k: t[k] for k in ("runs", "episodes", "success", "target",
                                                                        "distractor", "elsewhere")},
                      "tries_at_an_object": tries,
                      "right_share": f"{(t['success'] + t['target']) / tries:.3f}" if tries else ""})
    return table


def depths(paths):
    """depth_decisions.py's tables (results/<takeaway>/depths/TASK_LABEL-seedN.csv) summed per
    task, label, K and row over runs, with the shares of the sums."""
    sums = defaultdict(lambda: defaultdict(int))
    for path in paths:
        with open(path, newline="") as f:
            for row in csv.DictReader(f):
                total = sums[(task_of(path, row), row["label"], row["k"], row["row"])]
                total["runs"] += 1
                for place in ("actions", "target", "lookalike", "elsewhere"):
                    total[place] += int(row[place])
    rows = ["depth0", "depth1", "depth2", "depth0_argmax", "overruled", "overruled_argmax"]
    order = lambda kv: (kv[0][0], kv[0][1], kv[0][2], rows.index(kv[0][3]) if kv[0][3] in rows else len(rows))
    return [{"task": task, "label": label, "k": k, "row": name, **t,
             **{f"{p}_share": f"{t[p] / t['actions']:.3f}" if t["actions"] else "" for p in ("target", "lookalike",
                                                                                            "elsewhere")}}
            for (task, label, k, name), t in sorted(sums.items(), key=order)]


def acting_rows(paths):
    """(task, label, acting K, row) of each failure_reasons row: the K from the name's _act-kK
    suffix, else the label's own."""
    for path in paths:
        suffix = re.search(r"_act-k(\d+)\.csv$", path)
        with open(path, newline="") as f:
            for row in csv.DictReader(f):
                own = label_settings(row["label"])
                act_k = suffix.group(1) if suffix else str(own[1]) if own else ""
                yield task_of(re.sub(r"_act-k\d+\.csv$", ".csv", path), row), row["label"], act_k, row


def acting(paths):
    """Trained-by x acting-with: failure kinds summed per task, label and acting K."""
    sums = defaultdict(lambda: defaultdict(int))
    for task, label, act_k, row in acting_rows(paths):
        total = sums[(task, label, act_k)]
        total["runs"] += 1
        for kind in ("episodes", "success", "target", "distractor", "elsewhere", "failed_actions"):
            total[kind] += int(row.get(kind) or 0)
    return [{"task": task, "label": label, "acting_k": k, **{c: t[c] for c in ("runs", "episodes", "success", "target",
                                                                              "distractor", "elsewhere", "failed_actions")},
             "success_rate": f"{t['success'] / t['episodes']:.3f}" if t["episodes"] else ""}
            for (task, label, k), t in sorted(sums.items(), key=lambda kv: (kv[0][0], kv[0][1], int(kv[0][2] or 0)))]


def acting_paired(paths, baseline):
    """The trained-by x acting-with cells compared paired by seed: per network (label), acting
    with its larger K against its smaller; per acting K, each label's networks against
    `baseline`'s."""
    rate = defaultdict(dict)  # (task, label, acting K) -> seed -> success rate
    for task, label, act_k, row in acting_rows(paths):
        if act_k:  # an adaptive K's label names no K to pair by
            rate[(task, label, act_k)][row["seed"]] = int(row["success"]) / int(row["episodes"])
    table = []

    def compare(task, label, act_k, against, cell, other):
        seeds = sorted(set(rate[cell]) & set(rate[other]), key=int)
        if not seeds:
            return
        d = [rate[cell][s] - rate[other][s] for s in seeds]
        table.append({"task": task, "trained_by": label, "acting_k": act_k, "against": against, "pairs": len(d),
                      "mean_success": f"{statistics.mean(rate[cell][s] for s in seeds):.3f}",
                      "against_mean_success": f"{statistics.mean(rate[other][s] for s in seeds):.3f}",
                      **paired_statistics(d), "per_seed": " ".join(f"s{s}:{x:+.2f}" for s, x in zip(seeds, d))})

    for task, label in sorted({(t, l) for t, l, _ in rate}):
        ks = sorted({k for t, l, k in rate if (t, l) == (task, label)}, key=int)
        if len(ks) > 1:
            compare(task, label, ks[-1], f"{label} acting with K = {ks[0]}", (task, label, ks[-1]), (task, label, ks[0]))
    for task, label, act_k in sorted(rate, key=lambda c: (c[0], int(c[2]), c[1])):
        if label != baseline and (task, baseline, act_k) in rate:
            compare(task, label, act_k, f"{baseline} acting with K = {act_k}", (task, label, act_k),
                    (task, baseline, act_k))
    return table


def evaluations(paths):
    """(task, rows) of each run, its rows in the file's order."""
    for path in paths:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        if not rows:
            sys.exit(f"{path}: no evaluation rows (expected learn.sh's eval.csv)")
        yield task_of(path, rows[0]), rows


def curves(paths, task):
    """Every evaluation of the runs of `task`, by label, seed and eval_point."""
    rows = [{"task": t, **row} for t, run_rows in evaluations(paths) if t == task for row in run_rows]
    rows.sort(key=lambda r: (r["label"], int(r["seed"]), float(r["eval_point"])))
    if not rows:
        sys.exit(f"no runs of task '{task}' among the {len(paths)} given")
    # The columns every run has (runs of one takeaway may differ in the rest: CPU by role), so
    # that the tasks' curves, printed one after another, share one header.
    fields = ["task", "label", "seed", "env_steps", "eval_point", "episodes", "successes", "success_rate"]
    writer = csv.DictWriter(sys.stdout, fieldnames=fields, lineterminator="\n", extrasaction="ignore")
    writer.writeheader()
    writer.writerows(rows)


def processor_of(path):
    """The processor a run's CSV was made on: "model,vector_isa" from machines/NAME beside it
    (examples/Makefile copies learn.sh's machine file there: started_utc,model,vector_isa,cores, a
    line more for each other processor it was resumed on), "mixed" if its lines differ, "" where
    none was recorded."""
    machine = os.path.join(os.path.dirname(path), "machines", os.path.basename(path))
    try:
        with open(machine) as f:
            starts = {",".join(line.strip().split(",")[1:-1]) for line in f if line.strip()}
    except OSError:
        return ""
    return starts.pop() if len(starts) == 1 else ("mixed" if starts else "")


def final_rows(paths):
    runs = defaultdict(list)  # (task, label) -> final row of each run, in the order given
    for path, (task, rows) in zip(paths, evaluations(paths)):
        last = max(rows, key=lambda r: float(r["eval_point"]))
        runs[(task, last["label"])].append({"task": task, **last, "processor": processor_of(path)})
    return runs


def summary(task, label, rows):
    rates = [float(r["success_rate"]) for r in rows]
    times = [float(r["train_s"]) for r in rows if r.get("train_s")]
    per_run = " ".join(
        f"s{r['seed']}:{r['successes']}/{r['episodes']} [{float(r['ci95_low']):.2f},{float(r['ci95_high']):.2f}]"
        for r in sorted(rows, key=lambda r: int(r["seed"])))
    return {
        "task": task,
        "label": label,
        "runs": len(rows),
        "env_steps": f"{statistics.mean(float(r['env_steps']) for r in rows):.0f}",
        "learner_steps": f"{statistics.mean(float(r['train_step']) for r in rows):.0f}",
        "mean_success": f"{statistics.mean(rates):.3f}",
        "std_success": f"{statistics.stdev(rates):.3f}" if len(rates) > 1 else "",
        "mean_train_min": f"{statistics.mean(times) / 60:.1f}" if times else "",
        "per_run": per_run,
    }


def t_quantile(p, df):
    """The p-quantile of Student's t with df degrees of freedom (numerical: the density
    integrated by Simpson's rule, the quantile found by bisection)."""
    log_c = math.lgamma((df + 1) / 2) - math.lgamma(df / 2) - 0.5 * math.log(df * math.pi)

    def cdf(x):  # P(T <= x) for x >= 0
        n = 2000
        h = x / n
        f = [math.exp(log_c - (df + 1) / 2 * math.log1p((i * h) ** 2 / df)) for i in range(n + 1)]
        return 0.5 + h / 3 * (f[0] + f[-1] + 4 * sum(f[1:-1:2]) + 2 * sum(f[2:-1:2]))

    low, high = 0.0, 1.0
    while cdf(high) < p:
        high *= 2
    for _ in range(60):
        mid = (low + high) / 2
        low, high = (mid, high) if cdf(mid) < p else (low, mid)
    return (low + high) / 2


def sign_flip_p(differences):
    """Two-sided p-value of the exact sign-flip permutation test of a zero mean difference: the
    share of the 2^n sign assignments whose |sum| reaches the observed one. Success rates are
    counts over episodes, so the differences are fractions whose common denominator makes them
    integers, and the sums of all assignments are counted by convolution for any number of
    pairs; differences that are no such fractions are enumerated (at most 20 of them)."""
    fractions = [Fraction(d).limit_denominator(10000) for d in differences]
    if any(abs(float(f) - d) > 1e-9 for f, d in zip(fractions, differences)):
        if len(differences) > 20:
            raise ValueError(f"{len(differences)} differences that are no fractions of at most 10,000 episodes: "
                             "too many to enumerate their 2^n sign assignments")
        observed = abs(sum(differences))
        count = 0
        for signs in itertools.product((1, -1), repeat=len(differences)):
            count += abs(sum(s * d for s, d in zip(signs, differences))) >= observed - 1e-12
        return count / 2 ** len(differences)
    scale = math.lcm(*(f.denominator for f in fractions))
    grid = [int(f * scale) for f in fractions]
    sums = {0: 1}  # sum of the signed differences -> number of sign assignments giving it
    for g in grid:
        following = Counter()
        for total, count in sums.items():
            following[total + g] += count
            following[total - g] += count
        sums = following
    observed = abs(sum(grid))
    return sum(count for total, count in sums.items() if abs(total) >= observed) / 2 ** len(grid)


def paired_statistics(differences):
    """The mean of paired differences, its 95% interval (Student's t; none from one pair) and the
    exact sign-flip p-value."""
    mean = statistics.mean(differences)
    n = len(differences)
    half = t_quantile(0.975, n - 1) * statistics.stdev(differences) / math.sqrt(n) if n > 1 else None
    return {"mean_difference": f"{mean:+.3f}",
            "ci95_low": f"{mean - half:+.3f}" if half is not None else "",
            "ci95_high": f"{mean + half:+.3f}" if half is not None else "",
            "sign_flip_p": f"{sign_flip_p(differences):.4f}"}


def paired(runs, baseline):
    """Each label against `baseline` on the same task, paired by seed."""
    table = []
    for (task, label), rows in sorted(runs.items()):
        base = {r["seed"]: r for r in runs.get((task, baseline), [])}
        if label == baseline or not base:
            continue
        pairs = [(r, base[r["seed"]]) for r in sorted(rows, key=lambda r: int(r["seed"])) if r["seed"] in base]
        if not pairs:
            continue
        d = [float(a["success_rate"]) - float(b["success_rate"]) for a, b in pairs]
        one_processor = sum(a["processor"] not in ("", "mixed") and a["processor"] == b["processor"] for a, b in pairs)
        table.append({
            "task": task,
            "label": label,
            "baseline": baseline,
            "pairs": len(d),
            "mean_success": f"{statistics.mean(float(a['success_rate']) for a, _ in pairs):.3f}",
            "baseline_mean_success": f"{statistics.mean(float(b['success_rate']) for _, b in pairs):.3f}",
            **paired_statistics(d),
            "pairs_one_processor": one_processor,
            "per_seed": " ".join(f"s{a['seed']}:{x:+.2f}" for (a, _), x in zip(pairs, d)),
            "rates": [(float(a["success_rate"]), float(b["success_rate"])) for a, b in pairs],
        })
    # A label compared on several tasks: all its (task, seed) pairs pooled, the question of a
    # suite ("no loss across Task Set 1") rather than of one task; every pair weighs the same,
    # so a task with more seeds counts more.
    for label in sorted({row["label"] for row in table}):
        rows = [row for row in table if row["label"] == label]
        if len(rows) < 2:
            continue
        rates = [pair for row in rows for pair in row["rates"]]
        d = [a - b for a, b in rates]
        table.append({
            "task": f"all {len(rows)} tasks",
            "label": label,
            "baseline": baseline,
            "pairs": len(d),
            "mean_success": f"{statistics.mean(a for a, _ in rates):.3f}",
            "baseline_mean_success": f"{statistics.mean(b for _, b in rates):.3f}",
            **paired_statistics(d),
            "pairs_one_processor": sum(row["pairs_one_processor"] for row in rows),
            "per_seed": "",
            "rates": rates,
        })
    for row in table:
        del row["rates"]
    return table


def print_table(table, markdown):
    if not table:
        return
    # Rows from runs of different ages can have different columns (older CSVs lack the
    # processor split): every column any row has, blank where a row lacks it.
    columns = list(dict.fromkeys(c for row in table for c in row))
    if markdown:
        print("| " + " | ".join(columns) + " |")
        print("|" + "---|" * len(columns))
        for row in table:
            print("| " + " | ".join(str(row.get(c, "")) for c in columns) + " |")
    else:
        writer = csv.DictWriter(sys.stdout, fieldnames=columns, restval="", lineterminator="\n")
        writer.writeheader()
        writer.writerows(table)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--markdown", action="store_true", help="a Markdown table instead of CSV")
    parser.add_argument("--finals", action="store_true", help="each run's final row, as CSV")
    parser.add_argument("--k-ablation", action="store_true", help="final rows of the qte-kK-tK runs with K, as CSV")
    parser.add_argument("--failures", action="store_true", help="join failure_reasons CSVs, with the task")
    parser.add_argument("--lookalikes", action="store_true",
                        help="failure_reasons CSVs summed per task and label, with the right share of tries")
    parser.add_argument("--tasks", action="store_true", help="the runs' tasks, one a line")
    parser.add_argument("--curves", action="store_true", help="every evaluation of --task's runs, as CSV")
    parser.add_argument("--task", help="the task of --curves")
    parser.add_argument("--paired", metavar="BASELINE", help="every other label against BASELINE, paired by seed")
    parser.add_argument("--acting", action="store_true",
                        help="failure_reasons CSVs summed per task, label and the K the networks acted with")
    parser.add_argument("--acting-paired", metavar="BASELINE",
                        help="the --acting cells compared paired by seed: each network's larger K against its "
                             "smaller, and at each K every label against BASELINE")
    parser.add_argument("--depths", action="store_true",
                        help="depth_decisions.py's tables summed per task, label, K and row")
    parser.add_argument("--reasons", action="store_true",
                        help="failure_reasons CSVs' reasons summed per task, label and acting K")
    parser.add_argument("runs", nargs="+")
    args = parser.parse_args()
    if args.reasons:
        print_table(reasons(args.runs), args.markdown)
        return
    if args.failures:
        failures(args.runs)
        return
    if args.lookalikes:
        print_table(lookalikes(args.runs), args.markdown)
        return
    if args.acting:
        print_table(acting(args.runs), args.markdown)
        return
    if args.depths:
        print_table(depths(args.runs), args.markdown)
        return
    if args.acting_paired:
        print_table(acting_paired(args.runs, args.acting_paired), args.markdown)
        return
    if args.tasks:
        print("\n".join(sorted({task for task, _ in evaluations(args.runs)})))
        return
    if args.curves:
        if not args.task:
            parser.error("--curves needs --task")
        curves(args.runs, args.task)
        return
    runs = final_rows(args.runs)
    if args.finals or args.k_ablation:
        rows = [{"series": " ".join(filter(None, key)), **row}
                for key in sorted(runs) for row in sorted(runs[key], key=lambda r: int(r["seed"]))]
        if args.k_ablation:
            same_k = []
            for row in rows:
                settings = label_settings(row["label"])
                if settings and settings[0] == "qte" and settings[1] == settings[2]:
                    same_k.append({"k": str(settings[1]), **{c: v for c, v in row.items() if c != "series"}})
            rows = same_k
            rows.sort(key=lambda r: (int(r["k"]), int(r["seed"])))
            if not rows:
                return
        print_table(rows, markdown=False)
        return
    if args.paired:
        print_table(paired(runs, args.paired), args.markdown)
        return
    print_table([summary(task, label, rows) for (task, label), rows in sorted(runs.items())], args.markdown)


if __name__ == "__main__":
    main()
