#!/usr/bin/env python3
"""Where the agent went, episode by episode: the evidence for or against coarse ambiguity.

    failure_reasons.py EXPERTS.rec AGENT.rec [--label L] [--seed S] [--episodes]

EXPERTS.rec: the expert's demonstrations of the same scenes (demo-record --scenes eval with the
evaluation's seed); AGENT.rec: the agent's greedy episodes of them (sim-step, qte-select,
plan-path). Where the agent went is the first pose at which the gripper closes, or else the
last pose it chose. With the objects the simulator wrote (sim-step --objects, as
failure_reasons.sh runs it), the object it went for is the target or distractor that pose lies
on (ambiguity.py's object_at: within 2 cm of the object's bounding box or up to 10 cm above
it), as of the episode's first observation. In streams without them the objects are found in
the first observation's points (ambiguity.py's rule), the target is the object the expert
went for and the agent's the one nearest where it went, within 4 cm. Each episode is then one of
    success            the task was solved
    distractor         not solved, and the agent went for another object than the target (a
                       lookalike): what coarse ambiguity predicts
    target             not solved although it went for the target (a wrong height, rotation
                       or gripper command, or a failed action)
    elsewhere          at no object (with the simulator's objects: at no target or
                       distractor)
and the counts are printed as CSV: label, seed, episodes, the four kinds, and failed_actions (the
episodes that ended on a failed action: the planner's or the simulator's reason, any kind).
--episodes prints one line per episode on stderr: kind, distance to the nearest object, the
failure. Run with Debian's python3."""
import argparse
import csv
import sys
from collections import Counter

import numpy as np

sys.path.insert(0, __file__.rsplit("/", 2)[0] + "/lib/python")  # or installed: make install
from qte_stream import read_records  # noqa: E402
from ambiguity import box_centre, object_at, objects, task_objects  # noqa: E402  (one rule for what an object is)

NEAR_M = 0.04  # from a group of points (streams without objects)
MARGIN_M = 0.02  # around an object's bounding box (with the simulator's objects)


def scalar(record, name, default=None):
    if name not in record.fields:
        return default
    value = record.fields[name]
    return value if isinstance(value, str) else np.asarray(value).reshape(-1)[0]


def expert_episodes(path):
    episodes, current = [], []
    for r in read_records(path):
        if r.type == "obs":
            current.append(r)
        elif r.type == "episode" and current:
            episodes.append(current)
            current = []
    return episodes


def agent_episodes(path):
    """Per episode: its observations and the actions chosen after them."""
    episodes = []
    for r in read_records(path):
        if r.type == "obs" and int(scalar(r, "step")) == 0:
            episodes.append({"obs": [], "actions": []})
        if not episodes:
            continue
        if r.type == "obs":
            episodes[-1]["obs"].append(r)
        elif r.type == "action":
            episodes[-1]["actions"].append(r)
    return episodes


def went_for(poses_and_open, values=2):
    """Where the gripper went (xy, or xyz with values=3): its first closing pose, or else its last."""
    closing = [p for p, is_open in poses_and_open if not is_open]
    return np.asarray((closing or [poses_and_open[-1][0]])[0])[:values]


def nearest(found, xy):
    distances = [np.linalg.norm(c[:2] - xy) for c in found]
    i = int(np.argmin(distances))
    return i, distances[i]


KINDS = ["success", "distractor", "target", "elsewhere"]


def classify_by_poses(found, agent):
    """classify() with the simulator's objects (task_objects of the episode's first observation)."""
    last = agent["obs"][-1]
    failure = scalar(last, "failure", "")
    if not agent["actions"]:
        return ("success" if int(scalar(last, "success", 0)) else "elsewhere"), float("inf"), failure
    point = went_for([(a.fields["pose"], int(scalar(a, "gripper_open", 1))) for a in agent["actions"]], 3)
    distance = min((np.linalg.norm(box_centre(o)[:2] - point[:2]) for o in found), default=float("inf"))
    if int(scalar(last, "success", 0)):
        return "success", distance, failure
    chosen = object_at(found, point, MARGIN_M)
    if chosen is None:
        return "elsewhere", distance, failure
    return chosen.role, np.linalg.norm(box_centre(chosen)[:2] - point[:2]), failure


def classify(expert, agent):
    """(kind, distance from where the agent went to the nearest object, failure reason)."""
    with_poses = task_objects(agent["obs"][0]) if agent["obs"] else None
    if with_poses is not None:
        return classify_by_poses(with_poses, agent)
    found = objects(expert[0])
    last = agent["obs"][-1]
    failure = scalar(last, "failure", "")
    if not found or not agent["actions"]:  # nothing on the table to go for (reach_target's floating target)
        return ("success" if int(scalar(last, "success", 0)) else "elsewhere"), float("inf"), failure
    target, _ = nearest(found, went_for([(r.fields["gripper_pose"], int(scalar(r, "gripper_open"))) for r in expert]))
    chosen, distance = nearest(found, went_for([(a.fields["pose"], int(scalar(a, "gripper_open", 1)))
                                                for a in agent["actions"]]))
    if int(scalar(last, "success", 0)):
        return "success", distance, failure
    if distance > NEAR_M:
        return "elsewhere", distance, failure
    return ("distractor" if chosen != target else "target"), distance, failure


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("experts")
    parser.add_argument("agent")
    parser.add_argument("--label", default="")
    parser.add_argument("--seed", default="", help="the run's seed, for the seed column")
    parser.add_argument("--episodes", action="store_true", help="one line per episode on stderr")
    args = parser.parse_args()
    experts, agent = expert_episodes(args.experts), agent_episodes(args.agent)
    if len(experts) != len(agent):
        sys.exit(f"{len(experts)} expert episodes but {len(agent)} agent episodes: not the same scenes")
    for e, a in zip(experts, agent):
        if int(scalar(e[0], "episode_seed")) != int(scalar(a["obs"][0], "episode_seed")):
            sys.exit("the expert's and the agent's episodes are not of the same scenes (episode_seed differs)")
    results = [classify(e, a) for e, a in zip(experts, agent)]
    if args.episodes:
        for i, (kind, distance, failure) in enumerate(results):
            print(f"episode {i}: {kind}, {100 * distance:.1f} cm from the nearest object; {failure or 'no failure'}",
                  file=sys.stderr)
    kinds = Counter(kind for kind, _, _ in results)
    failed = sum(1 for _, _, failure in results if failure)
    out = csv.writer(sys.stdout, lineterminator="\n")
    out.writerow(["label", "seed", "episodes"] + KINDS + ["failed_actions"])
    out.writerow([args.label, args.seed, len(agent)] + [kinds[k] for k in KINDS] + [failed])


if __name__ == "__main__":
    main()
