#!/usr/bin/env python3
"""The results document (docs/results.md) from the committed CSVs alone.

    results_report.py RESULTS_DIR > docs/results.md

One section per takeaway directory of RESULTS_DIR (examples/results/): the final success per
method (results_table.py's table), every method against C2F-ARM paired by seed (mean
difference, 95% interval, exact sign-flip p-value), the processor time by role where the runs
recorded it, where the final agents went (failure_reasons) and the ceiling of learning on their
tasks (ceiling.sh, results/ceiling/), the pictures that paper-report
draws, and the directory's reading.md (the paper's claim and our reading, written by hand).
Every number in the document comes from a CSV; a test checks the document is up to date.
Standard library only.
"""
import glob
import os
import statistics
import sys

import results_table

BASELINE = "c2farm-k1-t0"
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


def markdown(table, columns=None):
    if not table:
        return ""
    columns = columns or list(table[0].keys())
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(str(row[c]) for c in columns) + " |" for row in table]
    return "\n".join(lines)


def cpu_by_role(runs):
    """Mean processor seconds per role at the final evaluation, per task and label, for runs
    whose CSVs split cpu_s by role."""
    table = []
    for (task, label), rows in sorted(runs.items()):
        if not all(rows[0].get(f"cpu_{role}_s") for role in ROLES):
            continue
        row = {"task": task, "label": label, "runs": len(rows),
               "cpu_s": f"{statistics.mean(float(r['cpu_s']) for r in rows):.0f}"}
        for role in ROLES:
            row[role] = f"{statistics.mean(float(r[f'cpu_{role}_s']) for r in rows):.0f}"
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


def section(directory, images):
    name = os.path.basename(directory.rstrip("/"))
    csvs = sorted(glob.glob(os.path.join(directory, "*-seed*.csv")))
    out = [f"## {TITLES.get(name, name)}\n"]
    if not csvs:
        out.append("No runs are committed yet.\n")
    else:
        runs = results_table.final_rows(csvs)
        out.append(f"{len(csvs)} run{'s' if len(csvs) != 1 else ''} (`examples/results/{name}/`). Final success on the held-out scenes, per method "
                   "(each run's last evaluation; Wilson 95% interval per run):\n")
        out.append(markdown([results_table.summary(task, label, rows) for (task, label), rows in sorted(runs.items())]))
        paired = results_table.paired(runs, BASELINE)
        if paired:
            out.append(f"\nEach method against C2F-ARM (`{BASELINE}`), paired by seed: mean difference in final "
                       "success rate, its 95% interval (Student's t over the paired differences) and the two-sided "
                       "p-value of the exact sign-flip permutation test; a method compared on several tasks also with "
                       "all its pairs pooled (`all N tasks`):\n")
            out.append(markdown(paired))
        cpu = cpu_by_role(runs)
        if cpu:
            out.append("\nProcessor seconds by role up to the final evaluation (mean over runs; evaluation excluded):\n")
            out.append(markdown(cpu))
        failures = sorted(glob.glob(os.path.join(directory, "failures", "*.csv")))
        if failures:
            out.append("\nWhere the final agents went on the held-out scenes (episodes summed over runs; "
                       "`right_share`: of the tries at an object, the share at the right one):\n")
            out.append(markdown(results_table.lookalikes(failures)))
        ceiling = ceiling_of(directory, {task for task, _ in runs})
        if ceiling:
            out.append("\nThe ceiling of learning (`make -C examples ceiling`): the expert's own keyframes on the same "
                       "held-out scenes, discretized as the networks' targets (the voxel per depth, 5-degree rotation "
                       "bins, the gripper) and acted through the agents' planner: the discretized expert acting "
                       "open-loop, a reference for what this grid and planner allow (a network acting closed-loop "
                       "may retry):\n")
            out.append(markdown(results_table.reasons(ceiling)))
        others = sorted(glob.glob(os.path.join(directory, "acting", "*.csv")))
        if others:
            out.append("\nTrained by one method, acting with each K: the final networks on the same held-out scenes "
                       "(episodes summed over runs; `acting_k` 1 is greedy without tree expansion):\n")
            out.append(markdown(results_table.acting(failures + others)))
            compared = results_table.acting_paired(failures + others, BASELINE)
            if compared:
                out.append("\nThe same cells paired by seed (the interval and test of the paired table): each network "
                           "that also acted with another K, acting with the larger K against itself acting with the "
                           "smaller, and, acting alike, each method's networks against C2F-ARM's:\n")
                out.append(markdown(compared))
    decided = sorted(glob.glob(os.path.join(directory, "depths", "*.csv")))
    if decided:
        out.append("\nWhich depth decided: where the final agents' chosen voxels lay at each depth, on the "
                   "held-out scenes (actions summed over runs; `depth0_argmax`: depth 0's own best voxel, where "
                   "K = 1 goes; `overruled`: the actions whose depth-0 voxel is not depth 0's best, a finer depth "
                   "having chosen another branch, and `overruled_argmax` where depth 0 alone would have gone):\n")
        out.append(markdown(results_table.depths(decided)))
    pictures = [p for p in (f"{name}.png", f"{name}_curves.png", f"{name}_k.png")
                if os.path.exists(os.path.join(images, p))]
    if pictures:
        out.append("\n" + " ".join(f"![{p}](../examples/images/{p})" for p in pictures) + "\n")
    reading = os.path.join(directory, "reading.md")
    if os.path.exists(reading):
        with open(reading) as f:
            out.append("\n" + f.read().strip() + "\n")
    return "\n".join(out)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__.strip().splitlines()[2].strip())
    results = sys.argv[1]
    images = os.path.join(results, "..", "images")
    names = sorted(os.path.basename(d.rstrip("/")) for d in glob.glob(os.path.join(results, "takeaway*/")))
    names.sort(key=lambda n: (list(TITLES).index(n) if n in TITLES else len(TITLES), n))
    print("# Results: the paper's four takeaways\n")
    print("Generated by `make -C examples paper-report` from the CSVs under `examples/results/` "
          "(do not edit by hand: a test compares it with the CSVs). Success rates are over 50 held-out scenes "
          "that no run explored or was shown; seeds pair runs of different methods on the same demonstrations "
          "and exploration scenes.\n")
    for name in names:
        print(section(os.path.join(results, name), images))


if __name__ == "__main__":
    main()
