#!/usr/bin/env python3
"""robot-step speaks the robot spool (formats/robot-spool.md) as its --help and the format say,
against a fake arm driver and camera recorder written here (a thread answering the spool as a
driver must: in order, each answer written under a '.' name and renamed, the frames sim-step
rendered copied for every capture, nothing answered once `stop` exists):

1. done: a reset and two steps judged by --outcomes (continue, success): one request counter
   for motions and captures, a capture after every motion; the motions in xarm-export's form
   (the reset one row at the ready pose in degrees, the steps sampled at --rate with the settle
   row last, the gripper in the driver's units); observations carry the joints and the gripper
   the driver REPORTED (0.5 deg and a few gripper units away from what was commanded), the
   camera's images and calibration, step/frame/time numbering, reward 100 and terminal at the
   end;
2. fault: a .fault answer ends the episode as failure "driver_fault:<its line>" without asking
   the judge (an --outcomes file with no lines), exit 0; the next reset goes on;
3. refused: a path outside the joint limits, one whose gripper dips below the table top, one
   not starting where the arm is, one too fast: the reason in the observation and NO motion file
   for that step; --speed 0.1 stretches a fast path in time (last time = duration x factor, no
   joint above 0.1 of the URDF's speed limits);
4. stop: --stop-file appearing while the driver is silent, --motion-timeout with no driver,
   SIGTERM, and a person's `touch spool/stop`: `stop` written, the unanswered request withdrawn,
   exit 1 with one line saying why (for SIGTERM: death by the signal);
5. a person at a pseudo-terminal (--terminal): prompts read from the master side, Enter starts
   the episode, 's' is a success, 'q' stops (exit 1 naming the terminal);
6. --judge CMD: 'CMD reset' before the start motion, 'CMD outcome' after the step's frame with
   QTE_TASK/SEED/EPISODE/STEP/MOTION/FRAME naming real files; its "failure knocked_over" in the
   observation; a command exiting 3 is one line naming it, exit 1;
7. --dry-run: no motion file at all, one "dry run, not sent" line per motion, captures still
   requested, observations at the path's last waypoint;
8. a judge saying "maybe" (or such a line in --outcomes): exit 1, one line naming the command
   (the file and line) and what was expected;
9. an answer robot-step cannot read (a gripper past open), --settle 0;
10. a driver never trusted: an answer that is a FIFO, a link to /dev/zero or larger than 64 KiB
   (a .done or a fault line) is one line and exit 1 within --motion-timeout; reached joints at
   1e308 deg or past a joint's limit stop the robot; reached joints 5 deg from the motion sent
   end the episode as a driver fault naming both; a fault beside a .done (or a recorder's
   .ready) wins; fault text that is not UTF-8 goes into the observation made valid and cut to
   200 bytes;
11. bounded judges and inputs: --outcomes /dev/zero or a directory, a judge command printing
   without end, standard input closed, --workspace of 1e300: one line each, in time;
12. the whole arm: a motion whose tool point stays inside --workspace but whose upper arm leaves
   it is refused before it is written; a --home outside the box is a usage error; a move back
   to the start pose through the table (from where the driver said the arm went) is never sent.

Assertions marked "BUG" are behaviour the spool format requires that robot-step did not have
when this test was written (see the commit message of this file).
Run with a python3 that has NumPy (ctest uses /usr/bin/python3)."""
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import xml.etree.ElementTree as ET

import numpy as np

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOOLS = os.environ.get("QTE_TOOLS") or os.path.join(SOURCE, "build", "tools")
tmp = tempfile.mkdtemp(prefix="qte_robot_step_")
sys.dont_write_bytecode = True
sys.path.insert(0, os.path.join(SOURCE, "lib", "python"))
import qte_stream  # noqa: E402

ANSWER_S = 10  # generous waits: the machine may be busy
failures = []
started = time.monotonic()
READY = np.array([0, -0.35, 0, 0.75, 0, 1.1, 0])  # world::SceneLayout::ready_joints(), rad
TABLE_TOP_Z = 0.752
CAMERA_POSE = "1.05,0,1.602,-0.63365,-0.63365,0.31383,0.31383"
REQUEST = re.compile(r"^(motion|capture)-(\d+)-(\d{6,})\.(xarm\.csv|request)$")
HEADER = "time_s,j1_deg,j2_deg,j3_deg,j4_deg,j5_deg,j6_deg,j7_deg,gripper"


def p(*names):
    return os.path.join(tmp, *names)


def check(condition, what):
    if not condition:
        failures.append(what)
    return condition


def check_bug(condition, what):
    """Behaviour formats/robot-spool.md requires that robot-step lacked when this was written."""
    return check(condition, "BUG (robot-step against formats/robot-spool.md): " + what)


def run(name, *args, stdin=None):
    r = subprocess.run([os.path.join(TOOLS, name), *map(str, args)], input=stdin, capture_output=True)
    if r.returncode != 0:
        sys.exit(f"FAIL: {name} {' '.join(map(str, args))} exited {r.returncode}: {r.stderr.decode()}")
    return r.stdout


def numbers(values):  # repr() round-trips float64 exactly
    return ",".join(repr(float(v)) for v in np.asarray(values, dtype=float).reshape(-1))


def read(path, mode="r"):
    with open(path, mode) as f:
        return f.read()


def put(directory, name, data):
    """A file as a driver writes it: whole under a '.' name, then renamed."""
    temporary = os.path.join(directory, "." + name + ".writing")
    with open(temporary, "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)
    os.replace(temporary, os.path.join(directory, name))


def wait_until(condition, timeout=ANSWER_S):
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.005)
    return True


def read_motion(text):
    """(comment lines, rows [N, 9]) of a motion file; problems raise ValueError."""
    lines = text.split("\n")
    if lines[-1] != "":
        raise ValueError("the last line does not end in \\n")
    lines = lines[:-1]
    comments = [line for line in lines if line.startswith("#")]
    body = [line for line in lines if not line.startswith("#")]
    if not body or body[0] != HEADER:
        raise ValueError(f"header {body[:1]}, not {HEADER}")
    rows = np.array([[float(v) for v in line.split(",")] for line in body[1:]])
    if rows.ndim != 2 or rows.shape[1] != 9 or len(rows) < 1:
        raise ValueError(f"rows of shape {rows.shape}")
    if rows[0, 0] != 0 or np.any(np.diff(rows[:, 0]) <= 0):
        raise ValueError("times do not start at 0 and increase")
    if np.any(rows[:, 8] != np.round(rows[:, 8])) or rows[:, 8].min() < 0 or rows[:, 8].max() > 850:
        raise ValueError("gripper not whole units 0..850")
    return comments, rows


# --- the arm's model: the URDF's limits and forward kinematics (checked against sim-step) --------
urdf = ET.parse(os.path.join(SOURCE, "lib", "robot", "xarm7.urdf")).getroot()
LIMITS = [urdf.find(f"joint[@name='joint{k + 1}']/limit") for k in range(7)]
LOWER = np.array([float(limit.get("lower")) for limit in LIMITS])
UPPER = np.array([float(limit.get("upper")) for limit in LIMITS])
SPEED = np.array([float(limit.get("velocity")) for limit in LIMITS])  # rad/s


def origin(joint):
    o = joint.find("origin")
    r, pitch, y = map(float, o.get("rpy").split())
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(pitch), math.sin(pitch), math.cos(y), math.sin(y)
    t = np.eye(4)
    t[:3, :3] = [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                 [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], [-sp, cp * sr, cp * cr]]
    t[:3, 3] = list(map(float, o.get("xyz").split()))
    return t


def tool_point(q):
    """The gripper's tool point in the world frame (the base on the table at (-0.3, 0, 0.752))."""
    t = np.eye(4)
    t[:3, 3] = [-0.3, 0, TABLE_TOP_Z]
    for k in range(7):
        turn = np.eye(4)
        turn[:2, :2] = [[math.cos(q[k]), -math.sin(q[k])], [math.sin(q[k]), math.cos(q[k])]]
        t = t @ origin(urdf.find(f"joint[@name='joint{k + 1}']")) @ turn
    return (t @ origin(urdf.find("joint[@name='tcp_joint']")))[:3, 3]


# --- frames the camera "takes": one sim-step observation saved as a camera saves it -----------------
reset_record = run("stream-pack", "reset", "task=reach_prism", "variation:i32=0", "seed:i64=5")
with open(p("sim_obs.rec"), "wb") as f:
    f.write(run("sim-step", "--image-size", "64x64", stdin=reset_record))
sim_obs = list(qte_stream.read_records(p("sim_obs.rec")))[0]
run("stream-png", "--depth-mm", "--dir", p("frames"), p("sim_obs.rec"))
COLOUR_PNG = read(p("frames", "000000.front.rgb.png"), "rb")
DEPTH_PNG = read(p("frames", "000000.front.depth_mm.png"), "rb")
K = sim_obs.fields["front.intrinsics"]
INTRINSICS = numbers([K[0, 0], K[1, 1], K[0, 2], K[1, 2]])
check(abs(K[0, 0] - 154.51 / 2) < 0.01 and abs(K[0, 2] - 31.5) < 1e-9,
      f"sim-step's 64x64 intrinsics {K.tolist()}: not the 128x128 ones (154.51, 63.5) halved")
check(np.allclose(tool_point(READY), sim_obs.fields["gripper_pose"][:3], atol=1e-6),
      f"this test's forward kinematics {tool_point(READY)} is not sim-step's {sim_obs.fields['gripper_pose'][:3]}")
CAMERA = ["--intrinsics", INTRINSICS, "--camera-pose", CAMERA_POSE]


# --- the fake robot: arm driver and camera recorder in one thread ------------------------------------
class FakeRobot(threading.Thread):
    """Answers the spool's requests in counter order. `motions` says how to answer each motion in
    turn ("done", "fault:<line>" or "silent": never, nor anything after it; "done" when the list
    runs out). A motion's .done reports its last row's joints + offset_deg and its gripper moved
    as GRIPPER_REPORTED says: what the real arm reports is never quite what was commanded.
    arm=False: a recorder alone (motions left unanswered)."""

    GRIPPER_REPORTED = {850: 840, 0: 7}

    def __init__(self, spool, motions=(), offset_deg=0.0, arm=True):
        super().__init__(daemon=True)
        self.spool, self.plan, self.offset_deg, self.arm = spool, list(motions), offset_deg, arm
        self.seen = []  # (n, kind, session) in the order first handled
        self.motions = {}  # n -> (comments, rows) as read when it was handled
        self.problems = []
        self.silent = self.halt = self.saw_stop = False
        os.makedirs(spool, exist_ok=True)
        self.start()

    def run(self):
        handled = set()
        while not self.halt:
            if os.path.exists(os.path.join(self.spool, "stop")):
                self.saw_stop = True  # answer nothing more
            elif not self.silent:
                pending = []
                for name in os.listdir(self.spool):
                    m = REQUEST.match(name)
                    if m and name not in handled:
                        pending.append((int(m.group(3)), m.group(1), m.group(2), name))
                for n, kind, session, name in sorted(pending):
                    if self.silent or os.path.exists(os.path.join(self.spool, "stop")):
                        break
                    handled.add(name)
                    self.seen.append((n, kind, session))
                    stem = name[: name.index(".")]
                    try:
                        self.motion(n, stem, read(os.path.join(self.spool, name))) if kind == "motion" \
                            else self.capture(stem, os.path.join(self.spool, name))
                    except (OSError, ValueError) as e:
                        self.problems.append(f"{name}: {e}")
            time.sleep(0.002)

    def motion(self, n, stem, text):
        comments, rows = read_motion(text)
        self.motions[n] = (comments, rows)
        if not self.arm:
            self.silent = True
            return
        how = self.plan.pop(0) if self.plan else "done"
        if how == "silent":
            self.silent = True
        elif how.startswith("fault:"):
            put(self.spool, stem + ".fault", how[len("fault:"):] + "\n")
        elif how.startswith("raw:"):  # an answer as a faulty driver might write it
            put(self.spool, stem + ".done", how[len("raw:"):] + "\n")
        else:
            degrees = rows[-1, 1:8] + self.offset_deg
            gripper = self.GRIPPER_REPORTED.get(int(rows[-1, 8]), int(rows[-1, 8]))
            put(self.spool, stem + ".done", ",".join(f"{d:.6f}" for d in degrees) + f",{gripper}\n")

    def capture(self, stem, request):
        if os.path.getsize(request) != 0:
            self.problems.append(f"{os.path.basename(request)}: not an empty file")
        put(self.spool, stem + ".color.png", COLOUR_PNG)
        put(self.spool, stem + ".depth.png", DEPTH_PNG)
        put(self.spool, stem + ".ready", b"")

    def end(self):
        self.halt = True
        self.join(5)
        for problem in self.problems:
            failures.append(f"fake driver on {os.path.basename(self.spool)}: {problem}")


class RobotStep:
    """robot-step on `records` (a list of streams) with --spool `spool` and the camera options;
    its observations and stderr lines once it has ended."""

    def __init__(self, name, spool, records, *options, env=None):
        self.name, self.spool = name, spool
        with open(p(name + ".in.rec"), "wb") as f:
            f.write(b"".join(records))
        with open(p(name + ".obs.rec"), "wb") as out, open(p(name + ".err"), "wb") as err:
            self.process = subprocess.Popen(
                [os.path.join(TOOLS, "robot-step"), "--spool", spool, *CAMERA, *map(str, options), p(name + ".in.rec")],
                stdin=subprocess.DEVNULL, stdout=out, stderr=err, env=env)
        self.session = self.process.pid
        self.code = None

    def end(self, timeout=30):
        try:
            self.code = self.process.wait(timeout)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.code = self.process.wait()
            failures.append(f"{self.name}: robot-step did not end within {timeout} s")
        self.stderr = read(p(self.name + ".err")).splitlines()
        try:
            self.obs = [r for r in qte_stream.read_records(p(self.name + ".obs.rec")) if r.type == "obs"]
        except qte_stream.StreamError as e:
            failures.append(f"{self.name}: its output: {e}")
            self.obs = []
        return self.code

    def request(self, kind, n):
        return f"{kind}-{self.session}-{n:06d}"

    def expect_exit(self, code, what):
        check(self.code == code, f"{self.name}: {what}: exit status {self.code}, expected {code}; stderr: {self.stderr}")

    def error_line(self):
        """The one error line: the last on stderr, every line robot-step's own."""
        check(all(line.startswith("robot-step: ") for line in self.stderr),
              f"{self.name}: stderr lines not each robot-step's one-line messages: {self.stderr}")
        return self.stderr[-1] if self.stderr else ""


def trajectory(times, joints, gripper_open=1):
    joints = np.asarray(joints, dtype=float).reshape(len(times), 7)
    return run("stream-pack", "trajectory", f"time_s:f64={numbers(times)}",
               f"joint_positions:f64[{len(times)},7]={numbers(joints)}", f"gripper_open:u8={gripper_open}")


def outcomes_file(name, *lines):
    with open(p(name), "w") as f:
        f.write("".join(line + "\n" for line in lines))
    return p(name)


def scalar(record, field):
    value = record.fields[field]
    return value if isinstance(value, str) else np.asarray(value).item()


def spool_names(spool):
    return sorted(os.listdir(spool))


def motion_files(spool):
    return sorted(f for f in os.listdir(spool) if f.endswith(".xarm.csv"))


NO_OUTCOMES = outcomes_file("no_outcomes.txt")  # a judge asked at all fails the run

# === 1. done: a reset and two steps, judged by a file =============================================
OFFSET_DEG = 0.5
offset = math.radians(OFFSET_DEG)
start1 = READY + offset  # where the driver said the reset left the arm
end1 = start1 + np.array([0.2, 0.1, 0, -0.1, 0, 0.1, 0.2])
start2 = end1 + offset
end2 = start2 + np.array([-0.1, 0.05, 0.1, 0.05, 0, -0.05, 0])
spool = p("spool_done")
robot = FakeRobot(spool, offset_deg=OFFSET_DEG)
done = RobotStep("done", spool, [reset_record, trajectory([0, 0.5], [start1, end1], 1),
                                 trajectory([0, 0.25, 0.5], [start2, (start2 + end2) / 2, end2], 0)],
                 "--outcomes", outcomes_file("continue_success.txt", "continue", "# judged by a person", "success"))
done.end()
robot.end()
done.expect_exit(0, "a reset and two steps")
check(all(line.startswith("robot-step: ") for line in done.stderr), f"done: stderr {done.stderr}")
expected_requests = [(0, "motion"), (1, "capture"), (2, "motion"), (3, "capture"), (4, "motion"), (5, "capture")]
check([(n, kind) for n, kind, _ in robot.seen] == expected_requests,
      f"done: requests (number, kind) {[(n, k) for n, k, _ in robot.seen]}, expected one counter {expected_requests}")
check(all(session == str(done.session) for _, _, session in robot.seen),
      f"done: request sessions {set(s for _, _, s in robot.seen)}, expected robot-step's pid {done.session}")
names = spool_names(spool)
expected_names = sorted([done.request("motion", n) + s for n in (0, 2, 4) for s in (".xarm.csv", ".done")] +
                        [done.request("capture", n) + s for n in (1, 3, 5)
                         for s in (".request", ".color.png", ".depth.png", ".ready")])
check(names == expected_names, f"done: the spool holds {names}, expected {expected_names} "
                               "(robot-step deletes nothing of the driver's and leaves no temporary name)")
# The motions, as xarm-export writes them: the reset one row at the ready pose in degrees, the
# gripper open; each step sampled at 100 Hz from the arm's reported joints, the gripper holding
# what the driver reported, the settle row last commanding the trajectory's gripper.
motions = [robot.motions.get(n) for n in (0, 2, 4)]
if check(all(motions), "done: the fake driver did not read all three motions"):
    (c0, reset_rows), (c1, rows1), (c2, rows2) = motions
    check(all(c and all(line.startswith("#") for line in c) for c in (c0, c1, c2)), "done: motions without comment lines")
    check(reset_rows.shape == (1, 9) and np.allclose(reset_rows[0, 1:8], np.degrees(READY), atol=1e-6)
          and reset_rows[0, 0] == 0 and reset_rows[0, 8] == 850,
          f"done: the reset motion {reset_rows.tolist()}: expected one row 0,<ready pose in degrees>,850")
    for rows, (t, q), (before, after) in ((rows1, ([0, 0.5], [start1, end1]), (840, 850)),
                                          (rows2, ([0, 0.25, 0.5], [start2, (start2 + end2) / 2, end2]), (840, 0))):
        times = np.round(np.arange(0, 0.5 + 1e-9, 0.01), 6)
        want = np.column_stack([np.interp(times, t, np.degrees(np.asarray(q)[:, k])) for k in range(7)])
        check(len(rows) == len(times) + 1 and np.allclose(rows[:-1, 0], times, atol=1e-6)
              and abs(rows[-1, 0] - 1.0) < 1e-6 and np.allclose(rows[:-1, 1:8], want, atol=2e-6)
              and np.allclose(rows[-1, 1:8], want[-1], atol=2e-6),
              f"done: a step's motion rows are not the path sampled at 100 Hz plus the settle row at 0.5 + 0.5 s "
              f"(first {rows[0].tolist()}, last {rows[-1].tolist()})")
        check(np.all(rows[:-1, 8] == before) and rows[-1, 8] == after,
              f"done: gripper column {sorted(set(rows[:, 8]))}, last {rows[-1, 8]}: expected {before} (the driver's "
              f"report) during the motion and {after} (the trajectory's gripper_open) in the settle row")
if check(len(done.obs) == 3, f"done: {len(done.obs)} observations, expected 3"):
    reported = [READY + offset, end1 + offset, end2 + offset]
    for i, (o, q) in enumerate(zip(done.obs, reported)):
        check(np.allclose(o.fields["joint_positions"], q, atol=1e-7),
              f"done: obs {i} joint_positions {o.fields['joint_positions'].tolist()}: not what the driver reported "
              f"({q.tolist()}: the commanded joints + {OFFSET_DEG} deg)")
        check(np.allclose(o.fields["gripper_pose"][:3], tool_point(q), atol=1e-6),
              f"done: obs {i} gripper_pose {o.fields['gripper_pose'][:3].tolist()}: not at the reported joints")
        check(np.array_equal(o.fields["front.rgb"], sim_obs.fields["front.rgb"]),
              f"done: obs {i} front.rgb is not the recorder's colour frame")
        sim_depth = np.nan_to_num(np.asarray(sim_obs.fields["front.depth"], dtype=np.float64))
        check(np.abs(o.fields["front.depth_mm"].astype(np.int64) - np.round(sim_depth * 1000)).max() <= 1,
              f"done: obs {i} front.depth_mm is not the recorder's depth frame")
        check(np.allclose(o.fields["front.intrinsics"], K) and
              np.allclose(o.fields["front.extrinsics"], sim_obs.fields["front.extrinsics"], atol=1e-4),
              f"done: obs {i} camera calibration is not --intrinsics/--camera-pose")
        check(scalar(o, "step") == i and scalar(o, "frame") == i and scalar(o, "episode_seed") == 5
              and scalar(o, "task") == "reach_prism" and scalar(o, "variation") == 0,
              f"done: obs {i} step {scalar(o, 'step')} frame {scalar(o, 'frame')} seed {scalar(o, 'episode_seed')}")
        check(abs(scalar(o, "time_s") - 1.0 * i) < 1e-6,
              f"done: obs {i} time_s {scalar(o, 'time_s')}, expected {1.0 * i} (each motion 0.5 s + 0.5 s settle)")
    check([round(scalar(o, "gripper_opening_m"), 9) for o in done.obs] == [0.084, 0.084, round(7 / 850 * 0.085, 9)]
          and [scalar(o, "gripper_open") for o in done.obs] == [1, 1, 0],
          f"done: gripper_opening_m {[scalar(o, 'gripper_opening_m') for o in done.obs]}: expected the reported "
          "840, 840 and 7 units of 850 (0.085 m)")
    ends = [(scalar(o, "reward"), scalar(o, "terminal"), scalar(o, "success")) for o in done.obs]
    check(ends == [(0, 0, 0), (0, 0, 0), (100, 1, 1)], f"done: (reward, terminal, success) {ends}")
    check(not any("failure" in o.fields for o in done.obs), "done: an observation with a failure")
check(len([line for line in done.stderr if "rows" in line]) == 3, f"done: not one stderr line per motion: {done.stderr}")

# === 2. fault: the driver's .fault ends the episode, the judge is not asked ========================
spool = p("spool_fault")
robot = FakeRobot(spool, motions=["done", "fault:collision detected", "done"])
fault = RobotStep("fault", spool, [reset_record, trajectory([0, 0.5], [READY, READY + [0.3, 0, 0, 0, 0, 0, 0]]),
                                   reset_record], "--outcomes", NO_OUTCOMES)
fault.end()
robot.end()
fault.expect_exit(0, "a driver fault (judge not asked: an empty --outcomes)")
if check(len(fault.obs) == 3, f"fault: {len(fault.obs)} observations, expected 3 (reset, faulted step, reset)"):
    o = fault.obs[1]
    check(o.fields.get("failure") == "driver_fault:collision detected",
          f"fault: failure {o.fields.get('failure')!r}, expected 'driver_fault:collision detected'")
    check((scalar(o, "reward"), scalar(o, "terminal"), scalar(o, "success")) == (0, 1, 0),
          "fault: the faulted step is not terminal without reward")
    check(scalar(fault.obs[2], "step") == 0 and scalar(fault.obs[2], "terminal") == 0, "fault: the reset after it")
check([(n, kind) for n, kind, _ in robot.seen] == [(0, "motion"), (1, "capture"), (2, "motion"), (3, "capture"),
                                                   (4, "motion"), (5, "capture")],
      f"fault: requests {[(n, k) for n, k, _ in robot.seen]}: expected a capture after the fault, then the reset")

# === 3. refused before sending, and --speed ========================================================
low = READY + [0, 0.8, 0, 0, 0, 0, 0]  # the tool point below the table top
check(tool_point(low)[2] < TABLE_TOP_Z - 0.02 and np.all(low >= LOWER) and np.all(low <= UPPER),
      f"the test's low pose is not below the table within the joint limits: {tool_point(low)}")
over = READY + [0, 0, 0, 3.25, 0, 0, 0]  # joint 4 past its upper limit (3.927)
check(over[3] > UPPER[3], "the test's pose over the limit is not")
refused_paths = [
    ("joint_limits:joint4", trajectory([0, 2], [READY, over])),
    ("workspace:", trajectory([0, 1, 2], [READY, low, READY])),  # above the table at both ends
    ("invalid_trajectory:does not start at the current joint positions",
     trajectory([0, 0.5], [READY + [0.01, 0, 0, 0, 0, 0, 0], READY + [0.2, 0, 0, 0, 0, 0, 0]])),
    ("velocity_limit:joint1", trajectory([0, 0.2], [READY, READY + [1.0, 0, 0, 0, 0, 0, 0]])),
]
spool = p("spool_refused")
robot = FakeRobot(spool)
refused = RobotStep("refused", spool, [r for _, path in refused_paths for r in (reset_record, path)],
                    "--outcomes", NO_OUTCOMES)
refused.end()
robot.end()
refused.expect_exit(0, "refused paths")
resets = [refused.request("motion", n) + ".xarm.csv" for n in (0, 3, 6, 9)]
check(motion_files(spool) == resets,
      f"refused: motion files {motion_files(spool)}: expected only the four resets {resets}, nothing for a refused step")
check(all(len(robot.motions[n][1]) == 1 for n in robot.motions), "refused: a motion of more than one row was sent")
if check(len(refused.obs) == 8, f"refused: {len(refused.obs)} observations, expected 8"):
    for (reason, _), o in zip(refused_paths, refused.obs[1::2]):
        got = o.fields.get("failure", "")
        check(got.startswith(reason) and (scalar(o, "reward"), scalar(o, "terminal")) == (0, 1),
              f"refused: failure {got!r} terminal {scalar(o, 'terminal')}, expected {reason!r}, terminal")
        check(np.allclose(o.fields["joint_positions"], READY, atol=1e-7), f"refused: the arm moved for {reason}")
    # The first place the arm leaves the box or meets the table: the tool point, or a finger's
    # collision sphere (which reaches lower), named with where it is and when.
    m = re.fullmatch(r"workspace:(\w+) at \((-?[\d.]+), (-?[\d.]+), (-?[\d.]+)\) at ([\d.]+) s",
                     refused.obs[3].fields.get("failure", ""))
    if check(m, f"refused: workspace failure {refused.obs[3].fields.get('failure')!r}: "
                "not 'workspace:<link> at (x, y, z) at T s'"):
        link = m.group(1)
        x, y, z, t = map(float, m.groups()[1:])
        q = np.interp(t, [0, 1, 2], [0, 0.8, 0]) * np.array([0, 1, 0, 0, 0, 0, 0]) + READY
        if link == "gripper":
            check(z < TABLE_TOP_Z and np.allclose(tool_point(q), [x, y, z], atol=2e-3),
                  f"refused: the workspace failure says the gripper is at {(x, y, z)} at {t} s; it is at {tool_point(q)}")
        else:
            check(link in ("left_finger", "right_finger") and z < TABLE_TOP_Z + 0.03
                  and np.linalg.norm(tool_point(q) - [x, y, z]) < 0.08 and tool_point(q)[2] > TABLE_TOP_Z - 0.01,
                  f"refused: the workspace failure names {link} at {(x, y, z)} at {t} s: expected a finger reaching the "
                  f"table before the tool point {tool_point(q)} does")

# --speed 0.1: a path at 1 rad/s on joint 1 (0.32 of its limit) is stretched by 1 / (0.1 pi).
fast_end = READY + [0.5, 0, 0, 0.3, 0, 0, 0]
spool = p("spool_speed")
robot = FakeRobot(spool)
speed = RobotStep("speed", spool, [reset_record, trajectory([0, 0.5], [READY, fast_end])],
                  "--speed", 0.1, "--outcomes", outcomes_file("success.txt", "success"))
speed.end()
robot.end()
speed.expect_exit(0, "--speed 0.1")
factor = max(np.abs(fast_end - READY) / 0.5 / (0.1 * SPEED))
if check(2 in robot.motions, "speed: the step's motion was not sent"):
    rows = robot.motions[2][1]
    check(abs(rows[-2, 0] - 0.5 * factor) < 2e-6 and abs(rows[-1, 0] - (0.5 * factor + 0.5)) < 2e-6,
          f"speed: the motion ends at {rows[-2, 0]} s (+ settle {rows[-1, 0]}), "
          f"expected 0.5 x {factor:.4f} = {0.5 * factor:.6f}")
    velocity = np.abs(np.diff(np.radians(rows[:-1, 1:8]), axis=0)) / np.diff(rows[:-1, 0])[:, None]
    check(np.all(velocity <= 0.1 * SPEED * 1.001),
          f"speed: joint speeds up to {(velocity / SPEED).max():.4f} of the URDF's limits, more than --speed 0.1")
    check(np.allclose(rows[-1, 1:8], np.degrees(fast_end), atol=2e-6), "speed: the stretched motion ends elsewhere")
if check(len(speed.obs) == 2, f"speed: {len(speed.obs)} observations"):
    check(abs(scalar(speed.obs[1], "time_s") - (0.5 * factor + 0.5)) < 1e-5 and scalar(speed.obs[1], "success") == 1,
          f"speed: obs time_s {scalar(speed.obs[1], 'time_s')}, expected the stretched motion's {0.5 * factor + 0.5}")

# === 4. stop ===========================================================================================
# --stop-file appearing while the driver never answers the step's motion.
spool = p("spool_stop_file")
stop_file = p("operator_stop")
robot = FakeRobot(spool, motions=["done", "silent"])
stopped = RobotStep("stop_file", spool, [reset_record, trajectory([0, 0.5], [READY, READY + [0.2, 0, 0, 0, 0, 0, 0]])],
                    "--stop-file", stop_file, "--outcomes", outcomes_file("continue.txt", "continue"))
step_motion = os.path.join(spool, stopped.request("motion", 2) + ".xarm.csv")
check(wait_until(lambda: 2 in robot.motions), "stop_file: the step's motion never reached the driver")
time.sleep(0.5)
with open(stop_file, "w"):
    pass
t = time.monotonic()
stopped.end()
took = time.monotonic() - t
robot.end()
stopped.expect_exit(1, "--stop-file appeared")
check(took < 2.0, f"stop_file: robot-step took {took:.2f} s to stop after the stop file appeared")
check(os.path.exists(os.path.join(spool, "stop")), "stop_file: spool/stop not written")
check(not os.path.exists(step_motion), "stop_file: the unanswered motion request was not withdrawn")
check(stop_file in stopped.error_line(), f"stop_file: the error line does not name the stop file: {stopped.stderr[-1:]}")
check(len(stopped.obs) == 1, f"stop_file: {len(stopped.obs)} observations, expected the reset's only")

# --motion-timeout 0.5 and no driver at all.
spool = p("spool_timeout")
os.makedirs(spool)
timeout = RobotStep("timeout", spool, [reset_record], "--motion-timeout", 0.5, "--outcomes", NO_OUTCOMES)
t = time.monotonic()
timeout.end()
took = time.monotonic() - t
timeout.expect_exit(1, "no driver, --motion-timeout 0.5")
check(0.5 <= took < 3.0, f"timeout: robot-step ended after {took:.2f} s, expected 0.5 s and a little")
check(os.path.exists(os.path.join(spool, "stop")), "timeout: spool/stop not written")
check(motion_files(spool) == [], f"timeout: the unanswered request was not withdrawn: {motion_files(spool)}")
line = timeout.error_line()
check("no answer" in line and "0.5" in line and timeout.request("motion", 0) in line,
      f"timeout: the error line does not say which request went unanswered in 0.5 s: {line!r}")


def stopped_while_waiting(name, stop_it):
    """robot-step waiting for the reset's motion, no driver; stop_it(run) stops it."""
    spool = p("spool_" + name)
    os.makedirs(spool)
    waiting = RobotStep(name, spool, [reset_record], "--outcomes", NO_OUTCOMES)
    motion = os.path.join(spool, waiting.request("motion", 0) + ".xarm.csv")
    check(wait_until(lambda: os.path.exists(motion)), f"{name}: the reset's motion request never appeared")
    time.sleep(0.2)
    stop_it(waiting, spool)
    t = time.monotonic()
    waiting.end()
    check(time.monotonic() - t < 2.0, f"{name}: robot-step took {time.monotonic() - t:.2f} s to stop")
    return waiting, spool, motion


# SIGTERM: dies of it, `stop` written; the format: "A robot-step killed outright (SIGKILL, power)
# cannot [withdraw the unanswered request]"; an interrupted one can and must.
term, spool, motion = stopped_while_waiting("sigterm", lambda r, s: r.process.send_signal(signal.SIGTERM))
check(term.code == -signal.SIGTERM, f"sigterm: exit {term.code}, expected death by SIGTERM")
check(os.path.exists(os.path.join(spool, "stop")) and "interrupted" in read(os.path.join(spool, "stop")),
      "sigterm: spool/stop not written (saying robot-step was interrupted)")
check_bug(not os.path.exists(motion), f"sigterm: the unanswered motion request {os.path.basename(motion)} "
                                      "was left in the spool (to be carried out once a person removes stop)")


# A person's `touch spool/stop` while robot-step waits: it ends, and withdraws its request too.
def person_stops(run_, spool):
    with open(os.path.join(spool, "stop"), "w"):
        pass


by_hand, spool, motion = stopped_while_waiting("stop_by_hand", person_stops)
by_hand.expect_exit(1, "spool/stop written by a person")
check(os.path.join(spool, "stop") in by_hand.error_line(), f"stop_by_hand: error line {by_hand.stderr[-1:]}")
check_bug(not os.path.exists(motion), f"stop_by_hand: the unanswered motion request {os.path.basename(motion)} "
                                      "was left in the spool (to be carried out once the person removes stop)")

# === 5. a person at a pseudo-terminal ================================================================


class Terminal:
    """The person's side of a pseudo-terminal: what robot-step prints, collected as it comes."""

    def __init__(self):
        self.master, self.slave = os.openpty()
        self.name = os.ttyname(self.slave)
        self.text = ""
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        while True:
            try:
                chunk = os.read(self.master, 4096)
            except OSError:
                return
            if not chunk:
                return
            self.text += chunk.decode(errors="replace")

    def answer(self, prompt, key, count=1):
        """Waits for the count-th `prompt`, then presses `key`."""
        ok = wait_until(lambda: self.text.count(prompt) >= count)
        time.sleep(0.05)
        os.write(self.master, key)
        return ok

    def close(self):
        os.close(self.slave)
        os.close(self.master)


steps = [trajectory([0, 0.5], [READY, READY + [0.2, 0, 0, 0, 0, 0, 0]])]
for case, step_key in (("person", b"s"), ("person_quits", b"q")):
    spool = p("spool_" + case)
    robot = FakeRobot(spool)
    terminal = Terminal()
    person = RobotStep(case, spool, [reset_record, *steps], "--terminal", terminal.name)
    check(terminal.answer("press Enter", b"\r"), f"{case}: no reset prompt on the terminal: {terminal.text!r}")
    check(terminal.answer("s = success", step_key), f"{case}: no step prompt on the terminal: {terminal.text!r}")
    person.end()
    robot.end()
    check("episode 0 of reach_prism (variation 0, scene seed 5)" in terminal.text and "step 1 of 10" in terminal.text,
          f"{case}: prompts {terminal.text!r}")
    terminal.close()
    if step_key == b"s":
        person.expect_exit(0, "a person pressing Enter then s")
        check(len(person.obs) == 2 and (scalar(person.obs[-1], "reward"), scalar(person.obs[-1], "success"),
                                        scalar(person.obs[-1], "terminal")) == (100, 1, 1),
              f"person: 's' did not give a successful last observation ({len(person.obs)} observations)")
    else:
        person.expect_exit(1, "a person pressing q")
        check(terminal.name in person.error_line() and "stopped by the person" in person.error_line(),
              f"person_quits: the error line does not name the terminal {terminal.name}: {person.stderr[-1:]}")

# Keys typed before a prompt are not its answer: an early Enter must not start the move home.
spool = p("spool_typed_ahead")
robot = FakeRobot(spool)
terminal = Terminal()
os.write(terminal.master, b"\r\r")
early = RobotStep("typed_ahead", spool, [reset_record, *steps], "--terminal", terminal.name)
check(wait_until(lambda: "press Enter" in terminal.text), f"typed_ahead: no reset prompt: {terminal.text!r}")
time.sleep(0.5)
check(not motion_files(spool), "typed_ahead: an Enter typed before the prompt started the move home")
terminal.answer("press Enter", b"\r")
terminal.answer("s = success", b"s")
early.end()
robot.end()
terminal.close()
early.expect_exit(0, "Enter and s pressed after their prompts")

# === 6. a judge command ==============================================================================
spool = p("spool_judge")
log = p("judge.log")
with open(p("judge.sh"), "w") as f:
    f.write(f"""#!/bin/sh
spool={spool}
motion=no frame=no
[ -n "${{QTE_MOTION-}}" ] && [ -f "$spool/$QTE_MOTION.xarm.csv" ] && [ -f "$spool/$QTE_MOTION.done" ] && motion=yes
[ -n "${{QTE_FRAME-}}" ] && [ -f "$QTE_FRAME" ] && frame=yes
motions=$(ls "$spool" | grep -c 'xarm.csv$')
echo "$1|${{QTE_TASK-}}|${{QTE_SEED-}}|${{QTE_EPISODE-}}|${{QTE_STEP-}}|${{QTE_MOTION-}}|${{QTE_FRAME-}}|\
$motion|$frame|$motions" >> {log}
case $1 in
  reset) ;;
  outcome) echo "failure knocked_over" ;;
  *) exit 2 ;;
esac
""")
robot = FakeRobot(spool)
judged = RobotStep("judge", spool, [reset_record, *steps, reset_record], "--judge", f"sh {p('judge.sh')}")
judged.end()
robot.end()
judged.expect_exit(0, "--judge")
if check(len(judged.obs) == 3, f"judge: {len(judged.obs)} observations, expected 3 (reset, step, reset)"):
    check(judged.obs[1].fields.get("failure") == "knocked_over" and scalar(judged.obs[1], "terminal") == 1
          and scalar(judged.obs[1], "reward") == 0, f"judge: failure {judged.obs[1].fields.get('failure')!r}")
calls = [line.split("|") for line in read(log).splitlines()] if os.path.exists(log) else []
if check([c[0] for c in calls] == ["reset", "outcome", "reset"], f"judge: calls {calls}"):
    reset_call, outcome_call, second_reset = calls
    check(second_reset[1:4] == ["reach_prism", "5", "1"] and second_reset[9] == "2",
          f"judge: the second reset saw {second_reset}: expected QTE_EPISODE 1, before its start motion "
          "(the first episode's two motion files only)")
    check(reset_call[1:4] == ["reach_prism", "5", "0"] and reset_call[9] == "0",
          f"judge: reset saw {reset_call}: expected QTE_TASK reach_prism, QTE_SEED 5, QTE_EPISODE 0, no motion sent yet")
    check(outcome_call[1:6] == ["reach_prism", "5", "0", "1", judged.request("motion", 2)],
          f"judge: outcome saw {outcome_call[1:6]}: expected QTE_STEP 1, QTE_MOTION {judged.request('motion', 2)}")
    check(outcome_call[7:9] == ["yes", "yes"], f"judge: at the outcome QTE_MOTION's file and .done answer "
                                               f"exist: {outcome_call[7]}; QTE_FRAME exists: {outcome_call[8]}")
    frame = outcome_call[6]
    check(os.path.basename(frame) == judged.request("capture", 3) + ".color.png"
          and read(frame, "rb")[:8] == b"\x89PNG\r\n\x1a\n",
          f"judge: QTE_FRAME {frame!r} is not the colour PNG of the capture after the motion")

with open(p("judge_exit3.sh"), "w") as f:
    f.write("case $1 in outcome) exit 3 ;; esac\n")
robot = FakeRobot(p("spool_judge_exit3"))
exit3 = RobotStep("judge_exit3", p("spool_judge_exit3"), [reset_record, *steps], "--judge", f"sh {p('judge_exit3.sh')}")
exit3.end()
robot.end()
exit3.expect_exit(1, "a judge exiting 3")
line = exit3.error_line()
check(f"sh {p('judge_exit3.sh')} outcome" in line and "3" in line,
      f"judge_exit3: the error line does not name the command and its exit status: {line!r}")

# === 7. --dry-run ======================================================================================
spool = p("spool_dry")
robot = FakeRobot(spool, arm=False)
dry_end1 = READY + [0.2, 0, 0, 0.1, 0, 0, 0]
dry_end2 = dry_end1 + [0, 0.1, 0, 0, 0, 0, -0.3]
dry = RobotStep("dry", spool, [reset_record, trajectory([0, 0.5], [READY, dry_end1]),
                               trajectory([0, 0.3, 0.6], [dry_end1, (dry_end1 + dry_end2) / 2, dry_end2], 0)],
                "--dry-run", "--outcomes", outcomes_file("two_continues.txt", "continue", "continue"))
dry.end()
robot.end()
dry.expect_exit(0, "--dry-run")
check(motion_files(spool) == [] and not robot.motions, f"dry: motion files written: {motion_files(spool)}")
dry_lines = [line for line in dry.stderr if "dry run, not sent" in line]
check(len(dry_lines) == 3 and len(dry.stderr) == 3, f"dry: expected one 'dry run, not sent' line per motion: {dry.stderr}")
check([(n, kind) for n, kind, _ in robot.seen] == [(0, "capture"), (1, "capture"), (2, "capture")],
      f"dry: requests {[(n, k) for n, k, _ in robot.seen]}: expected three captures")
if check(len(dry.obs) == 3, f"dry: {len(dry.obs)} observations"):
    for o, q in zip(dry.obs, (READY, dry_end1, dry_end2)):
        check(np.allclose(o.fields["joint_positions"], q, atol=1e-9),
              f"dry: obs joint_positions {o.fields['joint_positions'].tolist()}, expected the path's last {q.tolist()}")
    check([scalar(o, "gripper_open") for o in dry.obs] == [1, 1, 0], "dry: the gripper is not as commanded")

# === 8. a judge that says neither success, failure nor continue =========================================
with open(p("judge_maybe.sh"), "w") as f:
    f.write("case $1 in outcome) echo maybe ;; esac\n")
for case, options, names in (
        ("judge_maybe", ["--judge", f"sh {p('judge_maybe.sh')}"], [f"the judge command 'sh {p('judge_maybe.sh')} outcome'"]),
        ("outcomes_maybe", ["--outcomes", outcomes_file("maybe.txt", "# a person's notes", "maybe")],
         [p("maybe.txt"), "line 2"])):
    robot = FakeRobot(p("spool_" + case))
    maybe = RobotStep(case, p("spool_" + case), [reset_record, *steps], *options)
    maybe.end()
    robot.end()
    maybe.expect_exit(1, "an outcome 'maybe'")
    line = maybe.error_line()
    check(all(n in line for n in names) and "expected success, failure [reason] or continue" in line and "maybe" in line,
          f"{case}: the error line {line!r} does not name {names} and what was expected")

# === 9. a driver's answer robot-step cannot read, and settings the drivers would refuse =============
spool = p("spool_garbled")
robot = FakeRobot(spool, motions=["done", "raw:0,-20,0,43,0,63,0,851"])  # a gripper past open
garbled = RobotStep("garbled", spool, [reset_record, *steps], "--outcomes", outcomes_file("garbled.txt", "continue"))
garbled.end()
robot.end()
garbled.expect_exit(1, "a .done robot-step cannot read")
check(os.path.exists(os.path.join(spool, "stop")), "garbled: an unreadable answer did not write stop")
check("0 to 850" in garbled.error_line() and garbled.request("motion", 2) in garbled.error_line(),
      f"garbled: the error line {garbled.error_line()!r} does not name the answer and what was expected")
settle = subprocess.run([os.path.join(TOOLS, "robot-step"), "--spool", p("spool_settle"), *CAMERA, "--settle", "0"],
                        input=b"", capture_output=True)
check(settle.returncode == 2 and b"--settle" in settle.stderr,
      f"--settle 0 (a gripper row at the motion's last time, which drivers refuse): exit {settle.returncode}, {settle.stderr!r}")

# === 10. a driver never trusted ==========================================================================
class OddDriver(FakeRobot):
    """A driver whose answer to the step's motion (request 2) is made by `answer(spool, stem)`."""

    def __init__(self, spool, answer):
        self.answer = answer
        super().__init__(spool)

    def motion(self, n, stem, text):
        if n == 2:
            self.motions[n] = read_motion(text)
            self.answer(self.spool, stem)
        else:
            super().motion(n, stem, text)


def fifo_answer(spool, stem):
    os.mkfifo(os.path.join(spool, stem + ".done"))


def zero_answer(spool, stem):
    os.symlink("/dev/zero", os.path.join(spool, stem + ".done"))


def huge_answer(spool, stem):  # 300 MB, sparse: written in no time
    with open(os.path.join(spool, "." + stem), "wb") as f:
        f.truncate(300 << 20)
    os.replace(os.path.join(spool, "." + stem), os.path.join(spool, stem + ".done"))


def huge_fault(spool, stem):  # one line of 200 MB
    with open(os.path.join(spool, "." + stem), "wb") as f:
        f.write(b"x" * (200 << 20))
    os.replace(os.path.join(spool, "." + stem), os.path.join(spool, stem + ".fault"))


def lie(degrees):
    return lambda spool, stem: put(spool, stem + ".done", ",".join(str(d) for d in degrees) + ",850\n")


def fault_and_done(spool, stem):
    """Both answers at once: the arm faulted, and a confused driver also said done."""
    put(spool, "." + stem + ".f", "collision detected\n")
    put(spool, "." + stem + ".d", ",".join(f"{d:.6f}" for d in np.degrees(READY + [0.2, 0, 0, 0, 0, 0, 0])) + ",850\n")
    os.replace(os.path.join(spool, "." + stem + ".d"), os.path.join(spool, stem + ".done"))
    os.replace(os.path.join(spool, "." + stem + ".f"), os.path.join(spool, stem + ".fault"))


def odd_run(case, answer, outcomes=("continue",)):
    spool = p("spool_" + case)
    robot = OddDriver(spool, answer)
    r = RobotStep(case, spool, [reset_record, *steps], "--motion-timeout", 20,
                  "--outcomes", outcomes_file(case + ".txt", *outcomes))
    t = time.monotonic()
    r.end(timeout=40)
    r.took = time.monotonic() - t
    robot.end()
    return r, spool


for case, answer, words in (("answer_fifo", fifo_answer, "a FIFO, expected a regular file"),
                            ("answer_zero", zero_answer, "a device, expected a regular file"),
                            ("answer_huge", huge_answer, "larger than 64 KiB"),
                            ("fault_huge", huge_fault, "larger than 64 KiB"),
                            ("answer_1e308", lie([0, -20, 0, 1e308, 0, 63, 0]), "joint 4 reported at"),
                            ("answer_past_limit", lie([0, -20, 0, 250, 0, 63, 0]), "outside its limits")):
    r, spool = odd_run(case, answer)
    r.expect_exit(1, f"a driver's answer {case}")
    line = r.error_line()
    check(words in line and r.request("motion", 2) in line,
          f"{case}: the error line {line!r} does not name the answer file and say {words!r}")
    check(r.took < 15, f"{case}: robot-step took {r.took:.1f} s (--motion-timeout 20): it must not wait on the answer")
    check(os.path.exists(os.path.join(spool, "stop")), f"{case}: stop not written")
    check(len(r.obs) == 1, f"{case}: {len(r.obs)} observations: the step's answer went into one")

# Reached 5 deg away from the motion's end: a driver fault naming both poses, the episode over.
target = np.degrees(READY + [0.2, 0, 0, 0, 0, 0, 0])
astray, _ = odd_run("answer_astray", lie(target + [5, 0, 0, 0, 0, 0, 0]), outcomes=())
astray.expect_exit(0, "reached 5 deg from the motion sent")
if check(len(astray.obs) == 2, f"answer_astray: {len(astray.obs)} observations"):
    failure = astray.obs[1].fields.get("failure", "")
    check(failure.startswith("driver_fault:reached ") and f"{target[0] + 5:.1f}" in failure
          and f"{target[0]:.1f}" in failure and "2 deg" in failure and scalar(astray.obs[1], "terminal") == 1,
          f"answer_astray: failure {failure!r}: expected a driver fault with both poses and the 2 deg tolerance")
    check(np.allclose(astray.obs[1].fields["joint_positions"], np.radians(target + [5, 0, 0, 0, 0, 0, 0]), atol=1e-6),
          "answer_astray: the observation's joints are not where the driver says the arm is")

both, _ = odd_run("fault_and_done", fault_and_done, outcomes=())
both.expect_exit(0, "a .fault beside a .done")
check(len(both.obs) == 2 and both.obs[1].fields.get("failure") == "driver_fault:collision detected",
      f"fault_and_done: failure {both.obs[1].fields.get('failure') if len(both.obs) == 2 else len(both.obs)}: the fault must win")

bad_text = b"gripper \xff\xfe jammed \xc3\x28 " + "\u00e9".encode() * 300
mangled, _ = odd_run("fault_not_utf8", lambda spool, stem: put(spool, stem + ".fault", bad_text + b"\n"), outcomes=())
mangled.expect_exit(0, "fault text that is not UTF-8")
if check(len(mangled.obs) == 2, f"fault_not_utf8: {len(mangled.obs)} observations"):
    failure = mangled.obs[1].fields.get("failure", "")
    raw = failure.encode("utf-8", "surrogateescape")  # the reader keeps bytes that are not UTF-8 so
    check(failure.startswith("driver_fault:gripper ?? jammed ?( ") and len(raw) <= len("driver_fault:") + 200
          and raw.decode("utf-8", "replace") == failure and failure.endswith("\u00e9"),
          f"fault_not_utf8: failure {failure[:60]!r}... ({len(raw)} bytes): expected the bad bytes as '?', "
          "cut at a character to 200 bytes")


class TwoAnswerRecorder(FakeRobot):
    """A recorder that answers the step's capture (request 3) with both .ready and .fault."""

    def capture(self, stem, request):
        super().capture(stem, request)
        if stem.endswith("-000003"):
            put(self.spool, stem + ".fault", "camera unplugged\n")


spool = p("spool_ready_and_fault")
robot = TwoAnswerRecorder(spool)
ready_fault = RobotStep("ready_and_fault", spool, [reset_record, *steps], "--outcomes", NO_OUTCOMES)
ready_fault.end()
robot.end()
ready_fault.expect_exit(1, "a recorder's .fault beside its .ready")
check("camera unplugged" in ready_fault.error_line(),
      f"ready_and_fault: the error line {ready_fault.error_line()!r} does not give the recorder's fault")

# === 11. bounded judges and inputs =======================================================================
os.makedirs(p("outcomes_dir"))
for case, options, words in (("outcomes_zero", ["--outcomes", "/dev/zero"], "/dev/zero: line 1 is longer than 4 KiB"),
                             ("outcomes_dir", ["--outcomes", p("outcomes_dir")], "a directory"),
                             ("judge_endless", ["--judge", "yes 2>/dev/null"], "printed more than 64 KiB")):
    robot = FakeRobot(p("spool_" + case))
    r = RobotStep(case, p("spool_" + case), [reset_record, *steps], *options)
    r.end(timeout=20)
    robot.end()
    r.expect_exit(1, case)
    check(words in r.error_line(), f"{case}: the error line {r.error_line()!r} does not say {words!r}")

closed = subprocess.run([os.path.join(TOOLS, "robot-step"), "--spool", p("spool_closed"), *CAMERA,
                         "--outcomes", outcomes_file("closed.txt", "continue")],
                        stdin=subprocess.DEVNULL, capture_output=True, timeout=20,
                        preexec_fn=lambda: os.close(0))
check(closed.returncode == 2 and b"standard input is closed" in closed.stderr and not closed.stdout,
      f"stdin closed: exit {closed.returncode}, {closed.stderr!r}: expected a usage error saying so "
      "(not the outcomes file read as the record stream)")
wide = subprocess.run([os.path.join(TOOLS, "robot-step"), "--spool", p("spool_wide"), *CAMERA,
                       "--workspace", "-1e300,-1e300,-1e300,1e300,1e300,1e300"], input=b"", capture_output=True)
check(wide.returncode == 2 and b"--workspace" in wide.stderr and b"10 m" in wide.stderr,
      f"--workspace of 1e300: exit {wide.returncode}, {wide.stderr!r}")

# === 12. the whole arm ======================================================================================
# Joint 2 back and joint 4 bent: the tool point stays over the table, the upper arm (link3)
# swings behind the base, past a box whose back wall is at x = -0.45.
BOX = "-0.45,-0.5,0.752,0.7,0.5,1.6"
lean = READY + [0, -0.3, 0, 0.3, 0, 0, 0]
check(-0.45 < tool_point(lean)[0] < 0.7 and TABLE_TOP_Z < tool_point(lean)[2] < 1.6,
      f"the test's leaning pose has its tool point {tool_point(lean)} outside the box")
spool = p("spool_arm")
robot = FakeRobot(spool)
arm = RobotStep("arm", spool, [reset_record, trajectory([0, 1], [READY, lean])], "--workspace", BOX,
                "--outcomes", NO_OUTCOMES)
arm.end()
robot.end()
arm.expect_exit(0, "a motion whose upper arm leaves the box")
check(motion_files(spool) == [arm.request("motion", 0) + ".xarm.csv"],
      f"arm: motion files {motion_files(spool)}: the refused motion was written")
if check(len(arm.obs) == 2, f"arm: {len(arm.obs)} observations"):
    failure = arm.obs[1].fields.get("failure", "")
    m = re.fullmatch(r"workspace:(link\d) at \((-?[\d.]+), (-?[\d.]+), (-?[\d.]+)\) at ([\d.]+) s", failure)
    check(m and m.group(1) in ("link2", "link3", "link4") and float(m.group(2)) < -0.39,
          f"arm: failure {failure!r}: expected an upper-arm link behind x = -0.45")

narrow = subprocess.run([os.path.join(TOOLS, "robot-step"), "--spool", p("spool_narrow"), *CAMERA,
                         "--workspace", "-0.35,-0.5,0.752,0.7,0.5,1.6", "--outcomes", NO_OUTCOMES],
                        input=reset_record, capture_output=True)
check(narrow.returncode == 2 and b"--home" in narrow.stderr and b"link" in narrow.stderr
      and not os.listdir(p("spool_narrow")),
      f"a --home whose arm is outside --workspace: exit {narrow.returncode}, {narrow.stderr!r}, spool "
      f"{os.listdir(p('spool_narrow')) if os.path.isdir(p('spool_narrow')) else None}")

# The driver says the step left the fingers in the table (a fault: 5 deg off); going home from
# there along the joint-space line would drag them through it: the second reset sends nothing.
low_deg = np.degrees(READY + [0, 0.75, 0, 0, 0, 0, 0])
spool = p("spool_home")
robot = OddDriver(spool, lie(low_deg))
home = RobotStep("home", spool, [reset_record, *steps, reset_record], "--outcomes", NO_OUTCOMES)
home.end()
robot.end()
home.expect_exit(1, "a move home through the table")
check("start pose" in home.error_line() and "table" in home.error_line(),
      f"home: the error line {home.error_line()!r} does not say the move to the start pose was refused")
check(motion_files(spool) == [home.request("motion", n) + ".xarm.csv" for n in (0, 2)],
      f"home: motion files {motion_files(spool)}: the move home through the table was written")

if failures:
    print("\n".join("FAIL: " + f for f in failures))
    print(f"(files kept in {tmp})")
    sys.exit(1)
shutil.rmtree(tmp)
print(f"ok: robot-step's spool protocol, checks, stops and judges in {time.monotonic() - started:.1f} s")
