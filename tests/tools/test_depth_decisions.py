#!/usr/bin/env python3
"""examples/analysis/depth_decisions.py on a scene built here, where every answer is known: a target
block, a lookalike turned 45 degrees and a zone (other) at known poses. Voxel centres are
judged as the rule says (on the box, within half a voxel of it, above it, beside the turned
box's corner, on the zone: elsewhere); a stream of actions gives the table by depth, the
depth-0 argmax row and the overruled rows; failure_reasons sorts episodes by these objects, not
by points. Run with Debian's python3 (NumPy)."""
import csv
import math
import os
import sys
import tempfile

import numpy as np

SOURCE = os.environ.get("QTE_SOURCE") or os.path.join(os.path.dirname(__file__), "..", "..")
sys.path.insert(0, os.path.join(SOURCE, "examples", "analysis"))
import depth_decisions as dd  # noqa: E402
import failure_reasons as fr  # noqa: E402
from qte_stream import Record, scene_objects  # noqa: E402  (depth_decisions put lib/python on the path)

TABLE = 0.752
TARGET, LOOKALIKE, ZONE = np.array([0.10, -0.10, TABLE + 0.025]), np.array([0.10, 0.10, TABLE + 0.025]), \
    np.array([0.25, 0.0, TABLE + 0.3])
failures = []


def check(what, got, want):
    if got != want:
        failures.append(f"{what}: expected {want}, got {got}")


def yaw_pose(xyz, yaw):
    return list(xyz) + [0, 0, math.sin(yaw / 2), math.cos(yaw / 2)]


def obs(step=0, held=None):
    """An observation with the three objects as sim-step --objects writes them; `held`, the
    objects.held flags (none: a stream written before that field)."""
    return Record("obs", ({} if held is None else {"objects.held": np.array(held, np.uint8)}) | {
        "objects.names": "block1,block2,success_zone",
        "objects.role": np.array([1, 2, 0], np.uint8),
        "objects.pose": np.array([yaw_pose(TARGET, 0), yaw_pose(LOOKALIKE, math.pi / 4), yaw_pose(ZONE, 0)]),
        "objects.box": np.array([[-0.025] * 3 + [0.025] * 3] * 2 + [[-0.04] * 3 + [0.04] * 3]),
        "step": np.array(step, np.int32), "gripper_pose": np.array([0, 0, 1.2, 1, 0, 0, 0.0]),
        "gripper_open": np.array(1, np.uint8), "success": np.array(0, np.uint8)}, 0, 0)


found = [o for o in scene_objects(obs()) if o.role != "other"]
check("scene_objects", [(o.id, o.name, o.role) for o in scene_objects(obs())],
      [(0, "block1", "target"), (1, "block2", "distractor"), (2, "success_zone", "other")])
zone = scene_objects(obs())[2:]

# Voxel centres and where they lie, with the margin of a depth-0 voxel (6.25 cm) or a depth-1
# voxel (1.875 cm): half the edge.
coarse, fine = 0.0625, 0.01875
cases = [
    ("the target's centre", TARGET, fine, "target"),
    ("the lookalike's centre", LOOKALIKE, fine, "lookalike"),
    ("2.5 cm beside the target's face, depth 0", TARGET + [0.05, 0, 0], coarse, "target"),  # within 3.125
    ("2.5 cm beside the target's face, depth 1", TARGET + [0.05, 0, 0], fine, "elsewhere"),  # beyond 0.94
    ("8 cm above the target", TARGET + [0, 0, 0.105], fine, "target"),
    ("12 cm above the target", TARGET + [0, 0, 0.145], fine, "elsewhere"),
    ("under the table below the target", TARGET - [0, 0, 0.05], fine, "elsewhere"),
    # The lookalike is turned 45 degrees: a corner points along x, 3.54 cm from its centre (4.87
    # cm grown by half a depth-1 voxel); an unturned box, grown, would end at 3.44 cm.
    ("4.4 cm along x: short of the turned lookalike's corner", LOOKALIKE + [0.044, 0, 0], fine, "lookalike"),
    ("5.2 cm along x: past the turned lookalike's corner", LOOKALIKE + [0.052, 0, 0], fine, "elsewhere"),
    ("2.8 cm along x and y: past the turned lookalike's face", LOOKALIKE + [0.028, 0.028, 0], fine, "elsewhere"),
    ("between the two, depth 0", (TARGET + LOOKALIKE) / 2, coarse, "elsewhere"),
]
for what, point, edge, want in cases:
    check(what, dd.place(found, point, edge), want)
check("on the zone (other) only", dd.place(zone, ZONE, fine), "elsewhere")
# Overlapping grown boxes: the nearest object's centre decides.
near_both = [found[0], found[1]._replace(pose=np.array(yaw_pose(TARGET + [0.07, 0, 0], 0)))]
check("between two close objects, nearer the lookalike", dd.place(near_both, TARGET + [0.04, 0, 0], coarse), "lookalike")
check("between two close objects, nearer the target", dd.place(near_both, TARGET + [0.03, 0, 0], coarse), "target")


def action(points, argmax_point=None, k=10, explored=0, gripper_open=1):
    """An action of qte-select whose voxel at depth d holds points[d]: depth 0 over the 1 m scene,
    depth 1 the 30 cm around depth 0's voxel centre, 16 voxels per side; its pose at the last point."""
    fields, bounds = {"k": np.array(k, np.int32), "explored": np.array(explored, np.uint8),
                      "pose": np.array(list(points[-1]) + [1, 0, 0, 0.0]),
                      "gripper_open": np.array(gripper_open, np.uint8)}, np.array([-0.3, -0.5, 0.6, 1.0])
    for d, p in enumerate(points):
        edge = bounds[3] / 16
        index = np.floor((p - bounds[:3]) / edge).astype(np.int32)
        centre = bounds[:3] + (index + 0.5) * edge
        fields.update({f"depth{d}.index": index, f"depth{d}.bounds": bounds, f"depth{d}.centre": centre})
        if d == 0:
            fields["depth0.argmax_index"] = np.floor(((argmax_point if argmax_point is not None else p)
                                                      - bounds[:3]) / edge).astype(np.int32)
        bounds = np.concatenate([centre - 0.15, [0.3]])
    return Record("action", fields, 0, 0)


away = TARGET + np.array([0.0, 0.2, 0.0]) + [0.1, 0, 0]  # 20 cm from both
stream = [obs(0), action([TARGET, TARGET]),                       # both depths on the target
          obs(1), action([TARGET, TARGET], argmax_point=LOOKALIKE),  # depth 0's argmax on the lookalike, overruled
          obs(2), action([LOOKALIKE, LOOKALIKE]),                 # both on the lookalike
          obs(3, held=[1, 0, 0]), action([TARGET, TARGET + [0.04, 0, 0]], gripper_open=0),  # holding the target
          obs(4), action([away, away], argmax_point=TARGET),      # overruled, to nowhere
          obs(5), action([LOOKALIKE, LOOKALIKE], explored=1)]     # explored: left out
taken = dd.decisions(stream)
check("greedy actions", len(taken), 5)
counts = dd.table(taken)
check("rows", list(counts), ["depth0", "depth1", "depth0_argmax", "overruled", "overruled_argmax"])
check("depth0", counts["depth0"], {"target": 3, "lookalike": 1, "elsewhere": 1})
check("depth1", counts["depth1"], {"target": 2, "lookalike": 1, "elsewhere": 2})
check("depth0_argmax", counts["depth0_argmax"], {"target": 3, "lookalike": 2, "elsewhere": 0})
check("overruled", counts["overruled"], {"target": 1, "lookalike": 0, "elsewhere": 1})
check("overruled_argmax", counts["overruled_argmax"], {"target": 1, "lookalike": 1, "elsewhere": 0})
check("--step 1", dd.table(dd.decisions(stream, 1))["overruled"], {"target": 1, "lookalike": 0, "elsewhere": 0})
# --actions: a row per judged action, the explored one left out but counted in the indices
# (qte-select --png numbers every action it writes).
with tempfile.TemporaryDirectory() as tmp:
    dd.write_actions(taken, os.path.join(tmp, "actions.csv"))
    with open(os.path.join(tmp, "actions.csv")) as f:
        rows = list(csv.DictReader(f))
    check("--actions files", os.listdir(tmp), ["actions.csv"])
check("--actions columns", list(rows[0]), ["action", "obs_record", "episode_seed", "step", "k", "overruled", "held",
                                           "gripper_open", "pose_z", "depth0", "depth1", "depth0_argmax"])
# What the gripper held when each action was chosen (the observation's objects.held; an older
# stream's closed, stopped fingers otherwise: open here, so empty), and the action's gripper
# and height.
check("--actions held", [(r["held"], r["gripper_open"], r["pose_z"]) for r in rows],
      [("empty", "1", f"{TARGET[2]:.4f}"), ("empty", "1", f"{TARGET[2]:.4f}"), ("empty", "1", f"{LOOKALIKE[2]:.4f}"),
       ("target", "0", f"{TARGET[2]:.4f}"), ("empty", "1", f"{away[2]:.4f}")])
check("--actions indices", [(r["action"], r["step"], r["overruled"]) for r in rows],
      [("0", "0", "0"), ("1", "1", "1"), ("2", "2", "0"), ("3", "3", "0"), ("4", "4", "1")])
check("--actions places", [(r["depth0_argmax"], r["depth0"], r["depth1"]) for r in rows],
      [("target", "target", "target"), ("lookalike", "target", "target"), ("lookalike", "lookalike", "lookalike"),
       ("target", "target", "elsewhere"), ("target", "elsewhere", "elsewhere")])
# Voxels per side from an action's own fields, not assumed.
check("depth-1 voxel edge", round(float(dd.voxel_edge(stream[1], 1)), 6), 0.01875)

# failure_reasons sorts by the simulator's objects where the observations carry them (no
# points here at all: the old rule would find nothing and call every episode elsewhere).
fr_obs = obs(0)
episodes = [("distractor", [fr_obs, obs(1)], [Record("action", {"pose": np.array(list(LOOKALIKE) + [1, 0, 0, 0]),
                                                                "gripper_open": np.array(0, np.uint8)}, 0, 0)]),
            ("target", [fr_obs, obs(1)], [Record("action", {"pose": np.array(list(TARGET + [0, 0, 0.1]) + [1, 0, 0, 0]),
                                                            "gripper_open": np.array(1, np.uint8)}, 0, 0)]),
            ("elsewhere", [fr_obs, obs(1)], [Record("action", {"pose": np.array(list(ZONE) + [1, 0, 0, 0]),
                                                               "gripper_open": np.array(0, np.uint8)}, 0, 0)])]
for want, observations, actions in episodes:
    kind, _, _ = fr.classify([fr_obs], {"obs": observations, "actions": actions})
    check(f"failure_reasons with objects: {want}", kind, want)

if failures:
    sys.exit("FAIL: " + "; ".join(failures))
print(f"depth decisions ok: {len(cases) + 3} voxel centres placed, the table of {len(taken)} actions, "
      f"{len(episodes)} episodes sorted by the simulator's objects")
