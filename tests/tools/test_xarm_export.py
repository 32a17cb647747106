#!/usr/bin/env python3
"""xarm-export: a planned move's file checked against an independent reading of the robot: joint
limits and the 180 deg/s speed limit from the URDF (parsed here), rows every 1/rate s that follow
the planned waypoints, and forward kinematics written here in NumPy from the URDF: the file's last
pose is the planner's last waypoint and reaches the action's pose. Gripper units 850 open, 0 closed.
A path faster than the arm is refused with the record named and no file left.
Run with a python3 that has NumPy (ctest uses /usr/bin/python3)."""
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
import importlib.util

import numpy as np

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOOLS = os.environ.get("QTE_TOOLS") or os.path.join(SOURCE, "build", "tools")
tmp = tempfile.mkdtemp(prefix="qte_xarm_")
sys.path.insert(0, os.path.join(SOURCE, "lib", "python"))
import qte_stream  # noqa: E402
BASE = np.array([-0.3, 0.0, 0.752])  # the robot's base in the world (DESIGN, world::SceneLayout)


def run(name, *args, stdin=None, ok=True):
    r = subprocess.run([os.path.join(TOOLS, name), *map(str, args)], input=stdin, capture_output=True)
    if ok and r.returncode != 0:
        sys.exit(f"FAIL: {name} {' '.join(map(str, args))} exited {r.returncode}: {r.stderr.decode()}")
    return r


# --- the robot, read from its URDF here ---------------------------------------------------
def rpy_matrix(r, p, y):
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def axis_angle(axis, a):
    axis = axis / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K


urdf = ET.parse(os.path.join(SOURCE, "lib", "robot", "xarm7.urdf")).getroot()
joints = {j.find("child").get("link"): j for j in urdf.findall("joint")}
chain, link = [], "tcp"
while link in joints:
    chain.insert(0, joints[link])
    link = joints[link].find("parent").get("link")
arm = [j for j in chain if j.get("type") == "revolute"]
lower = np.array([float(j.find("limit").get("lower")) for j in arm])
upper = np.array([float(j.find("limit").get("upper")) for j in arm])
speed = np.array([float(j.find("limit").get("velocity")) for j in arm])


def fk(q):
    """TCP position and rotation in the world for joint angles q (rad)."""
    T = np.eye(4)
    T[:3, 3] = BASE
    k = 0
    for j in chain:
        o = j.find("origin")
        step = np.eye(4)
        step[:3, :3] = rpy_matrix(*map(float, o.get("rpy").split()))
        step[:3, 3] = list(map(float, o.get("xyz").split()))
        T = T @ step
        if j.get("type") == "revolute":
            R = np.eye(4)
            R[:3, :3] = axis_angle(np.array(list(map(float, j.find("axis").get("xyz").split()))), q[k])
            T = T @ R
            k += 1
    return T[:3, 3], T[:3, :3]


def quat_matrix(x, y, z, w):
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


# --- a planned move: 8 cm sideways and 10 cm down from where the gripper is, then close -------
obs = run("sim-step", "--task", "reach_target", "--seed", 2, "--image-size", "64x64", stdin=b"").stdout
with open(os.path.join(tmp, "obs.rec"), "wb") as f:
    f.write(obs)
(o,) = [r for r in qte_stream.read_records(os.path.join(tmp, "obs.rec")) if r.type == "obs"]
failures = []
start_position, start_rotation = fk(o.fields["joint_positions"])
if np.abs(start_position - o.fields["gripper_pose"][:3]).max() > 1e-6:
    failures.append(f"the test's FK {start_position} disagrees with sim-step's gripper pose {o.fields['gripper_pose'][:3]}")
goal = o.fields["gripper_pose"].copy()
goal[:3] += [0.0, 0.08, -0.10]
action = run("stream-pack", "action", "pose:f64=" + ",".join(repr(float(v)) for v in goal), "gripper_open:u8=0").stdout
planned = run("plan-path", "--seed", 1, stdin=obs + action).stdout
with open(os.path.join(tmp, "planned.rec"), "wb") as f:
    f.write(planned)
(traj,) = [r for r in qte_stream.read_records(os.path.join(tmp, "planned.rec")) if r.type == "trajectory"]
if "failure" in traj.fields:
    sys.exit(f"FAIL: the planner found no path: {traj.fields['failure']}")
rate = 50
run("xarm-export", "--dir", os.path.join(tmp, "out"), "--rate", rate, os.path.join(tmp, "planned.rec"))
path = os.path.join(tmp, "out", f"{traj.index:06d}.xarm.csv")
lines = open(path).read().splitlines()
comments = [l for l in lines if l.startswith("#")]
header = lines[len(comments)]
rows = np.array([[float(x) for x in l.split(",")] for l in lines[len(comments) + 1:]])
if header != "time_s,j1_deg,j2_deg,j3_deg,j4_deg,j5_deg,j6_deg,j7_deg,gripper" or not comments:
    failures.append(f"header {header!r}")
t, q, gripper = rows[:-1, 0], np.radians(rows[:-1, 1:8]), rows[:, 8]
waypoint_t, waypoint_q = traj.fields["time_s"], traj.fields["joint_positions"]
if not np.allclose(np.diff(t[:-1]), 1 / rate, atol=1e-4) or abs(t[-1] - waypoint_t[-1]) > 1e-4:
    failures.append(f"rows are not every 1/{rate} s to the path's end: {t[:4]} ... {t[-2:]}")
if (q < lower - 1e-6).any() or (q > upper + 1e-6).any():
    failures.append("a row outside the joint limits")
speeds = np.abs(np.diff(q, axis=0)) / np.diff(t)[:, None]
if (speeds > speed * 1.01).any():
    failures.append(f"a row faster than the joints' limits: {speeds.max(axis=0)}")
for k in range(7):  # the rows follow the waypoints: interpolating the plan gives the file
    expected = np.interp(t, waypoint_t, waypoint_q[:, k])
    if np.abs(expected - q[:, k]).max() > 1e-6:  # 6 decimals of a degree
        failures.append(f"joint {k + 1} leaves the planned path by {np.abs(expected - q[:, k]).max()} rad")
end_position, end_rotation = fk(q[-1])
planned_end, _ = fk(waypoint_q[-1])
if np.abs(end_position - planned_end).max() > 1e-6:
    failures.append("the file's last pose is not the plan's")
if np.linalg.norm(end_position - goal[:3]) > 1e-3:
    failures.append(f"the last row reaches {end_position}, not the action's {goal[:3]}")
angle = np.degrees(np.arccos(np.clip((np.trace(end_rotation.T @ quat_matrix(*goal[3:])) - 1) / 2, -1, 1)))
if angle > 0.5:
    failures.append(f"the last row's gripper is {angle:.2f} deg off the action's orientation")
if not (gripper[:-1] == 850).all() or gripper[-1] != 0 or not np.array_equal(rows[-1, 1:8], rows[-2, 1:8]):
    failures.append(f"gripper column {gripper[:3]} ... {gripper[-2:]}: expected open during the move, closed after")

# The player reads the file (its dry run needs no robot and no SDK).
r = subprocess.run([sys.executable, os.path.join(SOURCE, "examples", "robot", "xarm_play.py"), "--dry-run", path],
                   capture_output=True, text=True)
if r.returncode != 0 or f"{len(rows)} rows" not in r.stdout or "850 -> 0" not in r.stdout:
    failures.append(f"xarm_play.py --dry-run: exit {r.returncode}, {r.stdout!r} {r.stderr!r}")

# A path faster than the arm (1 rad in 0.1 s, 573 deg/s) is refused, naming the record.
fast = run("stream-pack", "trajectory", "time_s:f64=0,0.1",
           "joint_positions:f64[2,7]=0,0,0,1,0,0,0,1,0,0,1,0,0,0").stdout
r = run("xarm-export", "--dir", os.path.join(tmp, "bad"), stdin=fast, ok=False)
err = r.stderr.decode()
if r.returncode != 1 or "record 0" not in err or "velocity_limit:joint1" not in err or err.count("\n") != 1 \
        or os.path.exists(os.path.join(tmp, "bad")):  # the directory it made goes again
    failures.append(f"too fast a path: exit {r.returncode}, {err!r}")
# A planner failure has no motion: skipped, said on stderr, exit 0.
r = run("xarm-export", "--dir", os.path.join(tmp, "none"), stdin=run("stream-pack", "trajectory", "failure=no_path").stdout)
if r.returncode != 0 or "no_path" not in r.stderr.decode() or os.listdir(os.path.join(tmp, "none")):
    failures.append(f"a failed plan: exit {r.returncode}, {r.stderr.decode()!r}")

if failures:
    print("\n".join("FAIL: " + f for f in failures))
    sys.exit(1)
print(f"ok: {len(rows)} rows at {rate} Hz, limits, speeds (max {np.degrees(speeds.max()):.0f} deg/s) and FK hold")
