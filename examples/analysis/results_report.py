#!/usr/bin/env python3
"""The results document (docs/results.md) from the committed CSVs alone.

    results_report.py [--no-write] RESULTS_DIR > docs/results.md

A summary first: each takeaway's verdict, the paired comparison that answers it (mean
difference, 95% t interval, exact sign-flip p-value; SUMMARY below names the comparisons,
the numbers come from the CSVs). Then one section per takeaway directory of RESULTS_DIR
(examples/results/): the final success per method (results_table.py's table), every method
against C2F-ARM paired by seed (takeaway 3: every variant against K = 1), the processor time
by role where the runs recorded it, where the final agents went (failure_reasons) and the
ceiling of learning on their tasks (ceiling.sh, results/ceiling/), the pictures that
paper-report draws, the directory's reading.md (the paper's claim and our reading, written by
hand) and a link to its provenance.md (how the runs were made: processors, builds, resumed or
repeated runs; written by hand).

The document's tables keep at most MAX_COLUMNS columns; each links the CSV with all of them.
Those CSVs are paper-report's (table.csv, paired.csv, lookalikes.csv, acting_paired.csv,
depths.csv) but for the ones this script writes itself beside them (WRITTEN: takeaway 3's
ablation_paired.csv, acting.csv where networks acted with several K), unless --no-write.
Every number in the document comes from a CSV; a test checks the document and the CSVs this
script writes are up to date. Standard library only.
"""
import csv
import glob
import io
import os
import re
import statistics
import sys

import results_table

BASELINE = "c2farm-k1-t0"
MAX_COLUMNS = 8
# Section order and titles; a directory not listed here follows, titled by its name.
TITLES = {
    "takeaway1": "Takeaway 1: no loss where tree expansion is not needed (Task Set 1)",
    "takeaway2": "Takeaway 2: a gain under coarse ambiguity (Task Set 2)",
    "takeaway2-depths3": "Takeaway 2 at 3 depths (0.6 cm voxels, 1,000 pretraining steps; our variation, not published)",
    "takeaway2-depths3-pretrain100":
        "Takeaway 2 at 3 depths with takeaway 2's 100 pretraining steps (superseded: the finest depth breaks)",
    "takeaway2-long": "Takeaway 2's `lift_numbered_block` with 12.5 times the environment steps (5,000, 2 depths)",
    "takeaway3": "Takeaway 3: ablations on `reach_prism`",
    "takeaway4": "Takeaway 4: the real-world task in simulation (`reach_prism`, 1,200 processor seconds)",
    "takeaway4-unpaced": "Takeaway 4 without pacing (the earlier protocol, superseded)",
    "takeaway1-pick_up_cup-planned-to-grasp":
        "Takeaway 1's `pick_up_cup` with grasps planned to the grasp itself (superseded: the path swept through the cup)",
}
ROLES = ["demos", "pretrain", "learner", "actor", "other"]
# Takeaway 3 has no C2F-ARM run: its variants are paired against greedy K = 1, and acting-only
# expansion also against expansion in both (ABLATION_PAIRED, written by this script).
ABLATION = "takeaway3"
ABLATION_BASELINE = "qte-k1-t1"
ABLATION_ALSO = ("qte-k10-t0", "qte-k10-t10")  # (label, baseline)
ABLATION_PAIRED = "ablation_paired.csv"
# Comparisons with another baseline than C2F-ARM that the summary makes outside takeaway 3, each
# directory's written to a CSV of its own: {directory: (CSV, [(label, baseline)])}.
OTHER_BASELINES = {"takeaway2-depths3": ("released_paired.csv", [("qte-k3-t0", "qte-k10-t10")]),
                   "takeaway4": ("released_paired.csv", [("qte-k3-t0", "qte-k10-t10"), ("qte-k3-t0", "qte-k10-t0")])}
NAMES = {"c2farm-k1-t0": "C2F-ARM", "qte-k10-t10": "QTE", "qte-k10-t0": "QTE acting only",
         "qte-k1-t1": "K = 1", "qte-k3-t0": "QTE as released"}
# The summary: per takeaway, the paired comparisons that answer it: (takeaway, directory, CSV,
# task (None: the row of all tasks pooled), label, baseline, alpha, what we read in it, in
# words). The numbers and the test's verdict (p < alpha) come from the CSV's row.
SUMMARY = [
    ("1", "takeaway1", "paired.csv", None, "qte-k10-t10", BASELINE, 0.05,
     "No loss, as the paper says; two of the eight tasks are learned by neither method at this budget."),
    ("2", "takeaway2", "paired.csv", None, "qte-k10-t10", BASELINE, 0.05,
     "The paper's direction, not shown at these budgets: QTE ahead on average on the two tasks the "
     "methods learn; `setup_checkers` and `stack_blocks` are learned by neither."),
    ("2", "takeaway2-depths3", "paired.csv", None, "qte-k10-t10", BASELINE, 0.05,
     "Our variation (a third depth, 0.6 cm voxels): a gain, made by acting with tree expansion; "
     "C2F-ARM's own networks gain as much acting with K = 10."),
    ("2", "takeaway2-depths3", "paired.csv", "lift_numbered_block", "qte-k10-t10", BASELINE, 0.05,
     "The task of the pooled row above with the most seeds, on its own: a gain on every seed."),
    ("2", "takeaway2-depths3", "paired.csv", "lift_numbered_block", "qte-k3-t0", BASELINE, 0.05,
     "The authors' released configuration (K = 3 when acting, the double-DQN target), seeds 5-9: ahead "
     "of C2F-ARM on every seed; 5 pairs cannot give a p below 0.0625."),
    ("2", "takeaway2-depths3", "released_paired.csv", "lift_numbered_block", "qte-k3-t0", "qte-k10-t10", 0.05,
     "The released configuration against QTE as published (K = 10 in both), seeds 5-9: behind on 4 of "
     "5 seeds, level with C2F-ARM's own networks acting with K = 10."),
    ("2", "takeaway2-long", "paired.csv", "lift_numbered_block", "qte-k10-t10", BASELINE, 0.05,
     "With 12.5 times the experience both methods learn the digits; QTE ahead on every seed, by its "
     "acting (acting alike, the networks are level)."),
    ("3", "takeaway3", ABLATION_PAIRED, "reach_prism", "qte-k10-t10", ABLATION_BASELINE, 0.05,
     "Success rises with K, the paper's direction, over 3 seeds."),
    ("3", "takeaway3", ABLATION_PAIRED, "reach_prism", "qte-k10-t0", "qte-k10-t10", 0.05,
     "Under a processor budget, expanding only when acting does best (the paper ranks expanding in "
     "both first): its cheap target buys more learner steps."),
    ("4", "takeaway4", "paired.csv", "reach_prism", "qte-k10-t10", BASELINE, 0.025,
     "QTE as published: the paper's direction, not significant."),
    ("4", "takeaway4", "paired.csv", "reach_prism", "qte-k10-t0", BASELINE, 0.025,
     "QTE expanding only when acting: a gain on every seed; C2F-ARM's own networks acting with K = 10 "
     "gain too, the tree target does not."),
    ("4", "takeaway4", "paired.csv", "reach_prism", "qte-k3-t0", BASELINE, 0.05,
     "The authors' released configuration (K = 3 when acting, the double-DQN target), seeds 5-9: "
     "ahead on average, not significant (3 seeds of 5 ahead)."),
    ("4", "takeaway4", "released_paired.csv", "reach_prism", "qte-k3-t0", "qte-k10-t10", 0.05,
     "The released configuration against QTE as published (K = 10 in both), seeds 5-9: level."),
    ("4", "takeaway4", "released_paired.csv", "reach_prism", "qte-k3-t0", "qte-k10-t0", 0.05,
     "The released configuration against QTE acting only with K = 10, seeds 5-9: behind on every seed "
     "(-0.02 to -0.14); 5 pairs cannot give a p below 0.0625. Expanding 3 branches finds less than 10."),
]
FIGURE = "reach_prism_episode.gif"  # the README's figure, in RESULTS_DIR/../images/


def markdown(table, columns=None):
    if not table:
        return ""
    columns = columns or list(table[0].keys())
    if len(columns) > MAX_COLUMNS:
        raise ValueError(f"a table of {len(columns)} columns, more than {MAX_COLUMNS}: {columns}")
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(str(row.get(c, "")) for c in columns) + " |" for row in table]
    return "\n".join(lines)


def as_csv(table):
    """The table as results_table.py prints it without --markdown."""
    if not table:
        return ""
    out = io.StringIO()
    columns = list(dict.fromkeys(c for row in table for c in row))
    writer = csv.DictWriter(out, fieldnames=columns, restval="", lineterminator="\n")
    writer.writeheader()
    writer.writerows(table)
    return out.getvalue()


def interval(row):
    return f"{row['ci95_low']} to {row['ci95_high']}" if row["ci95_low"] else ""


def anchor(title):
    """GitHub's anchor of a heading."""
    return re.sub(r"[^\w\- ]", "", title.lower()).replace(" ", "-")


def link(name, path):
    """A link from docs/ to examples/results/PATH."""
    return f"[{name}](../examples/results/{path})"


def runs_of(directory):
    csvs = sorted(glob.glob(os.path.join(directory, "*-seed*.csv")))
    return csvs, results_table.final_rows(csvs) if csvs else {}


def ablation_paired(runs):
    """Takeaway 3's comparisons: every variant against ABLATION_BASELINE, and ABLATION_ALSO."""
    table = results_table.paired(runs, ABLATION_BASELINE)
    label, baseline = ABLATION_ALSO
    table += [row for row in results_table.paired(runs, baseline) if row["label"] == label]
    return table


def other_paired(name, runs):
    """The directory's comparisons with another baseline than C2F-ARM (OTHER_BASELINES)."""
    _, comparisons = OTHER_BASELINES[name]
    return [row for label, baseline in comparisons for row in results_table.paired(runs, baseline) if row["label"] == label]


def acting_paths(directory):
    failures = sorted(glob.glob(os.path.join(directory, "failures", "*.csv")))
    others = sorted(glob.glob(os.path.join(directory, "acting", "*.csv")))
    return failures, others


def written(results):
    """The CSVs this script writes: {path: text}."""
    files = {}
    for directory in sorted(glob.glob(os.path.join(results, "takeaway*/"))):
        name = os.path.basename(directory.rstrip("/"))
        if name == ABLATION:
            _, runs = runs_of(directory)
            files[os.path.join(directory, ABLATION_PAIRED)] = as_csv(ablation_paired(runs))
        if name in OTHER_BASELINES:
            _, runs = runs_of(directory)
            files[os.path.join(directory, OTHER_BASELINES[name][0])] = as_csv(other_paired(name, runs))
        failures, others = acting_paths(directory)
        if others:
            files[os.path.join(directory, "acting.csv")] = as_csv(results_table.acting(failures + others))
    return files


def comparison_row(results, directory, task, label, baseline):
    """The row of a paired table that SUMMARY names, as results_table.py computes it."""
    _, runs = runs_of(os.path.join(results, directory))
    table = ablation_paired(runs) if directory == ABLATION else results_table.paired(runs, baseline)
    for row in table:
        if (row["label"], row["baseline"]) == (label, baseline) and (
                row["task"] == task if task else row["task"].startswith("all ")):
            return row
    raise LookupError(f"{directory}: no paired row of {label} against {baseline} on {task or 'all tasks'}")


def test_verdict(row, alpha):
    """The sign-flip test's verdict at alpha, and whether the t interval excludes zero."""
    if float(row["sign_flip_p"]) < alpha:
        return "gain shown" if float(row["mean_difference"]) > 0 else "loss shown"
    excludes = row["ci95_low"] and (float(row["ci95_low"]) > 0 or float(row["ci95_high"]) < 0)
    return "not shown" + (" (the t interval excludes 0)" if excludes else "")


def holm_shown(p_values, alpha=0.05):
    """Holm's step-down correction over a family of tests: the i-th smallest p (from 1) is shown
    when it and every smaller one are at most alpha / (m - i + 1)."""
    order = sorted(range(len(p_values)), key=lambda i: p_values[i])
    shown = [False] * len(p_values)
    for rank, i in enumerate(order):
        if p_values[i] > alpha / (len(p_values) - rank):
            break
        shown[i] = True
    return shown


def summary(results, images):
    rows = []
    compared = [comparison_row(results, directory, task, label, baseline)
                for _, directory, _, task, label, baseline, _, _ in SUMMARY]
    holm = holm_shown([float(row["sign_flip_p"]) for row in compared])
    for (takeaway, directory, path, task, label, baseline, alpha, reading), row, shown in zip(SUMMARY, compared, holm):
        title = TITLES[directory]
        rows.append({
            "takeaway": f"[{takeaway}](#{anchor(title)})",
            "comparison": f"{NAMES.get(label, label)} (`{label}`) − {NAMES.get(baseline, baseline)} (`{baseline}`), "
                          + link(row["task"], f"{directory}/{path}"),
            "pairs": row["pairs"],
            "difference": row["mean_difference"],
            "95% t interval": interval(row),
            "sign-flip p (α)": f"{row['sign_flip_p']} ({alpha:g})",
            "test": test_verdict(row, alpha) + "; Holm: " + ("shown" if shown else "not shown"),
            "reading": reading,
        })
    out = ["## Summary\n",
           "C2F-ARM against C2F-ARM+QTE (QTE), each takeaway of the paper run at small budgets (200 to 1,600 "
           "learner steps a run, 2 processor cores), every run's final agent evaluated greedily on 50 held-out "
           "scenes. Each takeaway's answer, as the comparison that decides it:\n",
           markdown(rows),
           "\nEach comparison pairs the two methods' final success rates by seed (a pair: one task and seed; the "
           "same demonstrations and exploration scenes). `difference`: the mean over the pairs of the first "
           "method's rate minus the second's. `95% t interval`: Student's t interval of that mean. `sign-flip "
           "p`: the two-sided exact sign-flip permutation test of a zero mean difference (every one of the 2ⁿ "
           "sign assignments of the n paired differences; no assumption about their distribution), which with "
           "n pairs cannot fall below 2/2ⁿ: 0.25 for 3 pairs, 0.0625 for 5, 0.002 for 10. `test`: a gain or loss "
           "is shown where p < α; α is 0.05, and 0.025 for the two comparisons that answer takeaway 4, with one "
           "baseline (Bonferroni; the released configuration's rows are a further arm, at 0.05). `Holm`: the same tests corrected for making all of them, by Holm's step-down method at a "
           f"family-wise α of 0.05 over the {len(SUMMARY)} comparisons of this table (the i-th smallest p-value "
           f"is shown when it and every smaller one are at most 0.05 / ({len(SUMMARY)} − i + 1)). The pooled rows "
           "(`all N tasks`) weigh every pair the same, and their sign flips are per pair: each (task, seed) "
           "pair's difference changes sign on its own, as in a single task's test.\n"]
    if os.path.exists(os.path.join(images, FIGURE)):
        out.append(f"The README's figure, one greedy episode of QTE on `reach_prism`: "
                   f"[examples/images/{FIGURE}](../examples/images/{FIGURE}).\n")
    out.append("## Reading the tables\n\n"
               "Each section below shows, where its runs have them: the final success per method (each run's "
               "last evaluation; `per_run`: each seed's successes of 50 with its Wilson 95% interval); each "
               "method against C2F-ARM paired by seed (the statistics of the summary); the processor seconds by "
               "role up to the final evaluation (mean over runs, evaluation excluded); where the final agents "
               "went on the held-out scenes (episodes summed over runs: `success`, `target` (at the right object "
               "without succeeding), `distractor` (at a lookalike), `elsewhere`; `right_share`: of the tries at an "
               "object, the share at the right one); the ceiling of learning (`make -C examples ceiling`: the "
               "expert's own keyframes on the same scenes, discretized as the networks' targets and acted "
               "open-loop through the agents' planner, a reference for what the grid and planner allow; a network "
               "acting closed-loop may retry); the final networks acting with each K (`acting_k` 1: greedy); and "
               "which depth decided. A table that leaves columns out links the CSV with all of them. Each "
               "section ends with the paper's claim and our reading, and links how its runs were made "
               "(`provenance.md`).\n")
    return "\n".join(out)


def cpu_by_role(runs):
    """Mean processor seconds per role at the final evaluation, per task and label, for runs
    whose CSVs split cpu_s by role; and the (task, label)s left out."""
    table, without = [], []
    for (task, label), rows in sorted(runs.items()):
        if not all(rows[0].get(f"cpu_{role}_s") for role in ROLES):
            without.append((task, label))
            continue
        row = {"task": task, "label": label,
               "cpu_s": f"{statistics.mean(float(r['cpu_s']) for r in rows):.0f}"}
        for role in ROLES:
            row[role] = f"{statistics.mean(float(r[f'cpu_{role}_s']) for r in rows):.0f}"
        table.append(row)
    return table, without


def replayed(runs, failures):
    """The lookalike table with a row for every task and label of the final table: `runs` says
    how many of its runs' final agents were replayed, and which seeds were not."""
    seeds = {}
    for path in failures:
        with open(path, newline="") as f:
            for row in csv.DictReader(f):
                seeds.setdefault((results_table.task_of(path, row), row["label"]), set()).add(row["seed"])
    sums = {(r["task"], r["label"]): r for r in results_table.lookalikes(failures)}
    table = []
    for key in sorted(set(runs) | set(sums)):
        row = dict(sums.get(key, {"task": key[0], "label": key[1], **{c: "—" for c in ("success", "target", "distractor",
                                                                                     "elsewhere", "right_share")}}))
        expected = {r["seed"] for r in runs.get(key, [])}
        missing = sorted(expected - seeds.get(key, set()), key=int)
        if missing:
            done = len(expected) - len(missing)
            row["runs"] = (f"{done} of {len(expected)} (not replayed: " + ", ".join(f"s{s}" for s in missing) + ")"
                           if done else f"none of {len(expected)} replayed")
        table.append(row)
    return table


def ceiling_of(directory, tasks):
    """ceiling.sh's CSVs (results/ceiling/TASK_LABEL.csv) of `tasks` at the section's grid and
    planner (examples/Makefile's `ceiling`): the 3-depth ones for a 3-depth takeaway, those
    planned with the straight approach for takeaway2-long, else the tasks' own settings; none
    for runs planned without the approach their task now uses."""
    name = os.path.basename(directory.rstrip("/"))
    if "planned-to-grasp" in name:
        return []
    label = "keyframes-depths3" if "depths3" in name else "keyframes-approach" if name == "takeaway2-long" else "keyframes"
    paths = [os.path.join(directory, "..", "ceiling", f"{task}_{label}.csv") for task in sorted(tasks)]
    return [p for p in paths if os.path.exists(p)]


def ceiling_table(paths):
    """The ceiling's episodes by reason, the reasons of the failures in one column."""
    table = []
    for row in results_table.reasons(paths):
        failed = ", ".join(f"{reason} {row[reason]}" for reason in results_table.REASONS if int(row[reason] or 0))
        table.append({"task": row["task"], "keyframes": f"`{row['label']}`", "episodes": row["episodes"],
                      "success": row["success"], "failures by reason": failed or "none"})
    for row, path in zip(table, paths):  # one CSV a task; results_table.reasons sorts by task, as paths are
        assert os.path.basename(path).startswith(row["task"] + "_"), (path, row["task"])
        row["CSV"] = link(os.path.basename(path), "ceiling/" + os.path.basename(path))
    return table


def paired_narrow(table):
    return [{**row, "ci95": interval(row)} for row in table]


def see(directory, path, what, always=False):
    """A caption's pointer to the CSV with all of a table's columns: one this script writes, or
    one that is there."""
    if not always and not os.path.exists(os.path.join(directory, path)):
        return ""
    return f"; all columns, {what}, in {link(path, os.path.basename(directory.rstrip('/')) + '/' + path)}"


def left_out(without, runs):
    """The (task, label)s without a split of processor time, a task named alone where all its
    labels are left out."""
    words = []
    for task in sorted({task for task, _ in without}):
        labels = [label for t, label in without if t == task]
        words.append(f"`{task}`" if len(labels) == len([1 for t, _ in runs if t == task])
                     else f"`{task}` " + ", ".join(f"`{label}`" for label in labels))
    return ", ".join(words)


def section(directory, images):
    name = os.path.basename(directory.rstrip("/"))
    csvs, runs = runs_of(directory)
    out = [f"## {TITLES.get(name, name)}\n"]
    if not csvs:
        out.append("No runs are committed yet.\n")
    else:
        out.append(f"{len(csvs)} run{'s' if len(csvs) != 1 else ''} (`examples/results/{name}/`). Final success on "
                   "the held-out scenes, per method" + see(directory, "table.csv", "with the training wall-clock") + ":\n")
        out.append(markdown([results_table.summary(task, label, rows) for (task, label), rows in sorted(runs.items())],
                            ["task", "label", "runs", "env_steps", "learner_steps", "mean_success", "std_success",
                             "per_run"]))
        columns = ["task", "label", "pairs", "mean_success", "baseline_mean_success", "mean_difference", "ci95",
                   "sign_flip_p"]
        paired = results_table.paired(runs, BASELINE)
        if paired:
            out.append(f"\nEach method against C2F-ARM (`{BASELINE}`), paired by seed, and a method compared on several "
                       "tasks with all its pairs pooled (`all N tasks`)"
                       + see(directory, "paired.csv", "with each seed's difference and the pairs run on one processor")
                       + ":\n")
            out.append(markdown(paired_narrow(paired), columns))
        other = other_paired(name, runs) if name in OTHER_BASELINES else []
        if other:
            out.append("\nThe same runs against another baseline than C2F-ARM, paired by seed"
                       + see(directory, OTHER_BASELINES[name][0], "with each seed's difference and the pairs run on one "
                             "processor", always=True) + ":\n")
            out.append(markdown(paired_narrow(other), ["label", "baseline", "pairs", "mean_success",
                                                       "baseline_mean_success", "mean_difference", "ci95",
                                                       "sign_flip_p"]))
        if name == ABLATION:
            label, baseline = ABLATION_ALSO
            out.append(f"\nEach variant against greedy K = 1 (`{ABLATION_BASELINE}`), and `{label}` against `{baseline}`, "
                       "paired by seed" + see(directory, ABLATION_PAIRED, "with each seed's difference", always=True) + ":\n")
            out.append(markdown(paired_narrow(ablation_paired(runs)), ["label", "baseline", "pairs", "mean_success",
                                                                      "baseline_mean_success", "mean_difference",
                                                                      "ci95", "sign_flip_p"]))
        cpu, without = cpu_by_role(runs)
        if cpu:
            out.append("\nProcessor seconds by role up to the final evaluation, mean over runs, evaluation excluded"
                       + (f" (the runs of {left_out(without, runs)} are left out: their CSVs do not split it)"
                          if without else "") + ":\n")
            out.append(markdown(cpu))
        failures, others = acting_paths(directory)
        if failures:
            out.append("\nWhere the final agents went on the held-out scenes, episodes summed over the runs whose "
                       "final agents were replayed (`runs`)" + see(directory, "lookalikes.csv", "with the episodes and "
                                                                  "the tries at an object") + ":\n")
            out.append(markdown(replayed(runs, failures), ["task", "label", "runs", "success", "target", "distractor",
                                                            "elsewhere", "right_share"]))
        ceiling = ceiling_of(directory, {task for task, _ in runs})
        if ceiling:
            out.append("\nThe ceiling of learning: the discretized expert acting open-loop on the same held-out "
                       "scenes, one row a task:\n")
            out.append(markdown(ceiling_table(ceiling)))
        if others:
            out.append("\nTrained by one method, acting with each K: the final networks on the same held-out scenes, "
                       "episodes summed over runs" + see(directory, "acting.csv", "with the runs, episodes and "
                                                                               "failed actions", always=True) + ":\n")
            out.append(markdown(results_table.acting(failures + others),
                                ["task", "label", "acting_k", "success", "target", "distractor", "elsewhere",
                                 "success_rate"]))
            compared = results_table.acting_paired(failures + others, BASELINE)
            if compared:
                out.append("\nThe same cells paired by seed: each network acting with the larger K against itself "
                           "acting with the smaller, and, acting alike, each method's networks against C2F-ARM's"
                           + see(directory, "acting_paired.csv", "with the means and each seed's difference") + ":\n")
                out.append(markdown(paired_narrow(compared), ["task", "trained_by", "acting_k", "against", "pairs",
                                                              "mean_difference", "ci95", "sign_flip_p"]))
    decided = sorted(glob.glob(os.path.join(directory, "depths", "*.csv")))
    if decided:
        out.append("\nWhich depth decided: where the final agents' chosen voxels lay at each depth, on the "
                   "held-out scenes (actions summed over runs; `depth0_argmax`: depth 0's own best voxel, where "
                   "K = 1 goes; `overruled`: the actions whose depth-0 voxel is not depth 0's best, a finer depth "
                   "having chosen another branch, and `overruled_argmax` where depth 0 alone would have gone)"
                   + see(directory, "depths.csv", "with K and the other shares") + ":\n")
        out.append(markdown(results_table.depths(decided), ["task", "label", "row", "actions", "target", "lookalike",
                                                            "elsewhere", "target_share"]))
    pictures = [p for p in (f"{name}.png", f"{name}_curves.png", f"{name}_k.png")
                if os.path.exists(os.path.join(images, p))]
    if pictures:
        out.append("\n" + " ".join(f"![{p}](../examples/images/{p})" for p in pictures) + "\n")
    reading = os.path.join(directory, "reading.md")
    if os.path.exists(reading):
        with open(reading) as f:
            out.append("\n" + f.read().strip() + "\n")
    if os.path.exists(os.path.join(directory, "provenance.md")):
        out.append("How these runs were made (processors, builds, resumed or repeated runs): "
                   + link(f"{name}/provenance.md", f"{name}/provenance.md") + ".\n")
    return "\n".join(out)


def main():
    args = sys.argv[1:]
    write = "--no-write" not in args
    args = [a for a in args if a != "--no-write"]
    if len(args) != 1:
        sys.exit(__doc__.strip().splitlines()[2].strip())
    results = args[0]
    images = os.path.join(results, "..", "images")
    if write:
        for path, text in written(results).items():
            if not os.path.exists(path) or open(path).read() != text:
                with open(path, "w") as f:
                    f.write(text)
    names = sorted(os.path.basename(d.rstrip("/")) for d in glob.glob(os.path.join(results, "takeaway*/")))
    names.sort(key=lambda n: (list(TITLES).index(n) if n in TITLES else len(TITLES), n))
    print("# Results: the paper's four takeaways\n")
    print("Generated by `make -C examples paper-report` from the CSVs under `examples/results/` "
          "(do not edit by hand: a test compares it with the CSVs). Success rates are over 50 held-out scenes "
          "that no run explored or was shown; seeds pair runs of different methods on the same demonstrations "
          "and exploration scenes.\n")
    print(summary(results, images))
    for name in names:
        print(section(os.path.join(results, name), images))


if __name__ == "__main__":
    main()
