#!/usr/bin/env python3
"""The whole data path, checked by behaviour cloning: 20 reach_target demonstrations
(variation 0: the red target among two distractors of other colours) through keyframe into
qattn-train, 300 steps on the demonstrations alone; then on 20 held-out demonstrations the
greedy coarse-to-fine choice of qte-select --k 1 on each first observation must land within
one final-depth voxel of the demonstration's keyframe (its final gripper position: every
axis within 1.5 voxels of 1.875 cm, i.e. in that voxel or its neighbour) in >= 80% of cases.
3-7 minutes on 2 cores (300 learner steps), so labelled slow: `make check-slow` runs it, `make
check` does not. Run with a python3 that has NumPy (ctest uses /usr/bin/python3).

The scenes are fixed (--scenes any, seeds 1 and 99: the ones this test was written on). How
well 300 steps clone 20 demonstrations depends on the draw: on demo-record's demo scene set
(seeds 1 and 99) every learner variant measured reached 12-13/20 (published settings, no
clipping, norm clipping, beta 1), on these 18/20 (docs/learner.md, docs/testing.md). The
threshold holds on this draw only; it guards the data path against breaking, not the learner's
quality in general."""
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOOLS = os.environ.get("QTE_TOOLS") or os.path.join(SOURCE, "build", "tools")
sys.path.insert(0, os.path.join(SOURCE, "lib", "python"))
import qte_stream as read_stream  # noqa: E402
tmp = tempfile.mkdtemp(prefix="qte_bc_")


def run(name, *args):
    r = subprocess.run([os.path.join(TOOLS, name), *args], capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"FAIL: {name} {' '.join(args)}: exit {r.returncode}: {r.stderr.strip()[-500:]}")
    return r


def path(name):
    return os.path.join(tmp, name)


try:
    run("demo-record", "--task", "reach_target", "--episodes", "20", "--seed", "1", "--scenes", "any", "--variation", "0",
        "--compress", "--output", path("demos.rec"))
    run("keyframe", "--seed", "1", "--output", path("train.rec"), path("demos.rec"))
    run("qattn-train", "--steps", "300", "--start-after", "10", "--checkpoint-every", "300", "--seed", "1",
        "--checkpoint-dir", path("ckpt"), path("train.rec"))
    run("demo-record", "--task", "reach_target", "--episodes", "20", "--seed", "99", "--scenes", "any", "--variation", "0",
        "--output", path("held_out.rec"))
    run("stream-cat", "--type", "obs", "--where", "frame=0", "--output", path("starts.rec"), path("held_out.rec"))
    run("qte-select", "--checkpoint", path("ckpt/latest.rec"), "--k", "1", "--output", path("actions.rec"),
        path("starts.rec"))

    episodes = []
    for r in read_stream.read_records(path("held_out.rec")):
        if r.type == "obs":
            if int(r.fields["frame"]) == 0:
                episodes.append([])
            episodes[-1].append(r.fields["gripper_pose"][:3])
    keyframes = [np.array(e[-1]) for e in episodes]  # reach_target: one keyframe, the last frame
    actions = [r.fields["pose"][:3] for r in read_stream.read_records(path("actions.rec")) if r.type == "action"]
    if len(actions) != len(keyframes) or len(actions) != 20:
        sys.exit(f"FAIL: {len(actions)} actions for {len(keyframes)} held-out demonstrations")
    voxel = 2 * 0.15 / 16
    errors = [float(np.abs(a - k).max()) for a, k in zip(actions, keyframes)]
    hits = sum(e <= 1.5 * voxel for e in errors)
    print("distance to the keyframe, cm (max over axes):", " ".join(f"{100 * e:.1f}" for e in errors))
    print(f"{hits}/{len(errors)} within one final-depth voxel")
    if hits < 0.8 * len(errors):
        sys.exit(f"FAIL: behaviour cloning reached {hits}/{len(errors)}, expected >= 80%")
    print("behaviour cloning ok")
finally:
    shutil.rmtree(tmp, ignore_errors=True)
