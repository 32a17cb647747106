#!/usr/bin/env python3
"""Runs the shell examples of README.md and docs/*.md that are marked runnable, so that a changed
option or output breaks the build rather than the reader.

A runnable example is a fenced block whose info string is `sh runnable`. The blocks of one
document run in order, each as `bash -euo pipefail`, in one scratch directory per document that
starts empty, with the built programs first on PATH; every document makes its own inputs. A
block that fails is reported with its document and line. The README's learning pipeline must
also have taken learner steps (its train.csv) and printed success rates (episode-stats), and
docs/learning-loop.md's small online loop learner steps on the agent's own transitions."""
import csv
import os
import re
import shutil
import subprocess
import sys
import tempfile

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOOLS = os.environ.get("QTE_TOOLS") or os.path.join(SOURCE, "build", "tools")
TIMEOUT_S = 900
FENCE = re.compile(r"^```(.*)$")


def documents():
    docs = os.path.join(SOURCE, "docs")
    return [os.path.join(SOURCE, "README.md")] + sorted(
        os.path.join(docs, f) for f in os.listdir(docs) if f.endswith(".md"))


def runnable_blocks(path):
    """(line number, text) of each block fenced as `sh runnable` in a Markdown file."""
    blocks, inside, start, flags, lines = [], False, 0, [], []
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            m = FENCE.match(line.rstrip("\n"))
            if m and not inside:
                info = m.group(1).split()
                inside, start, flags, lines = True, number, info[1:] if info[:1] == ["sh"] else None, []
            elif m and inside:
                inside = False
                if flags and "runnable" in flags:
                    blocks.append((start, "".join(lines)))
            elif inside:
                lines.append(line)
    return blocks


def check_readme_learning(scratch, output, failures):
    """The README's pipeline trained (train.csv rows up to a step > 0) and evaluated."""
    metrics = os.path.join(scratch, "train.csv")
    if not os.path.exists(metrics):
        failures.append("README.md: the learning pipeline wrote no train.csv")
        return
    with open(metrics) as f:
        steps = [int(row["step"]) for row in csv.DictReader(f)]
    if not steps or max(steps) <= 0:
        failures.append(f"README.md: the learner took no step (train.csv steps {steps})")
    if output.count("success_rate") < 1:
        failures.append("README.md: the learning pipeline printed no success rate")
    print(f"README.md learning pipeline: {max(steps or [0])} learner steps; evaluation:\n{output.strip()}")


def check_online_loop(scratch, failures):
    """docs/learning-loop.md's small loop trained on the agent's own transitions: train.csv has
    rows after the 10 pretraining steps, with agent transitions in the replay."""
    metrics = os.path.join(scratch, "train.csv")
    if not os.path.exists(metrics):
        failures.append("docs/learning-loop.md: the online loop wrote no train.csv")
        return
    with open(metrics) as f:
        rows = [(int(r["step"]), int(r["agent_transitions"])) for r in csv.DictReader(f)]
    online = [step for step, agent in rows if step > 10 and agent > 0]
    if not online:
        failures.append(f"docs/learning-loop.md: the learner took no step on agent transitions (step, agent "
                        f"transitions: {rows})")
    print(f"docs/learning-loop.md online loop: steps on agent transitions up to {max(online or [0])}")


def main():
    env = dict(os.environ, PATH=os.path.abspath(TOOLS) + os.pathsep + os.environ.get("PATH", ""))
    failures, ran = [], 0
    for doc in documents():
        name = os.path.relpath(doc, SOURCE)
        blocks = runnable_blocks(doc)
        if not blocks:
            continue
        scratch = tempfile.mkdtemp(prefix="qte_doc_")
        outputs = []
        for line, text in blocks:
            ran += 1
            try:
                r = subprocess.run(["bash", "-euo", "pipefail", "-c", text], cwd=scratch, env=env,
                                   capture_output=True, text=True, timeout=TIMEOUT_S)
            except subprocess.TimeoutExpired:
                failures.append(f"{name}:{line}: still running after {TIMEOUT_S} s")
                break
            outputs.append(r.stdout)
            if r.returncode != 0:
                failures.append(f"{name}:{line}: exit {r.returncode}\n{text}--- output:\n"
                                f"{r.stdout[-2000:]}{r.stderr[-2000:]}")
                break  # later blocks of this document may need this one's files
        else:
            if name == "README.md" and any("qattn-train" in text for _, text in blocks):
                check_readme_learning(scratch, "".join(outputs), failures)
            if name == os.path.join("docs", "learning-loop.md"):
                check_online_loop(scratch, failures)
        shutil.rmtree(scratch, ignore_errors=True)
    if ran == 0:
        failures.append("no block marked 'sh runnable' in README.md or docs/")
    print("\n".join(failures) or f"{ran} runnable examples ran as written")
    if failures:
        sys.exit(f"FAIL ({len(failures)})")


if __name__ == "__main__":
    main()
