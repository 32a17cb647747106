#!/usr/bin/env python3
"""docs/results.md is what examples/analysis/results_report.py makes of the committed CSVs (so no number
in it is typed by hand, and a CSV committed without `make -C examples paper-report` fails
here), and the CSVs the report writes itself are up to date. Read as a reader would: the
summary's numbers are those of the paired CSVs it links and its verdicts follow from them; no
table is wider than 8 columns; every table of where the agents went has a row for each method of
the section's final table, with the same number of runs or the replayed ones out of them; every
link into the repository leads to a file; no sentence speaks of the machine or session that
made the runs. And examples/analysis/seed_plot.py draws seeds as categories: each method's mean and 95%
interval as computed here, the same picture twice for the same CSV."""
import csv
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile

SOURCE = os.environ.get("QTE_SOURCE") or os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
EXAMPLES = os.path.join(SOURCE, "examples")
ANALYSIS = os.path.join(EXAMPLES, "analysis")
sys.path.insert(0, ANALYSIS)
import results_report  # noqa: E402
import seed_plot  # noqa: E402

MAX_COLUMNS = 8
# Words about who made the runs and where, which belong in a takeaway's provenance.md if anywhere.
PERSONAL = ["this machine", "this session", "shared virtual machine", "this virtual machine", "our machine"]


def tables(document):
    """Every Markdown table of the document: (section title, caption, header, rows as lists)."""
    found, section, caption, lines = [], "", "", document.splitlines() + [""]
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("## "):
            section = line[3:]
        if line.startswith("|"):
            block = []
            while lines[i].startswith("|"):
                block.append([cell.strip() for cell in lines[i].strip()[1:-1].split("|")])
                i += 1
            assert set("".join(block[1])) <= set("-:"), f"{section}: a table without its header rule: {block[:2]}"
            found.append((section, caption, block[0], block[2:]))
            continue
        if line.strip():
            caption = line
        i += 1
    return found


def check_widths(document):
    for section, caption, header, rows in tables(document):
        widths = {len(header)} | {len(row) for row in rows}
        assert max(widths) <= MAX_COLUMNS, f"{section}: a table of {max(widths)} columns ({header}), more than {MAX_COLUMNS}"
        assert widths == {len(header)}, f"{section}: rows of other widths than the header's {header}"


def check_summary(document):
    """The summary's rows against the paired CSVs they link, and their verdicts against p and alpha."""
    summary = [t for t in tables(document) if t[0] == "Summary"]
    assert len(summary) == 1, "docs/results.md has no summary table"
    _, _, header, rows = summary[0]
    assert rows, "the summary has no rows"
    takeaways = set()
    # Holm's correction over the table's comparisons, as adjusted p-values (the running maximum of
    # (m - j + 1) p_(j) over the sorted p), a formulation of its own: shown where at most 0.05.
    p_values = [float(re.match(r"([0-9.]+)", dict(zip(header, cells))["sign-flip p (α)"]).group(1)) for cells in rows]
    adjusted, running = {}, 0.0
    for j, i in enumerate(sorted(range(len(p_values)), key=lambda i: p_values[i])):
        running = max(running, min(1.0, (len(p_values) - j) * p_values[i]))
        adjusted[i] = running
    for index, cells in enumerate(rows):
        row = dict(zip(header, cells))
        takeaways.add(re.match(r"\[(\d)\]", row["takeaway"]).group(1))
        m = re.fullmatch(r".*\(`([^`]+)`\) − .*\(`([^`]+)`\), \[([^\]]+)\]\(\.\./(examples/results/[^)]+\.csv)\)",
                         row["comparison"])
        assert m, f"summary: no labels and CSV link in {row['comparison']!r}"
        label, baseline, task, path = m.groups()
        with open(os.path.join(SOURCE, path), newline="") as f:
            matching = [r for r in csv.DictReader(f)
                        if (r["task"], r["label"], r.get("baseline", baseline)) == (task, label, baseline)]
        assert len(matching) == 1, f"summary: {len(matching)} rows of {label} against {baseline} on {task} in {path}"
        want = matching[0]
        assert row["pairs"] == want["pairs"], (row, want)
        assert row["difference"] == want["mean_difference"], (row, want)
        assert row["95% t interval"] == f"{want['ci95_low']} to {want['ci95_high']}", (row, want)
        p, alpha = re.fullmatch(r"([0-9.]+) \(([0-9.]+)\)", row["sign-flip p (α)"]).groups()
        assert p == want["sign_flip_p"], (row, want)
        shown = float(p) < float(alpha)
        difference = float(want["mean_difference"])
        excludes = float(want["ci95_low"]) > 0 or float(want["ci95_high"]) < 0
        verdict = (("gain shown" if difference > 0 else "loss shown") if shown
                   else "not shown" + (" (the t interval excludes 0)" if excludes else ""))
        verdict += "; Holm: " + ("shown" if adjusted[index] <= 0.05 else "not shown")
        assert row["test"] == verdict, f"summary: {label} against {baseline} on {task}: {row['test']!r}, not {verdict!r}"
    assert takeaways == {"1", "2", "3", "4"}, f"the summary answers takeaways {sorted(takeaways)}, not all four"


def check_runs_agree(document):
    """Within a section, the table of where the agents went has every (task, label) of the final
    table, with its number of runs or "k of n" replayed of them."""
    final, checked = {}, 0
    for section, caption, header, rows in tables(document):
        rows = [dict(zip(header, cells)) for cells in rows]
        if caption.startswith(tuple("0123456789")) and "Final success" in caption:
            final[section] = {(r["task"], r["label"]): r["runs"] for r in rows}
        elif caption.startswith("Where the final agents went"):
            assert section in final, f"{section}: where the agents went, without a final table before it"
            went = {(r["task"], r["label"]): r["runs"] for r in rows}
            assert set(went) == set(final[section]), \
                f"{section}: methods of the final table missing where the agents went: {set(final[section]) ^ set(went)}"
            for key, runs in went.items():
                n = final[section][key]
                assert runs == n or re.fullmatch(rf"(\d+ of|none of) {n}( .*)?", runs), \
                    f"{section}: {key} has {n} runs, where the agents went says {runs!r}"
            checked += 1
    assert checked, "no table of where the agents went found"


def check_links_and_words(document):
    for target in re.findall(r"\]\((\.\./[^)#]+)\)", document):
        assert os.path.exists(os.path.join(SOURCE, "docs", target)), f"docs/results.md links {target}, which is not there"
    lowered = document.lower()
    for words in PERSONAL:
        assert words not in lowered, f"docs/results.md speaks of {words!r} (a provenance.md's matter, if any)"


def main():
    made = subprocess.run([sys.executable, os.path.join(ANALYSIS, "results_report.py"), "--no-write",
                           os.path.join(EXAMPLES, "results")], capture_output=True, text=True, check=True).stdout
    with open(os.path.join(SOURCE, "docs", "results.md")) as f:
        committed = f.read()
    if made != committed:
        for n, (a, b) in enumerate(zip(made.splitlines(), committed.splitlines()), 1):
            if a != b:
                sys.exit(f"docs/results.md line {n} differs from the CSVs' (run make -C examples paper-report):\n"
                         f"  committed: {b}\n  from CSVs: {a}")
        sys.exit("docs/results.md and the CSVs' document differ in length (run make -C examples paper-report)")
    for path, text in results_report.written(os.path.join(EXAMPLES, "results")).items():
        with open(path) as f:
            assert f.read() == text, f"{path} differs from the CSVs' (run make -C examples paper-report)"
    # Holm's step-down method on a case counted by hand: of 0.012, 0.013, 0.02 and 0.2 at 0.05, the
    # first three are shown (0.012 <= 0.05/4, 0.013 <= 0.05/3, 0.02 <= 0.05/2; 0.2 > 0.05), where
    # Bonferroni (0.0125 each) would show only the first.
    assert results_report.holm_shown([0.2, 0.013, 0.012, 0.02]) == [False, True, True, True]
    assert results_report.holm_shown([0.03, 0.005, 0.04, 0.01]) == [False, True, False, True]
    check_widths(made)
    check_summary(made)
    check_runs_agree(made)
    check_links_and_words(made)
    # The checks fail where they should: a table one column too wide, a summary number changed.
    wide = "## S\n\n| " + " | ".join("c" * (MAX_COLUMNS + 1)) + " |\n|" + "---|" * (MAX_COLUMNS + 1) + "\n"
    for check, document in ((check_widths, wide), (check_summary, made.replace("| +0.027 |", "| +0.028 |", 1)),
                            (check_runs_agree, made.replace("none of 3 replayed", "none", 1)),
                            (check_links_and_words, made + "\nMade on this machine.\n")):
        assert document != made, f"{check.__name__}: the altered document is the same"
        try:
            check(document)
        except AssertionError:
            continue
        raise AssertionError(f"{check.__name__} passes a document it should refuse")
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
            subprocess.run([sys.executable, os.path.join(ANALYSIS, "seed_plot.py"), "--title", "t", "--output", out, finals],
                           check=True)
            with open(out, "rb") as f:
                pictures.append(f.read())
        assert pictures[0].startswith(b"\x89PNG") and pictures[0] == pictures[1], "not the same PNG twice"
    print("docs/results.md matches the CSVs (summary, table widths, runs, links); seed_plot's means, intervals and "
          "bytes as expected")


if __name__ == "__main__":
    main()
