#!/usr/bin/env python3
"""The robot's-side drivers (examples/robot/xarm_driver.py, examples/robot/realsense_recorder.py) speak the
spool protocol (formats/robot-spool.md), run with --dry-run as subprocesses on a temporary spool
that this test writes as robot-step would (each request under a '.' name, then renamed):

- motions made by xarm-export are answered .done, in the order written (one robot-step's counter
  read as a number past six digits; capture requests left to the recorder), with the last row's
  joints and gripper; a one-row motion too;
- malformed motions (not finite, a joint too fast, time going back, outside a joint's limits, a
  wrong header) get a .fault naming the line and what is wrong, and the driver keeps serving; so
  does a motion that starts away from where the last one left the arm;
- `stop` ends a driver promptly (between the streamed rows of a motion taking its own time, and
  before a motion) without answering further requests; SIGINT ends it cleanly and writes `stop`
  saying why; a driver started again answers nothing twice;
- the arm's own path (no --dry-run) against a stand-in for UFACTORY's SDK written here, whose
  position-mode moves and gripper take their time: .done with the joints the arm reports and its
  gripper clamped to 0..850 (it reports 851 open); a collision (controller error 22), an arm that
  does not come to rest and a TypeError from the SDK answered .fault in words, the arm stopped
  and cleared before the next motion; `stop` mid-motion, during the slow move to a first row and
  during a slow gripper move stopping the arm (emergency_stop) within 0.1 s, the gripper held;
  SIGTERM the same, writing `stop` with the request left unanswered, and a driver started again
  beside it moving nothing; an error even while stopping the arm after a fault ending the
  driver with `stop` written saying why and the arm stopped;
- the recorder answers captures with the frames of --frames DIR in turn, byte for byte, .ready
  last; a frame it cannot read is a .fault naming the file, and it keeps serving; its PNG writer
  (for the camera) writes what obs-pack (libpng) reads back exactly;
- every file a driver writes in a spool is opened under a '.' name and renamed once to its final
  name (an audit hook, sys.addaudithook, logs the drivers' opens and renames); a watcher looking
  at the spools all along sees every answer complete the first time its name appears, never
  rewritten, and no name but the requests and their answers.

The arm's limits the drivers check are those of lib/robot/xarm7.urdf. Neither UFACTORY's SDK nor
pyrealsense2 is needed.
Run with a python3 that has NumPy (ctest uses /usr/bin/python3)."""
import math
import os
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
ROBOT = os.path.join(SOURCE, "examples", "robot")
PYTHON = sys.executable
tmp = tempfile.mkdtemp(prefix="qte_drivers_")
sys.dont_write_bytecode = True  # nothing left in the source tree
sys.path.insert(0, ROBOT)
sys.path.insert(0, os.path.join(SOURCE, "lib", "python"))
import qte_stream  # noqa: E402
import realsense_recorder  # noqa: E402  (imports no pyrealsense2 until a camera is opened)
import xarm_play  # noqa: E402
import xarm_driver  # noqa: E402
ANSWER_S = 10  # generous: the machine may be busy
failures = []
started = time.monotonic()


def p(*names):
    return os.path.join(tmp, *names)


def run(name, *args, stdin=None):
    r = subprocess.run([os.path.join(TOOLS, name), *map(str, args)], input=stdin, capture_output=True)
    if r.returncode != 0:
        sys.exit(f"FAIL: {name} {' '.join(map(str, args))} exited {r.returncode}: {r.stderr.decode()}")
    return r.stdout


def put(spool, name, data):
    """A request as robot-step writes it: whole under a '.' name, then renamed."""
    temporary = os.path.join(spool, "." + name + ".writing")
    with open(temporary, "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)
    os.replace(temporary, os.path.join(spool, name))


def wait_for(path, timeout=ANSWER_S):
    deadline = time.monotonic() + timeout
    while not os.path.exists(path):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.005)
    return True


def read(path, mode="r"):
    with open(path, mode) as f:
        return f.read()


class Watcher(threading.Thread):
    """Looks at the spools every millisecond: the first content of each name (read as soon as it
    is seen), and whether a name was ever replaced (another inode or time)."""

    def __init__(self, spools):
        super().__init__(daemon=True)
        self.spools, self.seen, self.problems, self.done = spools, {}, [], False

    def look(self):
        for spool in self.spools:
            for name in os.listdir(spool):
                if name.startswith("."):
                    continue
                path = os.path.join(spool, name)
                try:
                    st = os.stat(path)
                    content = read(path, "rb") if path not in self.seen else None
                except FileNotFoundError:
                    continue
                if path not in self.seen:
                    self.seen[path] = (st.st_ino, st.st_mtime_ns, content)
                    if name.endswith(".ready"):  # its images were renamed before it
                        stem = path[: -len(".ready")]
                        for kind in ("color", "depth"):
                            if not os.path.exists(f"{stem}.{kind}.png"):
                                self.problems.append(f"{name} appeared before its {kind}.png")
                elif self.seen[path][:2] != (st.st_ino, st.st_mtime_ns):
                    self.problems.append(f"{name} was written again")
                    self.seen[path] = (st.st_ino, st.st_mtime_ns, self.seen[path][2])

    def run(self):
        while not self.done:
            self.look()
            time.sleep(0.001)


# The drivers run under an audit hook (sys.addaudithook) that logs every file they open for
# writing and every rename: whether answers are written under '.' names and renamed once is then
# read from what they did, not only from what the watcher happened to see.
AUDIT_LOG = p("audit.log")
LAUNCHER = p("audited.py")
with open(LAUNCHER, "w") as f:
    f.write(f"""import os, runpy, sys
log = open({AUDIT_LOG!r}, "a", buffering=1)
def hook(event, args):
    if event == "open" and isinstance(args[0], str) and args[2] & (os.O_WRONLY | os.O_RDWR):
        log.write("write " + os.path.abspath(args[0]) + "\\n")
    elif event == "os.rename":
        log.write("rename " + os.path.abspath(args[0]) + " " + os.path.abspath(args[1]) + "\\n")
sys.addaudithook(hook)
sys.dont_write_bytecode = True
sys.argv = sys.argv[1:]
runpy.run_path(sys.argv[0], run_name="__main__")
""")


def catching_signals(process, timeout=ANSWER_S):
    """Waits until the driver has its SIGTERM handler (robot_spool's, set with its SIGINT one; a
    busy machine may take long to start Python): /proc's SigCgt mask, or half a second."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and process.poll() is None:
        try:
            status = read(f"/proc/{process.pid}/status")
        except OSError:
            time.sleep(0.5)
            return
        caught = int(next(line.split()[1] for line in status.splitlines() if line.startswith("SigCgt:")), 16)
        if caught >> (signal.SIGTERM - 1) & 1:
            return
        time.sleep(0.01)


class Driver:
    """A driver program as a subprocess, its stdout lines collected as they come."""

    def __init__(self, script, *args):
        self.process = subprocess.Popen([PYTHON, LAUNCHER, os.path.join(ROBOT, script), *map(str, args)],
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.lines = []
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self):
        for line in self.process.stdout:
            self.lines.append(line.rstrip("\n"))

    def wait_line(self, fragment, timeout=ANSWER_S):
        deadline = time.monotonic() + timeout
        while not any(fragment in line for line in self.lines):
            if time.monotonic() > deadline or self.process.poll() is not None and not self.reader.is_alive():
                return False
            time.sleep(0.005)
        return True

    def end(self, timeout=ANSWER_S):
        """(exit status, seconds it took to exit, stderr)."""
        t = time.monotonic()
        try:
            self.process.wait(timeout)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
            failures.append(f"{os.path.basename(self.process.args[2])} did not exit within {timeout} s")
        self.reader.join(2)
        return self.process.returncode, time.monotonic() - t, self.process.stderr.read()


# --- the limits the drivers check are the URDF's ------------------------------------------------
urdf = ET.parse(os.path.join(SOURCE, "lib", "robot", "xarm7.urdf")).getroot()
for k in range(7):
    limit = urdf.find(f"joint[@name='joint{k + 1}']/limit")
    low, high, speed = (float(limit.get(a)) for a in ("lower", "upper", "velocity"))
    if (abs(low - xarm_play.JOINT_LIMITS_RAD[k][0]) > 1e-6 or abs(high - xarm_play.JOINT_LIMITS_RAD[k][1]) > 1e-6
            or abs(math.degrees(speed) - xarm_play.MAX_JOINT_SPEED_DEG_S) > 1e-3):
        failures.append(f"joint{k + 1}: xarm_play.py's limits {xarm_play.JOINT_LIMITS_RAD[k]}, "
                        f"{xarm_play.MAX_JOINT_SPEED_DEG_S} deg/s; the URDF's ({low}, {high}), {math.degrees(speed)} deg/s")

# --- motions as xarm-export writes them -----------------------------------------------------------
# Two planned motions in one stream: close the gripper at the end of the first, open it after the
# second; and a slow one (10 s) to be stopped halfway.
q0 = [0, 0, 0, 0.5, 0, 0.5, 0]
q1 = [0, 0.1, 0, 0.6, 0, 0.6, 0]
q2 = [0, 0.2, 0, 0.7, 0, 0.7, 0]
q3 = [-0.1, 0.1, 0, 0.6, 0, 0.6, -0.2]


def trajectory(times, joints, gripper_open):
    return run("stream-pack", "trajectory", "time_s:f64=" + ",".join(map(str, times)),
               f"joint_positions:f64[{len(joints)},7]=" + ",".join(str(v) for q in joints for v in q),
               f"gripper_open:u8={gripper_open}")


run("xarm-export", "--dir", p("moves"), "--rate", 20,
    stdin=trajectory([0, 0.2, 0.4], [q0, q1, q2], 0) + trajectory([0, 0.3], [q2, q3], 1))
run("xarm-export", "--dir", p("slow"), "--rate", 100, stdin=trajectory([0, 10], [q0, q1], 1))
move_a, move_b = read(p("moves", "000000.xarm.csv")), read(p("moves", "000001.xarm.csv"))
slow = read(p("slow", "000000.xarm.csv"))
lines_a = move_a.splitlines()
first_row = next(i for i, line in enumerate(lines_a) if line.startswith("time_s")) + 1  # index of row 0
reset = "\n".join(lines_a[:first_row]) + "\n0.0000," + ",".join(f"{math.degrees(v):.6f}" for v in q0) + ",850\n"


def last_row(text):
    return text.strip().splitlines()[-1].split(",", 1)[1]


def damaged(row, change):
    """move_a with its row `row` (0 = the first after the header) changed; and its line number."""
    lines = list(lines_a)
    cells = lines[first_row + row].split(",")
    change(cells)
    lines[first_row + row] = ",".join(cells)
    return "\n".join(lines) + "\n", first_row + row + 1


def set_cell(column, value):
    def change(cells):
        cells[column] = value
    return change


def shift(column, degrees):
    def change(cells):
        cells[column] = f"{float(cells[column]) + degrees:.6f}"
    return change


bad_motions = [  # (text, line, what the fault must say)
    (*damaged(3, set_cell(4, "nan")), "j4_deg"),
    (*damaged(5, shift(2, 20.0)), "faster than 180 deg/s"),           # 20 deg in 0.05 s: 400 deg/s
    (*damaged(4, set_cell(0, "0.1000")), "time_s"),                   # back to the row before's time
    (*damaged(0, set_cell(6, "-100.000000")), "outside the joint's limits"),  # joint 6 from -97 deg
    (*damaged(2, set_cell(8, "900")), "gripper"),
    (move_a.replace("j7_deg,gripper", "j7_deg"), first_row, "header"),
]

# --- the arm driver ---------------------------------------------------------------------------------
arm_spool, camera_spool = p("arm_spool"), p("camera_spool")
os.makedirs(arm_spool)
os.makedirs(camera_spool)
watcher = Watcher([arm_spool, camera_spool])
watcher.start()
expected = {}  # final name -> its content, for each name the spools should ever hold
session = "4242"


def name(kind, n, suffix):
    return f"{kind}-{session}-{n:06d}.{suffix}"


# Written before the driver starts: two motions with a capture between them, the counter past six
# digits (as text, 1000000 sorts before 999998).
for n, text in ((999998, move_a), (999999, ""), (1000000, move_b)):
    kind, suffix = ("capture", "request") if text == "" else ("motion", "xarm.csv")
    put(arm_spool, name(kind, n, suffix), text)
    expected[name(kind, n, suffix)] = text.encode()
driver = Driver("xarm_driver.py", "--spool", arm_spool, "--dry-run")
for n, text in ((999998, move_a), (1000000, move_b)):
    done = os.path.join(arm_spool, name("motion", n, "done"))
    if not wait_for(done):
        failures.append(f"no answer to motion {n}")
        continue
    expected[os.path.basename(done)] = (last_row(text) + "\n").encode()
    if read(done) != last_row(text) + "\n":
        failures.append(f"motion {n}: answered {read(done)!r}, expected the last row's {last_row(text)!r}")
driver.wait_line(name("motion", 1000000, "xarm.csv") + ":")  # its line is read by a thread, maybe after the answer
motion_lines = [line for line in driver.lines if line.startswith("motion-")]
if [line.split(":")[0] for line in motion_lines] != [name("motion", 999998, "xarm.csv"), name("motion", 1000000, "xarm.csv")]:
    failures.append(f"motions not executed in the order written: {driver.lines}")
elif "850 -> 0" not in motion_lines[0] or "0 -> 850" not in motion_lines[1] or "rows over" not in motion_lines[0]:
    failures.append(f"the dry run's lines do not say rows and gripper: {motion_lines}")

# Malformed motions, one at a time: a fault naming the line; then a one-row motion is executed.
n = 1000001
for text, line, what in bad_motions:
    request = name("motion", n, "xarm.csv")
    put(arm_spool, request, text)
    expected[request] = text.encode()
    fault = os.path.join(arm_spool, name("motion", n, "fault"))
    if not wait_for(fault):
        failures.append(f"no fault for a motion whose line {line} is wrong ({what})")
    else:
        answer = read(fault)
        expected[os.path.basename(fault)] = answer.encode()
        if (not answer.startswith(request + ": ") or f"line {line}: " not in answer or what not in answer
                or answer.count("\n") != 1 or not answer.endswith("\n")):
            failures.append(f"the fault for line {line} ({what}) says {answer!r}")
    if os.path.exists(os.path.join(arm_spool, name("motion", n, "done"))):
        failures.append(f"a motion with a bad line {line} was answered done")
    n += 2
request = name("motion", n, "xarm.csv")
put(arm_spool, request, reset)
expected[request] = reset.encode()
done = os.path.join(arm_spool, name("motion", n, "done"))
if not wait_for(done) or read(done) != last_row(reset) + "\n":
    failures.append(f"after the faults, the one-row motion: {read(done) if os.path.exists(done) else 'no answer'}")
else:
    expected[os.path.basename(done)] = read(done, "rb")
# The arm is at q0 now: a motion starting at q2 is refused (nothing moved), one from q0 is executed.
for text, answer in ((move_b, "fault"), (move_a, "done")):
    n += 1
    put(arm_spool, name("motion", n, "xarm.csv"), text)
    expected[name("motion", n, "xarm.csv")] = text.encode()
    path = os.path.join(arm_spool, name("motion", n, answer))
    if not wait_for(path):
        failures.append(f"motion {n}: no .{answer}")
        continue
    expected[os.path.basename(path)] = read(path, "rb")
    if answer == "fault" and "starts 11.5 deg from where the arm is (j2 at 0.000 deg" not in read(path):
        failures.append(f"a motion starting away from the arm: {read(path)!r}")

# stop, then a request: the driver exits at once, answering nothing more.
put(arm_spool, "stop", "")
expected["stop"] = b""
put(arm_spool, name("motion", n + 1, "xarm.csv"), move_a)
expected[name("motion", n + 1, "xarm.csv")] = move_a.encode()
status, _, stderr = driver.end()
if status != 0 or "stop" not in stderr or "Traceback" in stderr:
    failures.append(f"the arm driver on stop: exit {status}, {stderr!r}")
time.sleep(0.1)
if any(os.path.exists(os.path.join(arm_spool, name("motion", n + 1, s))) for s in ("done", "fault")):
    failures.append("a motion written after stop was answered")
if any(f.startswith("capture") and not f.endswith(".request") for f in os.listdir(arm_spool)):
    failures.append("the arm driver answered a capture request")

# Started again (stop removed, the last request taken back), it answers nothing twice; SIGINT
# ends it cleanly and writes `stop` saying why (robot-step stops at once).
os.remove(os.path.join(arm_spool, "stop"))
watcher.seen.pop(os.path.join(arm_spool, "stop"), None)  # the next `stop` is another file
os.remove(os.path.join(arm_spool, name("motion", n + 1, "xarm.csv")))
before = sorted(os.listdir(arm_spool))
driver = Driver("xarm_driver.py", "--spool", arm_spool, "--dry-run")
catching_signals(driver.process)
driver.process.send_signal(signal.SIGINT)
status, took, stderr = driver.end()
if status != 130 or "interrupted" not in stderr or "Traceback" in stderr or took > 3:
    failures.append(f"the arm driver on SIGINT: exit {status} after {took:.2f} s, {stderr!r}")
if sorted(os.listdir(arm_spool)) != sorted(before + ["stop"]) or driver.lines:
    failures.append(f"started again, the driver answered: {driver.lines}, {sorted(os.listdir(arm_spool))}")
expected[os.path.join(arm_spool, "stop")] = b"xarm_driver was interrupted (SIGINT)\n"
stop_file = os.path.join(arm_spool, "stop")
if not os.path.exists(stop_file) or read(stop_file, "rb") != expected[stop_file]:
    failures.append(f"the stop written on SIGINT: {read(stop_file) if os.path.exists(stop_file) else None!r}")

# stop between the streamed rows of a motion played at its own pace (10 s): out within 3 s,
# no answer.
stop_spool = p("stop_spool")
os.makedirs(stop_spool)
driver = Driver("xarm_driver.py", "--spool", stop_spool, "--dry-run", "--pace", 1)
put(stop_spool, "motion-77-000000.xarm.csv", slow)
if not driver.wait_line("motion-77-000000.xarm.csv: 1002 rows over 10.50 s"):
    failures.append(f"the slow motion did not start: {driver.lines}")
time.sleep(0.5)
put(stop_spool, "stop", "")
status, took, stderr = driver.end()
if status != 0 or took > 3 or os.path.exists(os.path.join(stop_spool, "motion-77-000000.done")):
    failures.append(f"stop in the middle of a motion: exit {status} after {took:.2f} s, "
                    f"{sorted(os.listdir(stop_spool))}, {stderr!r}")
# stop already there: nothing is executed.
driver = Driver("xarm_driver.py", "--spool", stop_spool, "--dry-run")
put(stop_spool, "motion-78-000000.xarm.csv", move_a)
status, took, stderr = driver.end()
if status != 0 or driver.lines or sorted(os.listdir(stop_spool)) != ["motion-77-000000.xarm.csv",
                                                                     "motion-78-000000.xarm.csv", "stop"]:
    failures.append(f"a driver started beside `stop`: exit {status}, {driver.lines}, {sorted(os.listdir(stop_spool))}")

# --- the arm's path, against a stand-in for UFACTORY's SDK ------------------------------------------
# xarm.wrapper.XArmAPI written here. It moves as an arm does: a position-mode move takes its time
# at the speed asked (get_is_moving() true meanwhile, the joints on the way), the gripper too (at
# FAKE_GRIPPER_SPEED units/s, reporting 851 when open, as a real one may), emergency_stop and
# set_state(4) freeze the arm where it is. It logs the calls that matter (emergency_stop and the
# gripper's commands with the time.monotonic() they came, a clock all processes share), refuses
# the SDK's own waiting (the driver must watch the slow moves itself), and on a flag file beside
# its log misbehaves once: `.collide`, a collision (controller error 22) on the 3rd streamed row;
# `.restless`, still moving after the streamed rows until stopped; `.typeerror`, a TypeError from
# the SDK on the 2nd streamed row. FAKE_ARM_BROKEN: get_servo_angle raises a TypeError and
# set_state(4) a ConnectionResetError (even the stop after a fault fails).
fake_sdk = p("fake_sdk")
os.makedirs(os.path.join(fake_sdk, "xarm", "core", "config"))
for package in ("xarm", "xarm/core", "xarm/core/config"):
    open(os.path.join(fake_sdk, package, "__init__.py"), "w").close()
with open(os.path.join(fake_sdk, "xarm", "core", "config", "x_code.py"), "w") as f:
    f.write("""class ControllerError:
    def __init__(self, code):
        self.description = {"en": "Collision limit", "cn": "-"} if code == 22 else None
ControllerWarn = ControllerError
""")
with open(os.path.join(fake_sdk, "xarm", "wrapper.py"), "w") as f:
    f.write("""import os, time
LOG = os.environ["FAKE_ARM_LOG"]
def flag(name):
    if os.path.exists(LOG + "." + name):
        os.remove(LOG + "." + name)
        return True
    return False
class XArmAPI:
    def __init__(self, ip):
        self.log = open(LOG, "a", buffering=1)
        self.angles, self.move, self.error_code, self.warn_code, self.streamed = [0.0] * 7, None, 0, 0, 0
        self.gripper = self.gripper_target = float(os.environ.get("FAKE_GRIPPER", 850))
        self.gripper_speed, self.gripper_since = float(os.environ.get("FAKE_GRIPPER_SPEED", 4250)), time.monotonic()
        self.restless, self.typeerror, self.broken = False, False, "FAKE_ARM_BROKEN" in os.environ
    def _note(self, what):
        self.log.write(what + "\\n")
        return 0
    def _where(self):
        if self.move:
            start, a, b, duration = self.move
            done = min(1.0, (time.monotonic() - start) / duration)
            self.angles = list(b) if done >= 1 else [x + done * (y - x) for x, y in zip(a, b)]
            self.move = None if done >= 1 else self.move
        return self.angles
    def _gripper(self):
        now = time.monotonic()
        step = self.gripper_speed * (now - self.gripper_since)
        self.gripper += max(-step, min(step, self.gripper_target - self.gripper))
        self.gripper_since = now
        return self.gripper
    def _halt(self):
        self._where()
        self.move, self.restless = None, False
    def clean_error(self):
        self.error_code = 0
        return self._note("clean_error")
    def clean_warn(self): return 0
    def motion_enable(self, enable): return 0
    def set_gripper_enable(self, enable): return 0
    def set_mode(self, mode):
        if mode == 1:
            self.streamed, self.restless, self.typeerror = 0, flag("restless"), flag("typeerror")
            self._note("servo mode")
        return 0
    def set_state(self, state):
        if state == 4:
            if self.broken:
                raise ConnectionResetError("fake SDK: the connection was reset")
            self._halt()
        return self._note(f"set_state {state}")
    def set_servo_angle(self, angle, speed, is_radian, wait):
        if wait:
            raise AssertionError("set_servo_angle(wait=True): the move would not be watched")
        a, b = self._where(), [float(q) for q in angle]
        distance = max(abs(x - y) for x, y in zip(a, b))
        self.move = (time.monotonic(), a, b, distance / speed) if distance > 0 else None
        self.angles = a if distance > 0 else b
        return self._note("reach " + ",".join(f"{q:.1f}" for q in angle))
    def set_servo_angle_j(self, angles, is_radian):
        if self.error_code:
            return 1
        self.streamed += 1
        if self.streamed == 2 and self.typeerror:
            raise TypeError("fake SDK: unsupported operand type(s) for +: 'int' and 'NoneType'")
        if self.streamed == 3 and flag("collide"):
            self.error_code = 22
            return 1
        self.angles = list(angles)
        return 0
    def set_gripper_position(self, position, wait, **kwargs):
        if wait or kwargs.get("wait_motion", True):
            raise AssertionError("set_gripper_position waiting: the gripper would not be watched")
        self._gripper()
        self.gripper_target = float(position)
        return self._note(f"gripper {position:g} {time.monotonic():.4f}")
    def get_servo_angle(self, is_radian):
        if self.broken:
            raise TypeError("'NoneType' object is not subscriptable")
        return 0, self._where() + [0.0]
    def get_gripper_position(self):
        g = self._gripper()
        return 0, 851.0 if g >= 850 else float(round(g))
    def get_err_warn_code(self):
        return 0, [self.error_code, self.warn_code]
    def get_is_moving(self):
        self._where()
        return self.move is not None or self.restless
    def emergency_stop(self):
        self._halt()
        return self._note(f"emergency_stop {time.monotonic():.4f} j4 {self.angles[3]:.2f}")
    def disconnect(self):
        return self._note("disconnect")
""")


class FakeArm:
    """xarm_driver.py on a spool of its own against the SDK's stand-in, its log and flags."""

    def __init__(self, label, *options, **environment):
        self.spool, self.log = p(f"{label}_spool"), p(f"{label}_arm.log")
        os.makedirs(self.spool, exist_ok=True)
        self.process = subprocess.Popen(
            [PYTHON, os.path.join(ROBOT, "xarm_driver.py"), "--spool", self.spool, "--ip", "fake", *map(str, options)],
            env=dict(os.environ, PYTHONPATH=fake_sdk, FAKE_ARM_LOG=self.log, **environment),
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)

    def flag(self, name):
        open(f"{self.log}.{name}", "w").close()

    def calls(self):
        return read(self.log).split("\n") if os.path.exists(self.log) else []

    def wait_call(self, prefix, timeout=ANSWER_S):
        deadline = time.monotonic() + timeout
        while not any(c.startswith(prefix) for c in self.calls()):
            if time.monotonic() > deadline or self.process.poll() is not None:
                return False
            time.sleep(0.005)
        return True

    def answer(self, request, timeout=ANSWER_S):
        """'done ...' or 'fault ...' of the request (its name without .xarm.csv), or 'none'."""
        answers = [os.path.join(self.spool, f"{request}.{s}") for s in ("done", "fault")]
        deadline = time.monotonic() + timeout
        while not any(map(os.path.exists, answers)) and time.monotonic() < deadline:
            time.sleep(0.005)
        return next((a.rsplit(".", 1)[1] + " " + read(a).strip() for a in answers if os.path.exists(a)), "none")

    def end(self):
        try:
            out, err = self.process.communicate(timeout=ANSWER_S)
        except subprocess.TimeoutExpired:
            self.process.kill()
            out, err = self.process.communicate()
            failures.append(f"the arm driver on {self.spool} did not exit")
        return self.process.returncode, err

    def answered(self):
        return [f for f in os.listdir(self.spool) if f.endswith((".done", ".fault"))]


def stop_time(calls):
    """When emergency_stop was first called (the stand-in's clock, time.monotonic())."""
    return next((float(c.split()[1]) for c in calls if c.startswith("emergency_stop")), math.inf)


# The .done's gripper is a whole number of units in 0..850, whatever the gripper reports.
if xarm_driver.numbers([0.0] * 7, 851.0).split(",")[-1] != "850" or xarm_driver.numbers([0.0] * 7, -0.4).split(",")[-1] != "0":
    failures.append(f"the .done's gripper is not clamped to 0..850: {xarm_driver.numbers([0.0] * 7, 851.0)!r}")

# Motions in turn, each answered: .done with the joints and gripper the arm reports (851 open
# answered as 850); a collision, an arm that does not come to rest and an error of the SDK's
# answered .fault in words, the arm stopped (set_state 4) and cleared before the next motion; then
# `stop` in the middle of a streamed motion calls emergency_stop and the driver exits.
arm = FakeArm("fake")
answers = []
motions = [(reset, None), (move_a, "collide"), (reset, None), (move_a, None), (reset, None),
           (move_a, "restless"), (reset, None), (move_a, "typeerror"), (reset, None)]
for n, (text, misbehaviour) in enumerate(motions):
    if misbehaviour:
        arm.flag(misbehaviour)
    put(arm.spool, f"motion-9-{n:06d}.xarm.csv", text)
    answers.append(arm.answer(f"motion-9-{n:06d}", ANSWER_S + 5))
n = len(motions)
put(arm.spool, f"motion-9-{n:06d}.xarm.csv", slow)
time.sleep(0.5)  # streaming at its own pace
put(arm.spool, "stop", "")
status, err = arm.end()
calls = [c.split(" ")[0] if c.startswith("emergency_stop") else c for c in arm.calls()]
done = {t: "done " + last_row(t) for t in (reset, move_a)}
expected_answers = [done[reset], "fault set_servo_angle_j returned 1 (the controller has an error); "
                    "Collision limit, error code 22", done[reset], done[move_a], done[reset],
                    "fault the arm did not come to rest within 5 s of the motion's last row; no controller error",
                    done[reset], "fault TypeError: fake SDK: unsupported operand type(s) for +: 'int' and 'NoneType'",
                    done[reset]]
if answers != expected_answers:
    failures.append(f"against the SDK's stand-in, answers {answers}; expected {expected_answers}")
faulted = [i for i, c in enumerate(calls) if c == "set_state 4"]
if len(faulted) != 3 or any("clean_error" not in calls[i:j] for i, j in zip(faulted, faulted[1:] + [len(calls)])) \
        or calls[-4:] != ["emergency_stop", "emergency_stop", "disconnect", ""] \
        or os.listdir(arm.spool).count(f"motion-9-{n:06d}.xarm.csv") != 1 or status != 0 \
        or any(f.startswith(f"motion-9-{n:06d}.") and not f.endswith(".xarm.csv") for f in os.listdir(arm.spool)):
    failures.append(f"against the SDK's stand-in: exit {status}, calls {calls}, {err!r}")

# `stop` during the slow move to a first row far from the arm (28.6 deg at 20 deg/s: 1.4 s; the
# start tolerance widened for it): the arm is stopped within 0.1 s where it is, no row is
# streamed, nothing is answered, the driver exits.
arm = FakeArm("reach_stop", "--start-tolerance", 30)
put(arm.spool, "motion-5-000000.xarm.csv", slow)
if not arm.wait_call("reach"):
    failures.append(f"the slow first-row move did not start: {arm.calls()}")
time.sleep(0.4)
stopped_at = time.monotonic()  # before the request: the driver may act on it before we run again
put(arm.spool, "stop", "")
status, err = arm.end()
calls = arm.calls()
halted = stop_time(calls)
if not 0 <= halted - stopped_at < 0.1 or "servo mode" in calls or status != 0 or arm.answered() \
        or not 5 < float(next(c for c in calls if c.startswith("emergency_stop")).split()[-1]) < 25:
    failures.append(f"stop during the first row's slow move: emergency_stop {halted - stopped_at:.3f} s after it, "
                    f"exit {status}, calls {calls}, answered {arm.answered()}, {err!r}")

# `stop` while the gripper opens slowly (170 units/s): the gripper held where it is and the arm
# stopped within 0.1 s, nothing answered.
arm = FakeArm("gripper_stop", FAKE_GRIPPER="0", FAKE_GRIPPER_SPEED="170")
put(arm.spool, "motion-6-000000.xarm.csv", reset.replace(reset.strip().splitlines()[-1], "0.0000" + ",0.000000" * 7 + ",850"))
if not arm.wait_call("gripper 850"):
    failures.append(f"the gripper's slow move did not start: {arm.calls()}")
time.sleep(0.4)
stopped_at = time.monotonic()  # before the request: the driver may act on it before we run again
put(arm.spool, "stop", "")
status, err = arm.end()
calls = arm.calls()
held = [c.split() for c in calls if c.startswith("gripper") and c != calls[0]]
held = held[-1] if held else ["gripper", "850", "inf"]
if not 0 <= stop_time(calls) - stopped_at < 0.1 or not 0 <= float(held[2]) - stopped_at < 0.1 \
        or not 10 < float(held[1]) < 840 or status != 0 or arm.answered():
    failures.append(f"stop while the gripper moves: exit {status}, calls {calls}, answered {arm.answered()}, {err!r}")

# SIGTERM during the slow move: the arm stopped within 0.1 s, `stop` written saying why and which
# request was left unanswered (robot-step stops at once and withdraws it); started again beside
# that `stop`, the driver exits at once and moves nothing.
arm = FakeArm("sigterm", "--start-tolerance", 30)
put(arm.spool, "motion-7-000000.xarm.csv", slow)
if not arm.wait_call("reach"):
    failures.append(f"the slow first-row move did not start: {arm.calls()}")
time.sleep(0.4)
signalled_at = time.monotonic()  # before the signal: the driver may stop the arm before we run again
arm.process.send_signal(signal.SIGTERM)
status, err = arm.end()
halted, stop_file = stop_time(arm.calls()) - signalled_at, os.path.join(arm.spool, "stop")
if not 0 <= halted < 0.1 or status != 130 or arm.answered() or not os.path.exists(stop_file) \
        or read(stop_file) != "xarm_driver was interrupted (SIGTERM) while handling motion-7-000000.xarm.csv, left unanswered\n":
    failures.append(f"SIGTERM during a motion: emergency_stop {halted:.3f} s after it, exit {status}, "
                    f"stop {read(stop_file) if os.path.exists(stop_file) else None!r}, calls {arm.calls()}, {err!r}")
before = arm.calls()
arm = FakeArm("sigterm")
status, err = arm.end()
if status != 0 or any(c.startswith(("reach", "gripper")) for c in arm.calls()[len(before):]) or arm.answered():
    failures.append(f"started again beside the stop it wrote: exit {status}, calls {arm.calls()[len(before):]}, {err!r}")

# An error while stopping the arm after a fault (the connection lost): the driver writes `stop`
# saying why and which request is unanswered, stops the arm as it ends, and exits with the error.
arm = FakeArm("broken", FAKE_ARM_BROKEN="1")
put(arm.spool, "motion-8-000000.xarm.csv", reset)
status, err = arm.end()
stop_file = os.path.join(arm.spool, "stop")
if status in (0, 130) or arm.answered() or "emergency_stop" not in " ".join(arm.calls()) or "ConnectionResetError" not in err \
        or not os.path.exists(stop_file) or read(stop_file) != (
            "xarm_driver ended by an error (ConnectionResetError: fake SDK: the connection was reset) while handling "
            "motion-8-000000.xarm.csv, left unanswered\n"):
    failures.append(f"a driver ended by an error: exit {status}, stop {read(stop_file) if os.path.exists(stop_file) else None!r}, "
                    f"calls {arm.calls()}, {err!r}")

# --- the recorder ----------------------------------------------------------------------------------
# Its PNG writer, read back by obs-pack (libpng): the same pixels and depth counts.
rng = np.random.default_rng(3)
frames = p("frames")
os.makedirs(frames)
images = []
for index in range(2):
    color = rng.integers(0, 256, (6, 8, 3), dtype=np.uint8)
    depth = rng.integers(0, 65536, (6, 8), dtype=np.uint16)
    depth[0, :3] = [0, 1, 65535]
    for kind, image in (("color", color), ("depth", depth)):
        with open(os.path.join(frames, f"{kind}_{index:06d}.png"), "wb") as f:
            f.write(realsense_recorder.png_bytes(image))
    images.append((color, depth))
with open(p("frames.rec"), "wb") as f:
    f.write(run("obs-pack", "--rgb", os.path.join(frames, "color_%06d.png"), "--depth", os.path.join(frames, "depth_%06d.png"),
                "--intrinsics", "8,8,3.5,2.5", "--camera-pose", "0,0,1,0,0,0,1"))
packed = [r for r in qte_stream.read_records(p("frames.rec")) if r.type == "obs"]
if len(packed) != 2 or any(not np.array_equal(r.fields["front.rgb"], c) or not np.array_equal(r.fields["front.depth_mm"], d)
                           for r, (c, d) in zip(packed, images)):
    failures.append("obs-pack reads other images than the recorder's PNG writer wrote")
frame_bytes = [{kind: read(os.path.join(frames, f"{kind}_{i:06d}.png"), "rb") for kind in ("color", "depth")}
               for i in range(2)]

session = "555"
for n, suffix in ((1, "request"), (2, "xarm.csv"), (3, "request")):  # a motion between: the arm's
    put(camera_spool, name("capture" if suffix == "request" else "motion", n, suffix), "" if suffix == "request" else move_a)
    expected[name("capture" if suffix == "request" else "motion", n, suffix)] = b"" if suffix == "request" else move_a.encode()
recorder = Driver("realsense_recorder.py", "--spool", camera_spool, "--dry-run", "--frames", frames)


def expect_frame(n, index):
    ready = os.path.join(camera_spool, name("capture", n, "ready"))
    if not wait_for(ready):
        failures.append(f"capture {n}: no .ready")
        return
    expected[os.path.basename(ready)] = b""
    for kind in ("color", "depth"):
        answer = name("capture", n, f"{kind}.png")
        expected[answer] = frame_bytes[index][kind]
        if read(os.path.join(camera_spool, answer), "rb") != frame_bytes[index][kind]:
            failures.append(f"capture {n}: its {kind}.png is not frame {index}'s")


expect_frame(1, 0)
expect_frame(3, 1)
recorder.wait_line(name("capture", 3, "request") + ":")
if [line.split(":")[0] for line in recorder.lines] != [name("capture", 1, "request"), name("capture", 3, "request")]:
    failures.append(f"captures not answered in the order written: {recorder.lines}")
put(camera_spool, name("capture", 5, "request"), "")
expected[name("capture", 5, "request")] = b""
expect_frame(5, 0)  # cycling
# A frame that cannot be read: a fault naming the file; the next request is answered.
os.remove(os.path.join(frames, "color_000001.png"))
put(camera_spool, name("capture", 7, "request"), "")
expected[name("capture", 7, "request")] = b""
fault = os.path.join(camera_spool, name("capture", 7, "fault"))
if not wait_for(fault) or "color_000001.png" not in read(fault) or read(fault).count("\n") != 1:
    failures.append(f"a missing frame: {read(fault) if os.path.exists(fault) else 'no fault'}")
else:
    expected[os.path.basename(fault)] = read(fault, "rb")
put(camera_spool, name("capture", 9, "request"), "")
expected[name("capture", 9, "request")] = b""
expect_frame(9, 0)
# obs-pack reads an answered pair as robot-step will.
run("obs-pack", "--rgb", os.path.join(camera_spool, f"capture-{session}-%06d.color.png"),
    "--depth", os.path.join(camera_spool, f"capture-{session}-%06d.depth.png"), "--start", 3, "--count", 1,
    "--intrinsics", "8,8,3.5,2.5", "--camera-pose", "0,0,1,0,0,0,1")
# stop, then a request: no answer, out at once.
put(camera_spool, "stop", "")
expected["stop"] = b""
put(camera_spool, name("capture", 11, "request"), "")
expected[name("capture", 11, "request")] = b""
status, _, stderr = recorder.end()
if status != 0 or "stop" not in stderr or "Traceback" in stderr:
    failures.append(f"the recorder on stop: exit {status}, {stderr!r}")
time.sleep(0.1)
if any(f.startswith(name("capture", 11, "")) and not f.endswith(".request") for f in os.listdir(camera_spool)):
    failures.append("a capture written after stop was answered")

# --- what the watcher saw ----------------------------------------------------------------------------
watcher.look()
watcher.done = True
watcher.join()
failures += watcher.problems
renamed = {}
spools = tuple(os.path.abspath(spool) + os.sep for spool in (arm_spool, camera_spool, stop_spool))
for line in read(AUDIT_LOG).splitlines():
    what, *paths = line.split(" ")
    if not paths[-1].startswith(spools):
        continue
    if what == "write" and not os.path.basename(paths[0]).startswith("."):
        failures.append(f"a driver opened {paths[0]} for writing: not a temporary name")
    if what == "rename":
        source, target = paths
        if not os.path.basename(source).startswith(".") or os.path.basename(target).startswith("."):
            failures.append(f"a driver renamed {source} to {target}")
        renamed[target] = renamed.get(target, 0) + 1
twice = [f for f, count in renamed.items() if count > 1]
if twice or not renamed:
    failures.append(f"answered more than once: {twice}" if twice else "no renames logged")
for spool in (arm_spool, camera_spool, stop_spool):
    for f in os.listdir(spool):
        if f.startswith("."):
            failures.append(f"{f}: a temporary name left in the spool")
for path, (_, _, first) in watcher.seen.items():
    f = os.path.basename(path)
    if f not in expected:
        failures.append(f"{f}: a name the spool should not hold")
    elif first != expected.get(path, expected[f]):  # a path's own, where the spools differ
        failures.append(f"{f}: when first seen it held {first[:80]!r}, not its whole answer")
missing = sorted(f for f in expected if os.path.join(arm_spool, f) not in watcher.seen
                 and os.path.join(camera_spool, f) not in watcher.seen and f != "stop")
if missing:
    failures.append(f"answers the watcher never saw: {missing}")

if failures:
    print("\n".join("FAIL: " + f for f in failures))
    sys.exit(1)
shutil.rmtree(tmp)
print(f"ok: {len(watcher.seen)} names watched in the spools, {len(bad_motions)} malformed motions refused by line, "
      f"stop, SIGINT, SIGTERM and errors honoured, in {time.monotonic() - started:.1f} s")
