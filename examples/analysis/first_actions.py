#!/usr/bin/env python3
"""Where an agent's actions of one step go: for every episode of an agent stream (sim-step
--objects | qte-select | plan-path, as failure_reasons.sh runs it), the action of step STEP
(0: the first), its horizontal distance to each of the scene's objects, the object it is
nearest and that object's yaw, the action's rotation bins and its gripper command. With --demonstrations REPLAY (keyframe's output for the same
scenes, in the same order) also the demonstrated keyframe of that step: how far the agent's
pose is from it, and whether depth 0's voxel, the rotation bins and the gripper agree.

A diagnosis, not a score: it tells an agent that goes to the right object and fails there from
one that goes somewhere else, and which step of the demonstrations it is imitating (an agent
that goes to a later keyframe's place with a later keyframe's gripper has taken one phase of
the task for another); and whether its rotation follows the object's (a rotation head that
gives one yaw bin whatever the object's yaw has not learned to read it).

Usage: first_actions.py [--step N] [--demonstrations REPLAY.rec] AGENT.rec > table.csv
A CSV row per episode, then on stderr a summary line. Run with Debian's python3 (NumPy)."""
import argparse
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "lib", "python"))  # or installed: make install
from qte_stream import read_records, scene_objects  # noqa: E402


def agent_actions(path, step):
    """Per episode, (the objects' names, their positions, the action of `step`), in order: an
    action is paired with the observation it answers (the last one before it)."""
    episodes, objects = [], None
    for record in read_records(path):
        if record.type == "obs":
            objects = scene_objects(record)
        elif record.type == "action" and int(record.fields["step"]) == step:
            if objects is None:
                sys.exit(f"first_actions.py: {path}: an action with no observation with objects before it "
                         "(run sim-step with --objects)")
            positions = np.array([o.pose[:3] for o in objects], dtype=float).reshape(-1, 3)
            yaws = [yaw_deg(o.pose[3:7]) for o in objects]
            targets = [o.role == "target" for o in objects]
            episodes.append(([o.name for o in objects], positions, yaws, record.fields, targets))
    return episodes


def yaw_deg(quaternion):
    """The heading of a pose's x axis about the world's z, degrees in (-180, 180]."""
    x, y, z, w = (float(v) for v in quaternion)
    return float(np.degrees(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))))


def demonstrated(path, step):
    """Per demonstrated episode (in file order), its transition of `step` from the earliest
    frame: the keyframe a demonstration went to at that step."""
    chosen, order = {}, []
    for record in read_records(path):
        f = record.fields
        if record.type != "transition" or int(f["demo"]) != 1 or int(f["step"]) != step:
            continue
        key = int(f["episode_key"])
        if key not in chosen:
            order.append(key)
        if key not in chosen or int(f["frame"]) < int(chosen[key]["frame"]):
            chosen[key] = f
    return [chosen[k] for k in order]


def rows(episodes, demos):
    for i, (names, positions, yaws, action, targets) in enumerate(episodes):
        pose = np.asarray(action["pose"], dtype=float)
        distances = [float(np.linalg.norm(pose[:2] - p[:2])) for p in positions]
        nearest = int(np.argmin(distances)) if names else None
        row = {"episode": i,
               "nearest": names[nearest] if names else "",
               "nearest_yaw_deg": f"{yaws[nearest]:+.0f}" if names else "",
               "rotation_bins": " ".join(str(int(b)) for b in action["rotation_bins"]),
               "gripper_open": int(action["gripper_open"])}
        if "depth0.index" in action:
            row["depth0_index"] = " ".join(str(int(v)) for v in action["depth0.index"])
        for name in action:  # the chosen voxels' Q values, where the stream has them (depth<d>.q_value)
            if name.startswith("depth") and name.endswith(".q_value"):
                row[f"q_{name[:-len('.q_value')]}"] = f"{float(np.asarray(action[name]).reshape(-1)[0]):.4f}"
        row.update({f"cm_to_{n}": f"{100 * d:.1f}" for n, d in zip(names, distances)})
        to_targets = [d for d, is_target in zip(distances, targets) if is_target]
        row["cm_to_target"] = f"{100 * min(to_targets):.1f}" if to_targets else ""
        if demos is not None:
            d = demos[i]
            row["cm_to_demonstrated"] = f"{100 * np.linalg.norm(pose[:3] - np.asarray(d['target_pose'][:3])):.1f}"
            row["depth0_agrees"] = int(list(action["depth0.index"]) == list(d["depth0.index"]))
            row["rotation_agrees"] = int(list(action["rotation_bins"]) == list(d["rotation_bins"]))
            row["demonstrated_rotation_bins"] = " ".join(str(int(b)) for b in d["rotation_bins"])
            row["demonstrated_gripper_open"] = int(d["gripper_open"])
        yield row


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("agent")
    parser.add_argument("--step", type=int, default=0)
    parser.add_argument("--demonstrations")
    args = parser.parse_args(argv)
    episodes = agent_actions(args.agent, args.step)
    if not episodes:
        sys.exit(f"first_actions.py: {args.agent}: no action of step {args.step}")
    demos = demonstrated(args.demonstrations, args.step) if args.demonstrations else None
    if demos is not None and len(demos) < len(episodes):
        sys.exit(f"first_actions.py: {args.demonstrations}: {len(demos)} demonstrated episodes with a step "
                 f"{args.step}, fewer than the agent's {len(episodes)}")
    table = list(rows(episodes, demos))
    columns = list(dict.fromkeys(k for row in table for k in row))
    writer = csv.DictWriter(sys.stdout, columns, lineterminator="\n")
    writer.writeheader()
    writer.writerows(table)
    nearest = [row["nearest"] for row in table]
    counts = ", ".join(f"{n} {nearest.count(n)}" for n in dict.fromkeys(nearest))
    closed = sum(row["gripper_open"] == 0 for row in table)
    yaw_bins = sorted({int(row["rotation_bins"].split()[2]) for row in table})
    to_target = [float(row["cm_to_target"]) for row in table if row["cm_to_target"]]
    target = (f"; to the target: median {np.median(to_target):.1f} cm, within 3 cm in {sum(d < 3 for d in to_target)}"
              if to_target else "")
    print(f"step {args.step}: {len(table)} episodes; nearest object: {counts}; gripper closed in {closed}; "
          f"yaw bins {' '.join(map(str, yaw_bins))}{target}", file=sys.stderr)


if __name__ == "__main__":
    main()
