#!/usr/bin/env python3
"""examples/analysis/results_table.py, the tables of `make -C examples paper-report`: runs of two tasks
with the same method labels stay apart (the task from examples/Makefile's file names), each
run counts by its last evaluation, and the means, standard deviations, Wilson intervals,
per-seed finals, learning curves and the K ablation are those of the rows written here."""
import csv
import io
import os
import statistics
import subprocess
import sys
import tempfile

SOURCE = os.environ.get("QTE_SOURCE") or os.path.join(os.path.dirname(__file__), "..", "..")
SCRIPT = os.path.join(SOURCE, "examples", "analysis", "results_table.py")
COLUMNS = ["label", "seed", "env_steps", "train_step", "eval_point", "train_s", "cpu_s", "episodes", "successes",
           "success_rate", "ci95_low", "ci95_high", "mean_steps", "mean_return"]


def write_run(directory, name, label, seed, finals):
    """An eval.csv of one run: an evaluation after pretraining, then `finals` = (successes, eval_point)."""
    path = os.path.join(directory, name)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(COLUMNS)
        for successes, point in [(5, 0)] + finals:
            w.writerow([label, seed, point, 100 + point // 10, point, 60 * (seed + 1), 100, 50, successes,
                        successes / 50, 0.1, 0.9, 4, successes])
    return path


def run(*args, check=True):
    return subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True, check=check)


def rows_of(text):
    return list(csv.DictReader(io.StringIO(text)))


def main():
    with tempfile.TemporaryDirectory() as d:
        paths = [
            write_run(d, "lift_numbered_block_c2farm-k1-t0-seed0.csv", "c2farm-k1-t0", 0, [(13, 400)]),
            write_run(d, "lift_numbered_block_c2farm-k1-t0-seed1.csv", "c2farm-k1-t0", 1, [(20, 200), (10, 400)]),
            write_run(d, "lift_numbered_block_qte-k10-t10-seed0.csv", "qte-k10-t10", 0, [(19, 400)]),
            write_run(d, "pick_and_lift_small_qte-k10-t10-seed0.csv", "qte-k10-t10", 0, [(40, 5000)]),
            write_run(d, "reach_prism_qte-k2-t2-seed0.csv", "qte-k2-t2", 0, [(36, 2000)]),
        ]
        table = rows_of(run(*paths).stdout)
        keys = [(r["task"], r["label"]) for r in table]
        assert keys == [("lift_numbered_block", "c2farm-k1-t0"), ("lift_numbered_block", "qte-k10-t10"),
                        ("pick_and_lift_small", "qte-k10-t10"), ("reach_prism", "qte-k2-t2")], keys
        c2farm = table[0]
        assert c2farm["runs"] == "2"
        # The last evaluation of each run counts (seed 1's 10/50 at 400, not its 20/50 at 200).
        assert c2farm["mean_success"] == f"{statistics.mean([13 / 50, 10 / 50]):.3f}", c2farm
        assert c2farm["std_success"] == f"{statistics.stdev([13 / 50, 10 / 50]):.3f}", c2farm
        assert c2farm["per_run"] == "s0:13/50 [0.10,0.90] s1:10/50 [0.10,0.90]", c2farm["per_run"]
        assert c2farm["mean_train_min"] == f"{statistics.mean([60, 120]) / 60:.1f}", c2farm
        assert table[2]["mean_success"] == "0.800" and table[2]["std_success"] == "", table[2]

        markdown = run("--markdown", *paths).stdout.splitlines()
        assert markdown[0].startswith("| task | label | runs |"), markdown[0]
        assert len(markdown) == 2 + len(table), markdown

        finals = rows_of(run("--finals", *paths).stdout)
        assert [(r["series"], r["seed"], r["successes"]) for r in finals] == [
            ("lift_numbered_block c2farm-k1-t0", "0", "13"), ("lift_numbered_block c2farm-k1-t0", "1", "10"),
            ("lift_numbered_block qte-k10-t10", "0", "19"), ("pick_and_lift_small qte-k10-t10", "0", "40"),
            ("reach_prism qte-k2-t2", "0", "36")], finals

        # A newer run's CSV splits cpu_s by role; an older one's does not: every run is in the
        # finals, the older one's split blank.
        newer = os.path.join(d, "lift_numbered_block_qte-k10-t10-seed1.csv")
        with open(newer, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(COLUMNS[:7] + ["cpu_learner_s"] + COLUMNS[7:])
            w.writerow(["qte-k10-t10", 1, 400, 140, 400, 60, 100, 80.5, 50, 25, 0.5, 0.3, 0.7, 4, 25])
        mixed = rows_of(run("--finals", paths[2], newer).stdout)
        assert [(r["seed"], r["successes"], r["cpu_learner_s"]) for r in mixed] == [("0", "19", ""), ("1", "25", "80.5")], mixed

        ablation = rows_of(run("--k-ablation", *paths).stdout)
        assert [(r["k"], r["label"]) for r in ablation] == [("2", "qte-k2-t2"), ("10", "qte-k10-t10"),
                                                            ("10", "qte-k10-t10")], ablation
        assert "series" not in ablation[0]

        # Learning curves: every evaluation of one task's runs, pick_and_lift's apart from
        # pick_and_lift_small's though one name begins the other.
        lift = write_run(d, "pick_and_lift_qte-k10-t10-seed0.csv", "qte-k10-t10", 0, [(30, 1000), (35, 5000)])
        with_lift = paths + [lift]
        assert run("--tasks", *with_lift).stdout.split() == [
            "lift_numbered_block", "pick_and_lift", "pick_and_lift_small", "reach_prism"]
        curve = rows_of(run("--curves", "--task", "lift_numbered_block", *with_lift).stdout)
        assert [(r["task"], r["label"], r["seed"], r["eval_point"], r["successes"]) for r in curve] == [
            ("lift_numbered_block", "c2farm-k1-t0", "0", "0", "5"), ("lift_numbered_block", "c2farm-k1-t0", "0", "400", "13"),
            ("lift_numbered_block", "c2farm-k1-t0", "1", "0", "5"), ("lift_numbered_block", "c2farm-k1-t0", "1", "200", "20"),
            ("lift_numbered_block", "c2farm-k1-t0", "1", "400", "10"), ("lift_numbered_block", "qte-k10-t10", "0", "0", "5"),
            ("lift_numbered_block", "qte-k10-t10", "0", "400", "19")], curve
        picked = rows_of(run("--curves", "--task", "pick_and_lift", *with_lift).stdout)
        assert [(r["eval_point"], r["successes"]) for r in picked] == [("0", "5"), ("1000", "30"), ("5000", "35")], picked
        unknown = run("--curves", "--task", "stack_blocks", *with_lift, check=False)
        assert unknown.returncode != 0 and "no runs of task 'stack_blocks'" in unknown.stderr, unknown

        # A run's own eval.csv (no task in its name) is grouped by label alone.
        own = write_run(d, "eval.csv", "qte-k10-t10", 3, [(30, 400)])
        alone = rows_of(run(own).stdout)
        assert [(r["task"], r["label"], r["runs"]) for r in alone] == [("", "qte-k10-t10", "1")], alone
        assert rows_of(run("--finals", own).stdout)[0]["series"] == "qte-k10-t10"

        # failure_reasons CSVs joined, each row with its run's task.
        failed = []
        for name, label, seed in [("reach_prism_qte-k2-t2-seed1.csv", "qte-k2-t2", 1),
                                  ("lift_numbered_block_c2farm-k1-t0-seed0.csv", "c2farm-k1-t0", 0)]:
            path = os.path.join(d, "failures_" + name)
            with open(path, "w") as f:
                f.write(f"label,seed,episodes,success\n{label},{seed},50,{20 + seed}\n")
            failed.append(path)
        # The task is what precedes _LABEL-seedN.csv in the name (here with a "failures_" prefix).
        joined = rows_of(run("--failures", *failed).stdout)
        assert [(r["task"], r["label"], r["success"]) for r in joined] == [
            ("failures_reach_prism", "qte-k2-t2", "21"), ("failures_lift_numbered_block", "c2farm-k1-t0", "20")], joined

        # With the reasons (failure_reasons.py's columns after failed_actions): an older file
        # first keeps the newer file's columns, empty for it; --reasons sums them per task,
        # label and acting K, leaving the older file out.
        reason_columns = ["wrong_object", "grasp_missed", "dropped", "goal_in_collision", "ik_failed", "no_path",
                          "start_in_collision", "outside_workspace", "invalid_pose", "trajectory_refused",
                          "collision", "other_failure", "out_of_steps"]
        with_reasons = []
        for name, seed, counts in [("pick_up_cup_c2farm-k1-t0-seed0.csv", 0, [2, 20, 3, 10, 0, 1, 0, 0, 0, 2, 0, 0, 2]),
                                   ("pick_up_cup_c2farm-k1-t0-seed1_act-k10.csv", 1, [1, 9, 0, 30, 0, 0, 0, 0, 0, 0, 0, 0, 0]),
                                   ("pick_up_cup_c2farm-k1-t0-seed1.csv", 1, [0, 10, 1, 25, 0, 0, 0, 0, 0, 0, 0, 0, 4])]:
            path = os.path.join(d, "reasons_" + name)
            with open(path, "w") as f:
                f.write("label,seed,episodes,success,distractor,target,elsewhere,failed_actions," + ",".join(reason_columns) + "\n")
                f.write(f"c2farm-k1-t0,{seed},50,{50 - sum(counts)},0,0,0,0," + ",".join(map(str, counts)) + "\n")
            with_reasons.append(path)
        joined = rows_of(run("--failures", failed[0], with_reasons[0]).stdout)
        assert [(r["label"], r["grasp_missed"], r["out_of_steps"]) for r in joined] == [
            ("qte-k2-t2", "", ""), ("c2farm-k1-t0", "20", "2")], joined
        summed = rows_of(run("--reasons", failed[0], *with_reasons).stdout)
        assert [(r["task"], r["acting_k"], r["runs"], r["episodes"], r["success"], r["grasp_missed"], r["goal_in_collision"],
                 r["out_of_steps"]) for r in summed] == [
            ("reasons_pick_up_cup", "1", "2", "100", str(100 - 40 - 40), "30", "35", "6"),
            ("reasons_pick_up_cup", "10", "1", "50", "10", "9", "30", "0")], summed
        assert [r["pushed"] for r in summed] == ["", ""], summed  # written before `pushed`: unknown, not 0
        # A run written with `pushed`: summed where every run of the cell has it, blank where one has not.
        newer = os.path.join(d, "reasons_stack_wine_qte-k10-t10-seed0.csv")
        with open(newer, "w") as f:
            f.write("label,seed,episodes,success,distractor,target,elsewhere,failed_actions,wrong_object,pushed,"
                    + ",".join(reason_columns[1:]) + "\n")
            f.write("qte-k10-t10,0,50,30,0,0,0,0,1,7,5,0,1,0,0,0,0,0,0,0,0,6\n")
        summed = rows_of(run("--reasons", newer, with_reasons[0]).stdout)
        assert [(r["task"], r["pushed"], r["grasp_missed"]) for r in summed] == [
            ("reasons_pick_up_cup", "", "20"), ("reasons_stack_wine", "7", "5")], summed
        # An analysis without a seed (ceiling.sh's TASK_LABEL.csv) has its task too.
        ceiling = os.path.join(d, "stack_wine_keyframes.csv")
        with open(ceiling, "w") as f:
            f.write("label,seed,episodes,success,distractor,target,elsewhere,failed_actions,wrong_object,pushed,"
                    + ",".join(reason_columns[1:]) + "\n")
            f.write("keyframes,,50,38,0,12,0,0,0,12,0,0,0,0,0,0,0,0,0,0,0,0\n")
        summed = rows_of(run("--reasons", ceiling).stdout)
        assert [(r["task"], r["label"], r["acting_k"], r["success"], r["pushed"]) for r in summed] == [
            ("stack_wine", "keyframes", "", "38", "12")], summed

        # Summed per task and label: of the tries at an object (success, target, distractor),
        # the share at the right one (success, target).
        tried = []
        for name, label, seed, kinds in [("lift_numbered_block_qte-k10-t10-seed0.csv", "qte-k10-t10", 0, (19, 0, 31, 0)),
                                         ("lift_numbered_block_qte-k10-t10-seed1.csv", "qte-k10-t10", 1, (23, 2, 25, 0)),
                                         ("reach_prism_qte-k1-t1-seed2.csv", "qte-k1-t1", 2, (0, 0, 0, 50))]:
            path = os.path.join(d, "lookalike_" + name)
            with open(path, "w") as f:
                f.write("label,seed,episodes,success,target,distractor,elsewhere,failed_actions\n")
                f.write(f"{label},{seed},50,{','.join(map(str, kinds))},0\n")
            tried.append(path)
        summed = rows_of(run("--lookalikes", *tried).stdout)
        assert [(r["task"], r["label"], r["runs"], r["episodes"], r["tries_at_an_object"], r["right_share"])
                for r in summed] == [
            ("lookalike_lift_numbered_block", "qte-k10-t10", "2", "100", "100", f"{(19 + 23 + 2) / 100:.3f}"),
            ("lookalike_reach_prism", "qte-k1-t1", "1", "50", "0", "")], summed

        # Paired by seed against C2F-ARM: the seeds both methods have (qte's seed 0 only here),
        # then a case checked by hand: differences +4, +2, +6, -2, +5 of 50 successes.
        pairs = rows_of(run("--paired", "c2farm-k1-t0", *paths).stdout)
        assert [(r["task"], r["label"], r["pairs"], r["mean_difference"]) for r in pairs] == [
            ("lift_numbered_block", "qte-k10-t10", "1", f"{(19 - 13) / 50:+.3f}")], pairs
        assert pairs[0]["ci95_low"] == pairs[0]["ci95_high"] == "", pairs  # no interval from one pair
        mine = []
        for seed, (base, qte) in enumerate([(20, 24), (30, 32), (10, 16), (40, 38), (25, 30)]):
            mine.append(write_run(d, f"reach_prism_c2farm-k1-t0-seed{seed}.csv", "c2farm-k1-t0", seed, [(base, 9)]))
            mine.append(write_run(d, f"reach_prism_qte-k10-t10-seed{seed}.csv", "qte-k10-t10", seed, [(qte, 9)]))
        pair = rows_of(run("--paired", "c2farm-k1-t0", *mine).stdout)
        assert len(pair) == 1, pair
        d_rates = [0.08, 0.04, 0.12, -0.04, 0.10]
        mean = statistics.mean(d_rates)
        half = 2.7764451 * statistics.stdev(d_rates) / 5 ** 0.5  # t(0.975, 4 df), from a table
        assert pair[0]["mean_difference"] == f"{mean:+.3f}", pair
        assert pair[0]["ci95_low"] == f"{mean - half:+.3f}" and pair[0]["ci95_high"] == f"{mean + half:+.3f}", pair
        # The exact sign-flip p-value: the share of the 32 sign assignments whose |sum| reaches
        # the observed 0.30: 6 of them (the observed signs, 0.30; -0.04 flipped, 0.38; both 0.04s
        # flipped, 0.30; and the three mirrored).
        sums = [abs(sum(s * x for s, x in zip(signs, d_rates)))
                for signs in __import__("itertools").product((1, -1), repeat=5)]
        p_value = sum(v >= 0.30 - 1e-12 for v in sums) / 32
        assert p_value == 6 / 32 and pair[0]["sign_flip_p"] == "0.1875", (pair, p_value)
        assert pair[0]["per_seed"] == "s0:+0.08 s1:+0.04 s2:+0.12 s3:-0.04 s4:+0.10", pair
        assert pair[0]["pairs_one_processor"] == "0", pair  # no machines/ files: none known

        # A label compared on several tasks gets a row of all its (task, seed) pairs pooled; its
        # p-value (counted on the 1/1000 grid of success rates) is checked against enumerating
        # all 2^14 sign assignments here: reach_prism's 5 pairs above and 9 of take_lid_off_saucepan.
        pooled_dir = os.path.join(d, "pooled")
        os.makedirs(pooled_dir)
        reach = [(20, 24), (30, 32), (10, 16), (40, 38), (25, 30)]  # reach_prism's pairs above
        lid = [(31, 33), (40, 40), (12, 19), (45, 44), (28, 35), (33, 30), (20, 27), (49, 50), (38, 41)]
        more = []
        for task, task_pairs in [("reach_prism", reach), ("take_lid_off_saucepan", lid)]:
            for seed, (base, qte) in enumerate(task_pairs):
                more.append(write_run(pooled_dir, f"{task}_c2farm-k1-t0-seed{seed}.csv", "c2farm-k1-t0", seed,
                                      [(base, 9)]))
                more.append(write_run(pooled_dir, f"{task}_qte-k10-t10-seed{seed}.csv", "qte-k10-t10", seed,
                                      [(qte, 9)]))
        pooled = rows_of(run("--paired", "c2farm-k1-t0", *more).stdout)
        assert [(r["task"], r["pairs"]) for r in pooled] == [
            ("reach_prism", "5"), ("take_lid_off_saucepan", "9"), ("all 2 tasks", "14")], pooled
        all_d = [(qte - base) / 50 for base, qte in reach + lid]
        sums = [abs(sum(s * x for s, x in zip(signs, all_d)))
                for signs in __import__("itertools").product((1, -1), repeat=14)]
        brute = sum(v >= abs(sum(all_d)) - 1e-9 for v in sums) / 2 ** 14
        mean = statistics.mean(all_d)
        assert pooled[2]["mean_difference"] == f"{mean:+.3f}", pooled[2]
        assert pooled[2]["sign_flip_p"] == f"{brute:.4f}", (pooled[2], brute)
        assert pooled[2]["mean_success"] == f"{statistics.mean(q for _, q in reach + lid) / 50:.3f}"
        # The pooled row's flips are per pair, counted by hand: task A's pairs +0.2 and +0.1, task B's
        # -0.1; of the 8 sign assignments 6 reach |sum| >= 0.2 (p = 0.75). Flipping each task's pairs
        # together (4 assignments of +0.3 and -0.1) would give 1.0.
        by_hand = os.path.join(d, "by_hand")
        os.makedirs(by_hand)
        files = []
        for task, task_pairs in [("task_a", [(10, 20), (10, 15)]), ("task_b", [(20, 15)])]:
            for seed, (base, qte) in enumerate(task_pairs):
                files.append(write_run(by_hand, f"{task}_c2farm-k1-t0-seed{seed}.csv", "c2farm-k1-t0", seed, [(base, 9)]))
                files.append(write_run(by_hand, f"{task}_qte-k10-t10-seed{seed}.csv", "qte-k10-t10", seed, [(qte, 9)]))
        hand = rows_of(run("--paired", "c2farm-k1-t0", *files).stdout)
        assert [(r["task"], r["pairs"], r["sign_flip_p"]) for r in hand][-1] == ("all 2 tasks", "3", "0.7500"), hand
        # Rates over 3 episodes (thirds) are counted on their common denominator, differences that
        # are no such fractions enumerated: both as the brute force here; too many of the latter
        # to enumerate are refused.
        sys.path.insert(0, os.path.dirname(SCRIPT))
        import results_table
        for values in ([1 / 3, -2 / 3, 1.0, 2 / 3, 1 / 3], [0.1234567, -0.0712345, 0.3141593, 0.0271828, -0.0141421]):
            sums = [abs(sum(s * x for s, x in zip(signs, values)))
                    for signs in __import__("itertools").product((1, -1), repeat=5)]
            assert results_table.sign_flip_p(values) == sum(v >= abs(sum(values)) - 1e-9 for v in sums) / 32, values
        try:
            results_table.sign_flip_p([0.1234567] * 21)
            raise AssertionError("21 differences off every grid were enumerated")
        except ValueError as e:
            assert "too many to enumerate" in str(e), e

        # Pairs made on one processor, from learn.sh's machine files in machines/: seeds 0 and 1
        # both runs on one (seed 1's QTE run resumed on it), seed 2 on two kinds, seed 3's C2F-ARM
        # run resumed on another kind (mixed), seed 4 only QTE's recorded.
        zen4, zen3 = "AMD EPYC (family 25 model 17),avx512f,2", "AMD EPYC (family 25 model 1),avx2,2"
        os.makedirs(os.path.join(d, "machines"))
        for name, starts in [("c2farm-k1-t0-seed0", [zen4]), ("qte-k10-t10-seed0", [zen4]),
                             ("c2farm-k1-t0-seed1", [zen4]), ("qte-k10-t10-seed1", [zen4, zen4]),
                             ("c2farm-k1-t0-seed2", [zen3]), ("qte-k10-t10-seed2", [zen4]),
                             ("c2farm-k1-t0-seed3", [zen4, zen3]), ("qte-k10-t10-seed3", [zen4]),
                             ("qte-k10-t10-seed4", [zen4])]:
            with open(os.path.join(d, "machines", f"reach_prism_{name}.csv"), "w") as f:
                f.writelines(f"2026-11-27T04:0{i}:00Z,{start}\n" for i, start in enumerate(starts))
        pair = rows_of(run("--paired", "c2farm-k1-t0", *mine).stdout)
        assert pair[0]["pairs_one_processor"] == "2", pair

        # Trained-by x acting-with: a run's own failures (its label's K) and those acting with
        # another K (learn.sh's ALSO_ACT_K, named ..._act-kK.csv) kept apart, summed over seeds.
        crossed = []
        for name, label, kinds in [("reach_prism_c2farm-k1-t0-seed0.csv", "c2farm-k1-t0", (30, 5, 15, 0)),
                                   ("reach_prism_c2farm-k1-t0-seed1.csv", "c2farm-k1-t0", (20, 10, 20, 0)),
                                   ("reach_prism_c2farm-k1-t0-seed0_act-k10.csv", "c2farm-k1-t0", (40, 0, 10, 0)),
                                   ("reach_prism_qte-k10-t10-seed0_act-k1.csv", "qte-k10-t10", (25, 0, 20, 5))]:
            path = os.path.join(d, name)
            with open(path, "w") as f:
                f.write("label,seed,episodes,success,target,distractor,elsewhere,failed_actions\n")
                f.write(f"{label},{name.split('seed')[1][0]},50,{','.join(map(str, kinds))},1\n")
            crossed.append(path)
        cells = rows_of(run("--acting", *crossed).stdout)
        assert [(r["task"], r["label"], r["acting_k"], r["runs"], r["success"], r["success_rate"]) for r in cells] == [
            ("reach_prism", "c2farm-k1-t0", "1", "2", "50", "0.500"), ("reach_prism", "c2farm-k1-t0", "10", "1", "40", "0.800"),
            ("reach_prism", "qte-k10-t10", "1", "1", "25", "0.500")], cells
        # The cells paired by seed: C2F-ARM's networks acting with K = 10 against themselves
        # greedy (seed 0 only: seed 1 never acted with 10), and QTE's acting greedily against
        # C2F-ARM's, by hand: 25/50 - 30/50.
        compared = rows_of(run("--acting-paired", "c2farm-k1-t0", *crossed).stdout)
        assert [(r["trained_by"], r["acting_k"], r["against"], r["pairs"], r["mean_difference"], r["ci95_low"],
                 r["sign_flip_p"]) for r in compared] == [
            ("c2farm-k1-t0", "10", "c2farm-k1-t0 acting with K = 1", "1", "+0.200", "", "1.0000"),
            ("qte-k10-t10", "1", "c2farm-k1-t0 acting with K = 1", "1", "-0.100", "", "1.0000")], compared
        # Three seeds whose K = 10 cells beat K = 1 by 10, 5 and 15 of 50: mean +0.200, sd 0.100,
        # t(0.975, 2) = 4.303 gives +-0.248; all three positive: 2 of the 8 sign flips are as extreme.
        three = []
        for seed, (greedy, expanded) in enumerate([(30, 40), (20, 25), (10, 25)]):
            for suffix, success in (("", greedy), ("_act-k10", expanded)):
                path = os.path.join(d, f"three_c2farm-k1-t0-seed{seed}{suffix}.csv")
                with open(path, "w") as f:
                    f.write(f"label,seed,episodes,success\nc2farm-k1-t0,{seed},50,{success}\n")
                three.append(path)
        row = rows_of(run("--acting-paired", "c2farm-k1-t0", *three).stdout)
        assert [(r["pairs"], r["mean_difference"], r["ci95_low"], r["ci95_high"], r["sign_flip_p"]) for r in row] == [
            ("3", "+0.200", "-0.048", "+0.448", "0.2500")], row

        # Which depth decided, summed over two runs of one label; the shares are those of the sums
        # (3 of 5 + 1 of 3 on the target at depth 1: 4 of 8), not the mean of the runs' shares.
        decided = []
        for seed, (depth0, depth1) in enumerate([((5, 2, 2, 1), (5, 3, 1, 1)), ((3, 1, 2, 0), (3, 1, 1, 1))]):
            path = os.path.join(d, f"lift_numbered_block_qte-k10-t10-seed{seed}.csv")
            with open(path, "w") as f:
                f.write("label,k,row,actions,target,lookalike,elsewhere,target_share,lookalike_share,elsewhere_share\n")
                for name, counts in (("depth1", depth1), ("depth0", depth0)):
                    f.write(f"qte-k10-t10,10,{name},{','.join(map(str, counts))},x,x,x\n")
            decided.append(path)
        table = rows_of(run("--depths", *decided).stdout)
        assert [(r["task"], r["row"], r["runs"], r["actions"], r["target"], r["lookalike"], r["elsewhere"],
                 r["target_share"]) for r in table] == [
            ("lift_numbered_block", "depth0", "2", "8", "3", "4", "1", "0.375"),
            ("lift_numbered_block", "depth1", "2", "8", "4", "2", "2", "0.500")], table

        empty = os.path.join(d, "empty.csv")
        with open(empty, "w") as f:
            f.write(",".join(COLUMNS) + "\n")
        refused = run(empty, check=False)
        assert refused.returncode != 0 and "empty.csv: no evaluation rows" in refused.stderr, refused
    print("results_table: tasks apart, last evaluations, means, finals, curves, lookalikes, paired tests and K ablation as written")


if __name__ == "__main__":
    main()
