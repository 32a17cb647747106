#!/usr/bin/env python3
"""Which depth decided: per depth, where the agent's chosen voxels lie — on the target, on a
lookalike (a distractor) or elsewhere — and how often a finer depth overruled depth 0.

    depth_decisions.py AGENT.rec [--label L] [--step N] [--actions OUT.csv]

AGENT.rec: the agent's episodes, observations written with the simulator's objects (sim-step
--objects) and qte-select's actions after them (depth_decisions.sh records them). Each action
is judged against the observation it was chosen for. A voxel lies on an object when its
centre does by ambiguity.py's rule (object_at) with a margin of half the voxel's edge — inside
the object's bounding box grown by half a voxel (the voxel touches the box) or up to 10 cm
above it; a voxel on no target or distractor (on a zone, a bin, the table) is elsewhere.
Actions that exploration changed are left out; --step N keeps only the actions chosen at the
observations of step N (0: each episode's first decision).

Printed as CSV, one row per line of the table:
    depth<d>           the voxel chosen at depth d
    depth0_argmax      depth 0's best voxel by its own Q (depth0.argmax_index): where K = 1
                       would have gone
    overruled          of the actions whose chosen depth-0 voxel is not depth 0's argmax (a
                       finer depth overruled it; never with K = 1), the chosen voxel
    overruled_argmax   of those actions, depth 0's argmax
with the columns label, k (the actions' K), row, actions, target, lookalike, elsewhere and the
three shares (empty when a row has no actions).

--actions OUT.csv: one row per judged action, to find a decision worth looking at: action (its
index among the stream's actions, the n of qte-select --png's <n>.depth<d>.png), obs_record
(the index of its observation in the stream, stream-png's <record index>.front.rgb.png),
episode_seed, step, k, overruled (1 when the chosen depth-0 voxel is not depth 0's argmax),
held (what the gripper held when the action was chosen: target, distractor, other, or empty),
the action's gripper_open and pose_z (its height, m), and the place of each row depth<d> and
depth0_argmax: an episode's rows in order tell what the agent did once it held the object.
Run with Debian's python3."""
import argparse
import collections
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "lib", "python"))  # or installed: make install
from qte_stream import read_records  # noqa: E402
from ambiguity import object_at, task_objects  # noqa: E402  (one rule for where an action went)
from failure_reasons import held_role  # noqa: E402  (one rule for what the gripper holds)

PLACES = ["target", "lookalike", "elsewhere"]


def scalar(record, name, default=None):
    if name not in record.fields:
        return default
    return np.asarray(record.fields[name]).reshape(-1)[0]


def voxel_edge(action, d):
    """The edge of depth d's voxels: the grid's edge over its voxels per side, the voxels per side
    from the chosen voxel's index and centre (centre = min + (index + 0.5) * edge / V)."""
    bounds = np.asarray(action.fields[f"depth{d}.bounds"], np.float64)
    index = np.asarray(action.fields[f"depth{d}.index"], np.float64)
    centre = np.asarray(action.fields[f"depth{d}.centre"], np.float64)
    per_side = np.rint(bounds[3] * (index[0] + 0.5) / (centre[0] - bounds[0]))
    return bounds[3] / per_side


def centre_of(action, d, index):
    bounds = np.asarray(action.fields[f"depth{d}.bounds"], np.float64)
    return bounds[:3] + (np.asarray(index, np.float64) + 0.5) * voxel_edge(action, d)


def pose_z(action):
    """The action's height (m), None for an action written without its pose."""
    return float(np.asarray(action.fields["pose"]).reshape(-1)[2]) if "pose" in action.fields else None


def place(found, point, edge):
    """Where a voxel centre lies: 'target', 'lookalike' or 'elsewhere'."""
    on = object_at(found, point, edge / 2)
    return {"target": "target", "distractor": "lookalike"}.get(on.role if on else None, "elsewhere")


Decision = collections.namedtuple("Decision", "k rows action obs_record episode_seed step held gripper_open pose_z")


def decisions(records, step=None):
    """Per action the agent took greedily: a Decision (k, {row: place} and where it is in the
    stream), each judged against the objects of the observation before it."""
    found, out, n_actions = None, [], 0
    for r in records:
        if r.type == "action":
            n_actions += 1
        if r.type == "obs":
            found, obs = task_objects(r), r
            obs_step = int(scalar(r, "step", -1))
            if found is None:
                sys.exit(f"record {r.index}: an observation without objects.*: record the episodes with "
                         "sim-step --objects (depth_decisions.sh does)")
            continue
        if r.type != "action" or found is None or int(scalar(r, "explored", 0)):
            continue
        if step is not None and obs_step != step:
            continue
        rows, d = {}, 0
        while f"depth{d}.centre" in r.fields:
            rows[f"depth{d}"] = place(found, r.fields[f"depth{d}.centre"], voxel_edge(r, d))
            d += 1
        if "depth0.argmax_index" in r.fields:
            argmax = r.fields["depth0.argmax_index"]
            rows["depth0_argmax"] = place(found, centre_of(r, 0, argmax), voxel_edge(r, 0))
            if not np.array_equal(np.asarray(argmax), np.asarray(r.fields["depth0.index"])):
                rows["overruled"] = rows["depth0"]
                rows["overruled_argmax"] = rows["depth0_argmax"]
        out.append(Decision(int(scalar(r, "k", 1)), rows, n_actions - 1, obs.index,
                            int(scalar(obs, "episode_seed", -1)), obs_step, held_role(obs) or "empty",
                            int(scalar(r, "gripper_open", 1)), pose_z(r)))
    return out


def depth_rows(taken):
    """depth0 ... depth<D-1>, depth0_argmax: the rows every action has."""
    depths = max((int(name[5:]) for t in taken for name in t.rows if name[5:].isdigit()), default=-1) + 1
    return [f"depth{d}" for d in range(depths)] + ["depth0_argmax"]


def write_actions(taken, path):
    names = depth_rows(taken)
    with open(path + ".tmp", "w", newline="") as f:
        out = csv.writer(f, lineterminator="\n")
        out.writerow(["action", "obs_record", "episode_seed", "step", "k", "overruled", "held", "gripper_open",
                      "pose_z"] + names)
        for t in taken:
            z = "" if t.pose_z is None else f"{t.pose_z:.4f}"
            out.writerow([t.action, t.obs_record, t.episode_seed, t.step, t.k, int("overruled" in t.rows), t.held,
                          t.gripper_open, z] + [t.rows.get(name, "") for name in names])
    os.replace(path + ".tmp", path)  # whole or not at all


def table(taken):
    """{row: {place: count}} in the order of the module's text; the overruled rows always."""
    counts = {name: dict.fromkeys(PLACES, 0) for name in depth_rows(taken) + ["overruled", "overruled_argmax"]}
    for decision in taken:
        for name, where in decision.rows.items():
            counts[name][where] += 1
    return counts


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("agent")
    parser.add_argument("--label", default="")
    parser.add_argument("--step", type=int, default=None, help="only the actions chosen at observations of step N")
    parser.add_argument("--actions", help="also write one row per judged action to this CSV file")
    args = parser.parse_args()
    taken = decisions(read_records(args.agent), args.step)
    if not taken:
        sys.exit(f"{args.agent}: no greedy actions after observations with objects")
    if args.actions:
        write_actions(taken, args.actions)
    ks = sorted({t.k for t in taken})
    out = csv.writer(sys.stdout, lineterminator="\n")
    out.writerow(["label", "k", "row", "actions"] + PLACES + [p + "_share" for p in PLACES])
    for name, count in table(taken).items():
        n = sum(count.values())
        shares = [f"{count[p] / n:.3f}" if n else "" for p in PLACES]
        out.writerow([args.label, "/".join(map(str, ks)), name, n] + [count[p] for p in PLACES] + shares)


if __name__ == "__main__":
    main()
