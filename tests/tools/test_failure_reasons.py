#!/usr/bin/env python3
"""examples/analysis/failure_reasons.py sorts episodes by where the agent went: checked on a scene built
here by hand (three objects of points on the table, the expert over the first) against the rule
it documents: success; a distractor (the object it went for is not the expert's); the target
missed; elsewhere (over 4 cm from every object); the first closing pose decides a grasp; and a
table without objects. Then each reason from observations written before objects.held (what
the fingers stopped on): the first cause, one made good by a later grasp, a lookalike before
all, every failure name mapped; a target let go where the expert let one go is no drop.
(tests/tools/test_failure_reasons_run.sh: the reasons on a real scene.) Run with Debian's
python3 (NumPy)."""
import os
import sys

import numpy as np

SOURCE = os.environ.get("QTE_SOURCE") or os.path.join(os.path.dirname(__file__), "..", "..")
sys.path.insert(0, os.path.join(SOURCE, "examples", "analysis"))
import failure_reasons as fr  # noqa: E402
from qte_stream import Record  # noqa: E402  (failure_reasons put lib/python on the path)

TABLE = fr.objects.__globals__["TABLE_Z"]
OBJECTS = [np.array([0.10, -0.10]), np.array([0.20, 0.05]), np.array([0.05, 0.15])]  # the target first


def points(with_objects=True):
    """A 20 x 20 'image' of points: the table, and 30 points 2 cm above it around each object."""
    rng = np.random.default_rng(1)
    xyz = np.column_stack([rng.uniform(-0.05, 0.35, 400), rng.uniform(-0.3, 0.3, 400), np.full(400, TABLE)])
    if with_objects:
        for k, centre in enumerate(OBJECTS):
            xyz[k * 30:(k + 1) * 30, :2] = centre + rng.uniform(-0.01, 0.01, (30, 2))
            xyz[k * 30:(k + 1) * 30, 2] = TABLE + 0.02
    return xyz.reshape(20, 20, 3).astype(np.float32)


def obs(step, xy=(0.0, 0.0), gripper_open=1, success=0, failure="", with_objects=True):
    fields = {"front.points": points(with_objects), "gripper_pose": np.array([xy[0], xy[1], TABLE + 0.1, 1, 0, 0, 0]),
              "gripper_open": np.array(gripper_open, np.uint8), "step": np.array(step, np.int32),
              "success": np.array(success, np.uint8)}
    if failure:
        fields["failure"] = failure
    return Record("obs", fields, 0, 0)


def action(xy, gripper_open=1):
    return Record("action", {"pose": np.array([xy[0], xy[1], TABLE + 0.03, 1, 0, 0, 0]),
                             "gripper_open": np.array(gripper_open, np.uint8)}, 0, 0)


def episode(actions, **last):
    return {"obs": [obs(0)] + [obs(i + 1) for i in range(len(actions) - 1)] + [obs(len(actions), **last)],
            "actions": actions}


expert = [obs(0), obs(0, OBJECTS[0]), obs(1, OBJECTS[0], success=1)]
cases = [
    ("success", episode([action(OBJECTS[0])], success=1)),
    ("distractor", episode([action(OBJECTS[1] + 0.01)])),
    ("target", episode([action(OBJECTS[0])], failure="goal_in_collision: the gripper in the table")),
    ("elsewhere", episode([action(OBJECTS[2] + 0.05)])),  # 5 cm from the nearest object
    ("distractor", episode([action(OBJECTS[0]), action(OBJECTS[2], gripper_open=0), action(OBJECTS[0])])),
    ("target", episode([action(OBJECTS[2]), action(OBJECTS[0])])),  # no grasp: the last pose decides
]
failures = []
for want, agent in cases:
    kind, distance, failure = fr.classify(expert, agent)
    if kind != want:
        failures.append(f"expected {want}, got {kind} ({100 * distance:.1f} cm)")
kind, _, _ = fr.classify([obs(0, with_objects=False)], {"obs": [obs(0, with_objects=False), obs(1, success=1)],
                                                        "actions": [action(OBJECTS[0])]})
if kind != "success":
    failures.append(f"a table without objects: expected success, got {kind}")

# Reasons from the observations alone, in a stream written before objects.held: the gripper
# holds something when closed with the fingers stopped apart (over 1 mm).
def step(gripper_open=1, opening=0.085, failure="", success=0):
    fields = {"gripper_open": np.array(gripper_open, np.uint8), "gripper_opening_m": np.array(opening),
              "gripper_pose": np.array([0.3, 0.3, TABLE + 0.05, 1, 0, 0, 0]), "step": np.array(0, np.int32),
              "success": np.array(success, np.uint8)}
    if failure:
        fields["failure"] = failure
    return Record("obs", fields, 0, 0)


held, missed, opened = step(0, 0.07), step(0, 0.0), step(1)
reason_cases = [
    ("success", [step(), held, step(0, 0.07, success=1)], "target"),
    ("grasp_missed", [step(), missed, step(0, 0.0)], "elsewhere"),
    ("dropped", [step(), held, opened], "target"),
    ("no_path", [step(), held, opened, held, step(0, 0.07, failure="timeout")], "target"),  # made good by the grasp again
    ("grasp_missed", [step(), missed, opened, step(failure="goal_in_collision")], "elsewhere"),  # the first cause
    ("wrong_object", [step(), held, opened], "distractor"),  # went for a lookalike: whatever came after
    ("ik_failed", [step(), step(failure="ik_failed")], "elsewhere"),
    ("trajectory_refused", [step(), step(failure="joint_limits:joint2")], "elsewhere"),
    ("trajectory_refused", [step(), step(failure="invalid_trajectory:not_finite")], "elsewhere"),
    ("collision", [step(), step(failure="collision:link3-table")], "elsewhere"),
    ("other_failure", [step(), step(failure="something_new")], "elsewhere"),
    ("out_of_steps", [step(), step(), step()], "elsewhere"),
]
for want, observations, kind in reason_cases:
    got = fr.reason({"obs": observations, "actions": []}, kind)
    if got != want:
        failures.append(f"reason: expected {want}, got {got} ({kind}, {len(observations)} observations)")
if fr.reason({"obs": [step(), missed], "actions": []}, "elsewhere", grasping=False) != "out_of_steps":
    failures.append("a gripper closed on nothing in a task that needs no grasp counts as grasp_missed")
if set(fr.REASONS) != {want for want, _, _ in reason_cases} | {"pushed", "goal_in_collision", "no_path", "start_in_collision",
                                                               "outside_workspace", "invalid_pose",
                                                               "approach_blocked"}:
    failures.append(f"REASONS {fr.REASONS} and the cases tested differ")
for failure in ("goal_in_collision", "ik_failed", "no_path", "start_in_collision", "outside_workspace", "invalid_pose",
                "approach_blocked"):
    if fr.action_reason(failure) != failure:  # plan-path's own names
        failures.append(f"plan-path's {failure}: {fr.action_reason(failure)}")

# What is held: objects.held where the observation has it, else the object the closed gripper
# is on (scene_objects' held is None then).
def with_objects(at, held=None):
    o = step(0, 0.05)
    o.fields.update({"objects.names": "block,lookalike", "objects.role": np.array([1, 2], np.uint8),
                     "objects.pose": np.array([[0.3, 0.3, TABLE + 0.025, 0, 0, 0, 1], [0.1, 0.1, TABLE + 0.025, 0, 0, 0, 1]]),
                     "objects.box": np.array([[-0.025] * 3 + [0.025] * 3] * 2)})
    o.fields["gripper_pose"] = np.array([at[0], at[1], TABLE + 0.03, 1, 0, 0, 0])
    if held is not None:
        o.fields["objects.held"] = np.array(held, np.uint8)
    return o


for want, o in [("target", with_objects((0.3, 0.3))), ("distractor", with_objects((0.1, 0.1))),
                ("distractor", with_objects((0.3, 0.3), [0, 1])), (None, with_objects((0.3, 0.3), [0, 0]))]:
    if fr.held_role(o) != want:
        failures.append(f"held_role: expected {want}, got {fr.held_role(o)}")
if [o.held for o in fr.scene_objects(with_objects((0.3, 0.3)))] != [None, None]:
    failures.append("scene_objects without objects.held: held is not None")

# A grasp that held nothing is `pushed` when the move that closed the gripper shifted a target or
# distractor by over 1 cm, else grasp_missed; an `other` object moving does not count.
def closing_on_nothing(moved, dx, role=1):
    before, after = with_objects((0.3, 0.3), [0, 0]), with_objects((0.3, 0.3), [0, 0])
    before.fields["gripper_open"] = np.array(1, np.uint8)
    after.fields["objects.role"] = before.fields["objects.role"] = np.array([role, 2], np.uint8)
    after.fields["objects.pose"] = after.fields["objects.pose"].copy()
    after.fields["objects.pose"][moved, 0] += dx
    return {"obs": [before, after], "actions": []}


for want, moved, dx, role in [("pushed", 0, 0.03, 1), ("pushed", 1, -0.02, 1), ("grasp_missed", 0, 0.005, 1),
                              ("grasp_missed", 0, 0.03, 0)]:
    got = fr.reason(closing_on_nothing(moved, dx, role), "target")
    if got != want:
        failures.append(f"object {moved} (role {role}) moved {100 * dx:+.1f} cm by a grasp on nothing: expected {want}, got {got}")

# A target let go where the expert let one go on the scene (within 2 cm) was put down, not
# dropped: a block stacked as the expert stacks it, then a grasp that misses, is a grasp_missed.
def release(block_at):
    holding, opened = with_objects((0.3, 0.3), [1, 0]), with_objects((0.3, 0.3), [0, 0])
    opened.fields["gripper_open"] = np.array(1, np.uint8)
    opened.fields["objects.pose"] = opened.fields["objects.pose"].copy()
    opened.fields["objects.pose"][0, :3] = block_at
    return [holding, opened]


stacked = np.array([0.2, 0.0, TABLE + 0.075])
missed_after = with_objects((0.1, 0.1), [0, 0])  # closed on nothing, the stacked block where it was
missed_after.fields["objects.pose"] = missed_after.fields["objects.pose"].copy()
missed_after.fields["objects.pose"][0, :3] = stacked
if [list(p) for p in fr.placements([step()] + release(stacked))] != [list(stacked)]:
    failures.append(f"placements: expected [{list(stacked)}], got {fr.placements([step()] + release(stacked))}")
for want, block_at, after in [("out_of_steps", stacked + [0.01, 0.01, 0], []), ("dropped", stacked + [0.03, 0, 0], []),
                              ("dropped", stacked - [0, 0, 0.05], []), ("grasp_missed", stacked, [missed_after])]:
    got = fr.reason({"obs": [step()] + release(block_at) + after, "actions": []}, "target", placed=[stacked])
    if got != want:
        failures.append(f"a block let go {100 * np.linalg.norm(block_at - stacked):.1f} cm from the expert's: expected {want}, got {got}")
if fr.reason({"obs": [step()] + release(stacked), "actions": []}, "target") != "dropped":
    failures.append("a release with no expert placement to match is not dropped")

if failures:
    sys.exit("FAIL: " + "; ".join(failures))
print(f"failure reasons ok: {len(cases) + 1} episodes sorted as the rule says, {len(reason_cases) + 1} reasons, releases by the expert's placements")
