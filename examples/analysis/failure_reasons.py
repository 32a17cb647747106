#!/usr/bin/env python3
"""Where the agent went and why each episode failed, episode by episode.

    failure_reasons.py EXPERTS.rec AGENT.rec [--label L] [--seed S] [--episodes]
    failure_reasons.py EPISODES.rec [--label L] [--seed S] [--episodes]

EXPERTS.rec: the expert's demonstrations of the same scenes (demo-record --scenes eval with the
evaluation's seed); AGENT.rec: the agent's greedy episodes of them (sim-step, qte-select,
plan-path). With one stream, its own episodes are sorted (an expert's, demo-record --objects,
or an agent's), by the simulator's objects, which it must carry.

Where the agent went is the first pose at which the gripper closes, or else the last pose it
chose (for a stream without actions, an expert's, the gripper's pose in the first observation
with the gripper closed, else in the last). With the objects the simulator wrote (sim-step
--objects, as failure_reasons.sh runs it), the object it went for is the target or distractor
that pose lies on (ambiguity.py's object_at: within 2 cm of the object's bounding box or up to
10 cm above it), as of the episode's first observation. In streams without them the objects
are found in the first observation's points (ambiguity.py's rule), the target is the object the
expert went for and the agent's the one nearest where it went, within 4 cm. Each episode is
then one of
    success            the task was solved
    distractor         not solved, and the agent went for another object than the target (a
                       lookalike): what coarse ambiguity predicts
    target             not solved although it went for the target (a wrong height, rotation
                       or gripper command, or a failed action)
    elsewhere          at no object (with the simulator's objects: at no target or
                       distractor)

and has one reason (REASONS), the first cause in the episode that explains the failure:
    success            the task was solved
    wrong_object       it went for a lookalike (the distractor kind above), or the gripper
                       held an object that is no target and never held a target afterwards
  then, in the order they happened, the first of these not made good by a later grasp that
  held a target:
    pushed             the gripper closed and held nothing, on a task that needs a grasp, and
                       the move that closed it shifted a target or distractor by over 1 cm (the
                       way in swept into it; with the simulator's objects only)
    grasp_missed       the gripper closed and held nothing, on a task that needs a grasp (the
                       expert holds an object on the scene; always when sorting one stream)
    dropped            the gripper opened on a target it held, and the target did not come to
                       rest where the expert let one go on the same scene (within 2 cm, with
                       the simulator's objects; a block stacked where the expert stacks one
                       is a step of the task, not a drop)
    goal_in_collision, ik_failed, no_path, start_in_collision, outside_workspace, invalid_pose,
    approach_blocked   the planner found no trajectory (plan-path's failure; its timeout, no
                       path within the time budget, counts as no_path)
    trajectory_refused sim-step refused the trajectory (invalid_trajectory, joint_limits,
                       velocity_limit)
    collision          the arm hit the table or itself while moving (sim-step's collision)
    other_failure      an action failed for a reason not named above
  and if none:
    out_of_steps       the episode used its steps without any of the above
What the gripper holds is the observation's objects.held (sim-step --objects); in older streams
it holds something when closed with the fingers stopped apart (gripper_opening_m over 1 mm),
the object its pose lies on (a target where there are no objects to tell). An action failure
ends an episode (it is its last observation's failure).

The counts are printed as CSV: label, seed, episodes, the four kinds, failed_actions (the
episodes that ended on a failed action: the planner's or the simulator's reason, any kind) and
one column per reason but success (the success column already counts it; the reasons add up to
the episodes). --episodes prints one line per episode on stderr: reason, kind, distance to the
nearest object, the failure, and the expert's reason on that scene where its stream carries the
objects. Run with Debian's python3."""
import argparse
import csv
import os
import sys
from collections import Counter

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "lib", "python"))  # or installed: make install
from qte_stream import read_records, scene_objects  # noqa: E402
from ambiguity import box_centre, object_at, objects, task_objects  # noqa: E402  (one rule for what an object is)

NEAR_M = 0.04  # from a group of points (streams without objects)
MARGIN_M = 0.02  # around an object's bounding box (with the simulator's objects)
HOLDING_M = 0.001  # fingers closed this far apart or more stopped on something (streams without objects.held)
PUSHED_M = 0.01  # an object moved this far by the move that closed the gripper on nothing: pushed
PLACED_M = 0.02  # a target let go this near where the expert let one go on the scene was put down, not dropped


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


def starts_episode(obs):
    """An episode's first observation: frame 0 (step 0 in streams without frames; with an
    observation every control step, step 0 lasts a whole move)."""
    return int(scalar(obs, "frame", scalar(obs, "step"))) == 0


def agent_episodes(path):
    """Per episode: its observations and the actions chosen after them."""
    episodes = []
    for r in read_records(path):
        if r.type == "obs" and starts_episode(r):
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
    """classify() with the simulator's objects (task_objects of the episode's first observation).
    An episode without actions (an expert's) went where its observed gripper went."""
    last = agent["obs"][-1]
    failure = scalar(last, "failure", "")
    if agent["actions"]:
        poses = [(a.fields["pose"], int(scalar(a, "gripper_open", 1))) for a in agent["actions"]]
    else:
        poses = [(o.fields["gripper_pose"], int(scalar(o, "gripper_open", 1))) for o in agent["obs"][1:]]
    if not poses:
        return ("success" if int(scalar(last, "success", 0)) else "elsewhere"), float("inf"), failure
    point = went_for(poses, 3)
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


REASONS = ["success", "wrong_object", "pushed", "grasp_missed", "dropped", "goal_in_collision", "ik_failed", "no_path",
           "start_in_collision", "outside_workspace", "invalid_pose", "approach_blocked", "trajectory_refused", "collision",
           "other_failure", "out_of_steps"]
PLANNER_FAILURES = {"goal_in_collision", "ik_failed", "no_path", "start_in_collision", "outside_workspace",
                    "invalid_pose", "approach_blocked"}
REFUSED_TRAJECTORIES = {"invalid_trajectory", "joint_limits", "velocity_limit"}


def action_reason(failure):
    """The reason of a failure an observation carries (plan-path's, passed on, or sim-step's)."""
    name = failure.split(":", 1)[0].strip()
    if name == "timeout":  # RRT-Connect's time budget ran out: no path found in it
        return "no_path"
    if name in PLANNER_FAILURES:
        return name
    if name in REFUSED_TRAJECTORIES:
        return "trajectory_refused"
    return "collision" if name == "collision" else "other_failure"


def held_role(obs):
    """What the gripper holds in an observation: the held object's role (target, distractor,
    other), or None when it holds nothing."""
    found = scene_objects(obs)
    if found and found[0].held is not None:
        return next((o.role for o in found if o.held), None)
    # Older streams: closed, the fingers stopped on something; the object the gripper is on.
    if int(scalar(obs, "gripper_open", 1)) or float(scalar(obs, "gripper_opening_m", 0)) < HOLDING_M:
        return None
    on = object_at(found, obs.fields["gripper_pose"], MARGIN_M) if found else None
    return on.role if on is not None else "target"


def shifted(before, after):
    """Whether a target or distractor moved over PUSHED_M between two observations (False for
    streams without the simulator's objects)."""
    was, now = scene_objects(before), scene_objects(after)
    if not was or not now or [o.name for o in was] != [o.name for o in now]:
        return False
    return any(a.role in ("target", "distractor") and np.linalg.norm(np.asarray(b.pose[:3]) - np.asarray(a.pose[:3])) > PUSHED_M
               for a, b in zip(was, now))


def holds_something(observations):
    """Whether the gripper holds an object in any of the observations (the expert's, on a
    task that needs a grasp)."""
    return any(held_role(o) is not None for o in observations)


def released_at(before, after):
    """Where the target the gripper holds in `before` lies in `after`, the observation after it
    opened (None for streams without the simulator's objects)."""
    was, now = scene_objects(before), scene_objects(after)
    if not was or not now or [o.name for o in was] != [o.name for o in now]:
        return None
    return next((np.asarray(b.pose[:3], dtype=float) for a, b in zip(was, now) if a.held and a.role == "target"), None)


def placements(observations):
    """Where an episode (the expert's) let go of each target it held: the positions they lay at
    in the next observation."""
    found, holding = [], held_role(observations[0])
    for before, after in zip(observations, observations[1:]):
        now = held_role(after)
        if holding == "target" and now is None and (at := released_at(before, after)) is not None:
            found.append(at)
        holding = now
    return found


def reason(episode, kind, grasping=True, placed=()):
    """The episode's reason (REASONS; see the module's text), given its kind (classify());
    grasping: whether the task needs a grasp (an empty one is then a grasp_missed); placed:
    where the expert let go of targets on the scene (placements()), releases there are no drop."""
    observations = episode["obs"]
    if int(scalar(observations[-1], "success", 0)):
        return "success"
    if kind == "distractor":
        return "wrong_object"
    pending = []  # causes in the order they happened, since the last grasp that held a target
    holding = held_role(observations[0])
    for before, after in zip(observations, observations[1:]):
        now = held_role(after)
        if int(scalar(before, "gripper_open", 1)) and not int(scalar(after, "gripper_open", 1)):
            if now == "target":
                pending = []  # whatever went wrong before was made good
            elif now is not None:
                pending.append("wrong_object")
            elif grasping:
                pending.append("pushed" if shifted(before, after) else "grasp_missed")
        elif holding == "target" and now is None:
            at = released_at(before, after)
            if at is None or not any(np.linalg.norm(at - p) <= PLACED_M for p in placed):
                pending.append("dropped")
        failure = scalar(after, "failure", "")
        if failure:
            pending.append(action_reason(failure))
        holding = now
    return pending[0] if pending else "out_of_steps"


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("experts", help="the expert's episodes of the scenes (or, alone, the episodes to sort)")
    parser.add_argument("agent", nargs="?", help="the agent's episodes of the same scenes")
    parser.add_argument("--label", default="")
    parser.add_argument("--seed", default="", help="the run's seed, for the seed column")
    parser.add_argument("--episodes", action="store_true", help="one line per episode on stderr")
    args = parser.parse_args()
    if args.agent is None:  # one stream: its own episodes, by the objects they carry
        agent = agent_episodes(args.experts)
        if any(task_objects(a["obs"][0]) is None for a in agent):
            sys.exit(f"{args.experts}: its observations carry no objects: record it with --objects "
                     "(sim-step --objects, demo-record --objects) to sort it alone")
        results = [classify([], a) for a in agent]
        experts = [None] * len(agent)
    else:
        experts, agent = expert_episodes(args.experts), agent_episodes(args.agent)
        if len(experts) != len(agent):
            sys.exit(f"{len(experts)} expert episodes but {len(agent)} agent episodes: not the same scenes")
        for e, a in zip(experts, agent):
            if int(scalar(e[0], "episode_seed")) != int(scalar(a["obs"][0], "episode_seed")):
                sys.exit("the expert's and the agent's episodes are not of the same scenes (episode_seed differs)")
        results = [classify(e, a) for e, a in zip(experts, agent)]
    placed = [placements(e) if e is not None else () for e in experts]  # the expert's, per scene
    reasons = [reason(a, kind, e is None or holds_something(e), p)
               for a, (kind, _, _), e, p in zip(agent, results, experts, placed)]
    if args.episodes:
        for i, ((kind, distance, failure), why, expert, expert_placed) in enumerate(zip(results, reasons, experts, placed)):
            line = (f"episode {i}: {why} ({kind}, {100 * distance:.1f} cm from the nearest object; "
                    f"{failure or 'no failure'})")
            if expert is not None and task_objects(expert[0]) is not None:
                expert_episode = {"obs": expert, "actions": []}
                expert_kind = classify_by_poses(task_objects(expert[0]), expert_episode)[0]
                line += f"; the expert: {reason(expert_episode, expert_kind, placed=expert_placed)}"
            print(line, file=sys.stderr)
    kinds = Counter(kind for kind, _, _ in results)
    counts = Counter(reasons)
    failed = sum(1 for _, _, failure in results if failure)
    out = csv.writer(sys.stdout, lineterminator="\n")
    out.writerow(["label", "seed", "episodes"] + KINDS + ["failed_actions"] + REASONS[1:])
    out.writerow([args.label, args.seed, len(agent)] + [kinds[k] for k in KINDS] + [failed]
                 + [counts[r] for r in REASONS[1:]])


if __name__ == "__main__":
    main()
