#!/usr/bin/env python3
"""examples/analysis/first_actions.py on streams made with stream-pack, its table against values
worked out here by hand: the action of the asked step per episode, its distance to each object,
the nearest and its yaw, the rotation bins, the gripper, the distance to the target (the role-1
object), depth 0's voxel and the chosen voxels' Q values; with --demonstrations, the earliest frame's demonstrated transition of
that step per episode key in file order; an agent stream without objects is refused."""
import csv
import io
import os
import subprocess
import sys
import tempfile

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOOLS = os.environ.get("QTE_TOOLS") or os.path.join(SOURCE, "build", "tools")
SCRIPT = os.path.join(SOURCE, "examples", "analysis", "first_actions.py")
failures = []


def pack(path, rtype, *fields):
    with open(path, "ab") as out:
        subprocess.run([os.path.join(TOOLS, "stream-pack"), rtype, *fields], stdout=out, check=True)


def obs(path, step, objects=True):
    fields = [f"step:i32={step}"]
    if objects:
        fields += ["objects.names=base,phone", "objects.role:u8=0,1",
                   "objects.pose:f64[2,7]=0,0,0.75,0,0,0,1,0.3,0,0.75,0,0,0.5,0.8660254037844386",
                   "objects.box:f64[2,6]=-0.05,-0.09,-0.01,0.05,0.09,0.01,-0.04,-0.07,-0.005,0.04,0.07,0.005"]
    pack(path, "obs", *fields)


def action(path, step, x, y, gripper, d0="1,2,3", bins="0,36,20", q=("0.5", "0.25")):
    pack(path, "action", f"step:i32={step}", f"pose:f64={x},{y},0.8,0,0,0,1", f"gripper_open:u8={gripper}",
         f"depth0.index:i32={d0}", f"rotation_bins:i32={bins}", f"depth0.q_value:f32={q[0]}", f"depth1.q_value:f32={q[1]}")


def transition(path, key, frame, step, x, gripper, d0, bins):
    pack(path, "transition", f"episode_key:i64={key}", f"frame:i32={frame}", f"step:i32={step}", "demo:u8=1",
         f"target_pose:f64={x},0,0.8,0,0,0,1", f"gripper_open:u8={gripper}", f"depth0.index:i32={d0}",
         f"rotation_bins:i32={bins}")


def run(*args):
    return subprocess.run(["/usr/bin/python3", SCRIPT, *args], capture_output=True, text=True)


with tempfile.TemporaryDirectory() as tmp:
    agent, replay = os.path.join(tmp, "agent.rec"), os.path.join(tmp, "replay.rec")
    # Episode 0: the first action 1 cm from the base, gripper closed; episode 1: 2 cm from the
    # phone, open. Each episode's step-1 action is not the asked step's.
    obs(agent, 0); action(agent, 0, 0.01, 0.0, 0, d0="7,5,4")
    obs(agent, 1); action(agent, 1, 0.3, 0.0, 1)
    obs(agent, 0); action(agent, 0, 0.3, 0.02, 1, d0="9,9,4", bins="0,36,22", q=("0.75", "-0.125"))
    # The phone is turned by +60 degrees (quaternion z = sin 30, w = cos 30), the base not.
    # Demonstrations: episode key 5 twice at step 0 (frames 4 and 0: frame 0 counts), key 9 once;
    # a step-1 transition of key 5 in between.
    transition(replay, 5, 4, 0, 0.5, 0, "0,0,0", "0,0,0")
    transition(replay, 5, 0, 0, 0.0, 1, "7,5,4", "0,36,21")
    transition(replay, 5, 9, 1, 0.9, 0, "1,1,1", "0,0,0")
    transition(replay, 9, 0, 0, 0.25, 1, "8,9,4", "0,36,22")

    r = run("--demonstrations", replay, agent)
    if r.returncode != 0:
        failures.append(f"exit {r.returncode}: {r.stderr}")
    else:
        table = list(csv.DictReader(io.StringIO(r.stdout)))
        # Worked by hand: horizontal distances in cm; the demonstrated pose is (x, 0, 0.8).
        want = [
            {"episode": "0", "nearest": "base", "nearest_yaw_deg": "+0", "rotation_bins": "0 36 20",
             "gripper_open": "0", "depth0_index": "7 5 4", "q_depth0": "0.5000", "q_depth1": "0.2500",
             "cm_to_base": "1.0", "cm_to_phone": "29.0", "cm_to_target": "29.0",
             "cm_to_demonstrated": "1.0", "depth0_agrees": "1", "rotation_agrees": "0",
             "demonstrated_rotation_bins": "0 36 21",
             "demonstrated_gripper_open": "1"},
            {"episode": "1", "nearest": "phone", "nearest_yaw_deg": "+60", "rotation_bins": "0 36 22",
             "gripper_open": "1", "depth0_index": "9 9 4", "q_depth0": "0.7500", "q_depth1": "-0.1250",
             "cm_to_base": "30.1", "cm_to_phone": "2.0", "cm_to_target": "2.0",
             "cm_to_demonstrated": "5.4", "depth0_agrees": "0", "rotation_agrees": "1",
             "demonstrated_rotation_bins": "0 36 22",
             "demonstrated_gripper_open": "1"},
        ]
        if table != want:
            failures.append(f"table:\n{table}\nwanted:\n{want}")
        if ("nearest object: base 1, phone 1; gripper closed in 1; yaw bins 20 22; to the target: median 15.5 cm, "
                "within 3 cm in 1") not in r.stderr:
            failures.append(f"summary: {r.stderr}")

    r = run("--step", "1", agent)
    rows = list(csv.DictReader(io.StringIO(r.stdout)))
    if r.returncode != 0 or [row["nearest"] for row in rows] != ["phone"]:
        failures.append(f"--step 1: {r.returncode} {r.stdout} {r.stderr}")

    bare = os.path.join(tmp, "bare.rec")
    obs(bare, 0, objects=False); action(bare, 0, 0.0, 0.0, 1)
    r = run(bare)
    if r.returncode == 0 or "--objects" not in r.stderr or "Traceback" in r.stderr:
        failures.append(f"an agent stream without objects: exit {r.returncode}, {r.stderr!r}")

for f in failures:
    print("FAIL:", f)
if failures:
    sys.exit(1)
print("ok: first_actions.py")
