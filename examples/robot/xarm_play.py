#!/usr/bin/env python3
"""Plays xarm-export files on a real xArm 7 with UFACTORY's Python SDK.

    python3 examples/robot/xarm_play.py --ip 192.168.1.185 moves/000004.xarm.csv [more.csv ...]
    python3 examples/robot/xarm_play.py --dry-run moves/*.xarm.csv     # check the files, move nothing

The SDK is not a dependency of the toolkit; install it where the robot is reached from:
    pip install xarm-python-sdk        (https://github.com/xArm-Developer/xArm-Python-SDK)

Each file is checked again before anything moves, as xarm-export checked it: the header, every
cell a finite number, the gripper a whole number of units in 0..850, times from 0 and increasing,
at most 60 s, every row within the xArm 7's joint limits and no joint faster than 180 deg/s from
row to row (1 % slack for the printed decimals); an error names the file and line.

Each file's first row is reached slowly in position mode (set_servo_angle, 20 deg/s), then the
rows are streamed in servo mode (mode 1, set_servo_angle_j) at the file's own times; the gripper
is moved (set_gripper_position) whenever its column changes. A file of one row is a move to that
row, reached slowly. The slow moves are commanded without the SDK's waiting and watched every
20 ms (the arm's joints, motion and error codes; the gripper's position), so a stop is seen at
once during them as between streamed rows: Ctrl-C (or SIGTERM) stops the arm with the SDK's
emergency_stop, holds the gripper where it is, and ends the program (status 130). Keep a hand on
the emergency stop all the same: the planner saw only what the camera saw.

This file is the one home for reading and playing the files: examples/robot/xarm_driver.py imports
read_moves and play from it.
"""
import argparse
import inspect
import math
import signal
import sys
import time

HEADER = "time_s,j1_deg,j2_deg,j3_deg,j4_deg,j5_deg,j6_deg,j7_deg,gripper"
COLUMNS = HEADER.split(",")
# The xArm 7's joint limits in radians, as lib/robot/xarm7.urdf has them from the datasheet
# (tests/tools/test_drivers.py checks that they agree), and its 180 deg/s joint speed.
JOINT_LIMITS_RAD = [(-6.283185, 6.283185), (-2.059489, 2.094395), (-6.283185, 6.283185),
                    (-0.191986, 3.926991), (-6.283185, 6.283185), (-1.692969, 3.141593),
                    (-6.283185, 6.283185)]
MAX_JOINT_SPEED_DEG_S = 180.0
SPEED_SLACK = 1.01          # as xarm-export's own check (robot::JointPathLimits::velocity_slack)
LIMIT_SLACK_DEG = 1e-4      # the file's 6 decimals of a degree around a limit
MAX_DURATION_S = 60.0
GRIPPER_OPEN_UNITS = 850
REACH_SPEED_DEG_S = 20      # how fast the first row is reached in position mode
POLL_S = 0.02               # how often a slow move is watched (and a stop looked for)
REACHED_DEG = 0.5           # a position-mode move has ended once the arm is still within this of its row
STALLED_S = 0.5             # ... and has failed once it stands this long elsewhere
GRIPPER_REACHED_UNITS = 1   # the gripper is there within this (the SDK's own test)
GRIPPER_STALLED_S = 1.0     # a gripper that has not moved for this long holds something: it is done
GRIPPER_TIMEOUT_S = 10.0    # the SDK's own wait for the gripper


class MotionFileError(ValueError):
    """A file that is not a motion the arm may execute; its text names the file and line."""


class Stopped(Exception):
    """play() saw its stop test come true; the arm has been stopped (emergency_stop)."""


def read_moves(path):
    """(time_s, [7 joint degrees], gripper units) rows of an xarm-export file, checked as the
    module's docstring says; a MotionFileError names the file and line of the first fault."""
    rows, header_seen = [], False

    def fail(number, what):
        raise MotionFileError(f"{path}: line {number}: {what}")

    try:
        with open(path, encoding="utf-8") as f:
            lines = f.read().split("\n")
    except (OSError, UnicodeDecodeError) as e:
        raise MotionFileError(f"{path}: {e.strerror if isinstance(e, OSError) else e}") from None
    for number, line in enumerate(lines, 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        if not header_seen:
            if line != HEADER:
                fail(number, f"expected xarm-export's header {HEADER!r}, got {line[:100]!r}")
            header_seen = True
            continue
        cells = line.split(",")
        if len(cells) != len(COLUMNS):
            fail(number, f"expected {len(COLUMNS)} columns, got {len(cells)}")
        values = []
        for column, cell in zip(COLUMNS, cells):
            try:
                value = float(cell)
            except ValueError:
                fail(number, f"{column}: {cell[:40]!r} is not a number")
            if not math.isfinite(value):
                fail(number, f"{column}: {cell!r} is not a finite number")
            values.append(value)
        t, joints, gripper = values[0], values[1:8], values[8]
        if gripper != int(gripper) or not 0 <= gripper <= GRIPPER_OPEN_UNITS:
            fail(number, f"gripper: {cells[8]!r} is not a whole number of units in 0..{GRIPPER_OPEN_UNITS}")
        if not rows and t != 0:
            fail(number, f"time_s: the first row's time is {cells[0]}, not 0")
        if rows and t <= rows[-1][0]:
            fail(number, f"time_s: {cells[0]} does not increase (the row before is at {rows[-1][0]:g} s)")
        if t > MAX_DURATION_S:
            fail(number, f"time_s: {cells[0]} s, longer than {MAX_DURATION_S:g} s")
        for k, (q, (low, high)) in enumerate(zip(joints, JOINT_LIMITS_RAD)):
            if not math.degrees(low) - LIMIT_SLACK_DEG <= q <= math.degrees(high) + LIMIT_SLACK_DEG:
                fail(number, f"j{k + 1}_deg: {cells[k + 1]} outside the joint's limits "
                             f"[{math.degrees(low):.3f}, {math.degrees(high):.3f}]")
            if rows:
                speed = abs(q - rows[-1][1][k]) / (t - rows[-1][0])
                if speed > MAX_JOINT_SPEED_DEG_S * SPEED_SLACK:
                    fail(number, f"j{k + 1}_deg: {speed:.1f} deg/s from the row before, faster than "
                                 f"{MAX_JOINT_SPEED_DEG_S:g} deg/s")
        rows.append((t, joints, int(gripper)))
    if not header_seen:
        raise MotionFileError(f"{path}: no header (expected {HEADER!r})")
    if not rows:
        raise MotionFileError(f"{path}: no rows")
    return rows


def describe(rows):
    """One line: rows, duration, start and end joints, gripper."""
    joints = lambda q: "(" + ",".join(f"{v:.1f}" for v in q) + ")"  # noqa: E731
    return (f"{len(rows)} rows over {rows[-1][0]:.2f} s, joints {joints(rows[0][1])} -> {joints(rows[-1][1])} deg, "
            f"gripper {rows[0][2]} -> {rows[-1][2]}")


# The SDK's return codes (doc/api/xarm_api_code.md of the SDK), for faults in words.
API_CODES = {-9: "emergency stop", -8: "out of range", -7: "joint angle limit", -6: "cartesian position limit",
             -2: "the arm is not ready (motion not enabled or state not set)", -1: "the arm is not connected",
             1: "the controller has an error", 2: "the controller has a warning", 3: "no response in time",
             8: "the command could not be sent (network?)"}


class ArmFault(Exception):
    """An SDK call failed; the text says which and why, in words."""


def check(arm, code, call):
    """SDK calls answer a code, 0 for success; anything else stops the motion with the
    controller's error or warning, in words."""
    if code != 0:
        raise ArmFault(f"{call} returned {code} ({API_CODES.get(code, 'see the SDK code list')}); {controller_state(arm)}")


def controller_state(arm):
    """The controller's error and warning codes in words (the SDK's own descriptions)."""
    try:
        arm.get_err_warn_code()
    except Exception:  # noqa: BLE001 - the codes below are the last ones the arm reported
        pass
    error, warn = getattr(arm, "error_code", 0) or 0, getattr(arm, "warn_code", 0) or 0
    if not error and not warn:
        return "no controller error"
    try:
        from xarm.core.config.x_code import ControllerError, ControllerWarn
    except ImportError:
        ControllerError = ControllerWarn = None
    words = []
    for code, kind, describe_code in ((error, "error", ControllerError), (warn, "warning", ControllerWarn)):
        if code:
            text = describe_code(code).description if describe_code else None
            if isinstance(text, dict):  # {'en': ..., 'cn': ...} in the SDK's newer versions
                text = text.get("en")
            words.append(f"{text or 'controller ' + kind}, {kind} code {code}")
    return "; ".join(words)


def error_codes(arm):
    """The controller's (error, warning) codes as it reports them now."""
    code, codes = arm.get_err_warn_code()
    return (codes[0], codes[1]) if code == 0 else (getattr(arm, "error_code", 0), getattr(arm, "warn_code", 0))


def joints_deg(arm):
    """The arm's 7 joint angles in degrees, as it reports them."""
    code, angles = arm.get_servo_angle(is_radian=False)
    check(arm, code, "get_servo_angle")
    return [float(q) for q in list(angles)[:7]]


def gripper_units(arm):
    """The gripper's position in its units, as it reports it. (The SDK answers a bare code, not
    a pair, when the gripper has a fault.)"""
    answer = arm.get_gripper_position()
    code, position = answer if isinstance(answer, (tuple, list)) else (answer, None)
    check(arm, code, "get_gripper_position")
    if position is None:
        raise ArmFault(f"get_gripper_position gave no position; {controller_state(arm)}")
    return float(position)


def stop_now(arm):
    """Stops the arm where it is, at once."""
    arm.emergency_stop()
    raise Stopped()


def reach(arm, target_deg, stopped):
    """Moves the arm to `target_deg` slowly in position mode, watching it every POLL_S: a stop
    stops it at once (Stopped); a controller error, an arm standing still away from the row or a
    move far longer than its speed allows is an ArmFault (the caller stops the arm)."""
    check(arm, arm.set_servo_angle(angle=target_deg, speed=REACH_SPEED_DEG_S, is_radian=False, wait=False),
          "set_servo_angle")
    start = time.monotonic()
    distance = max(abs(a - b) for a, b in zip(joints_deg(arm), target_deg))
    deadline = start + 2 * distance / REACH_SPEED_DEG_S + 5.0  # its speed's time, with its accelerations and more
    still_since = None
    while True:
        if stopped():
            stop_now(arm)
        error, _ = error_codes(arm)
        if error:
            raise ArmFault(f"set_servo_angle: {controller_state(arm)}")
        now = time.monotonic()
        if arm.get_is_moving():
            still_since = None
        else:
            off = max(abs(a - b) for a, b in zip(joints_deg(arm), target_deg))
            if off <= REACHED_DEG:
                return
            still_since = still_since or now
            if now - still_since > STALLED_S:  # not started, or stopped short
                raise ArmFault(f"the arm stands {off:.1f} deg from the row it was sent to; {controller_state(arm)}")
        if now > deadline:
            raise ArmFault(f"the arm did not reach the row it was sent to in {now - start:.0f} s; "
                           f"{controller_state(arm)}")
        time.sleep(POLL_S)


def move_gripper(arm, target, stopped):
    """Moves the gripper to `target` units, watching it every POLL_S until it is there or stands
    still (it holds something). A stop holds it where it is and stops the arm (Stopped)."""
    command = {"wait": False}
    parameters = inspect.signature(arm.set_gripper_position).parameters.values()
    if any(p.name == "wait_motion" or p.kind == p.VAR_KEYWORD for p in parameters):
        command["wait_motion"] = False  # newer SDKs would first wait for the arm, unwatched
    check(arm, arm.set_gripper_position(target, **command), "set_gripper_position")
    start = last_move = time.monotonic()
    last = None
    while True:
        if stopped():
            try:
                arm.set_gripper_position(gripper_units(arm), **command)  # hold it where it is
            finally:
                stop_now(arm)
        position = gripper_units(arm)
        now = time.monotonic()
        if abs(position - target) <= GRIPPER_REACHED_UNITS:
            return
        if last is None or abs(position - last) >= 1:
            last, last_move = position, now
        elif now - last_move > GRIPPER_STALLED_S:
            return
        if now - start > GRIPPER_TIMEOUT_S:
            raise ArmFault(f"the gripper did not reach {target} in {GRIPPER_TIMEOUT_S:g} s (at {position:g}); "
                           f"{controller_state(arm)}")
        time.sleep(POLL_S)


def play(arm, rows, stopped=lambda: False, pace=1.0):
    """Executes checked rows on an XArmAPI (or anything with its methods). stopped() is asked
    before the motion, every POLL_S during the slow moves (the first row, the gripper) and
    between streamed rows; when it is true, the arm is stopped at once (emergency_stop, the
    gripper held where it is) and Stopped is raised. pace scales the rows' times (0: no waiting,
    for a dry run's stand-in)."""
    _, first, gripper = rows[0]
    if stopped():
        stop_now(arm)
    arm.set_mode(0)  # position mode: reach the first row slowly
    arm.set_state(0)
    reach(arm, first, stopped)
    move_gripper(arm, gripper, stopped)
    if len(rows) == 1:
        return
    arm.set_mode(1)  # servo mode: stream the rows
    arm.set_state(0)
    time.sleep(0.1 * pace)
    start = time.monotonic()
    for t, angles, g in rows:
        if stopped():
            stop_now(arm)
        delay = start + t * pace - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        if g != gripper:
            move_gripper(arm, g, stopped)
            gripper = g
            start = time.monotonic() - t * pace  # the gripper's wait shifts the remaining rows
        check(arm, arm.set_servo_angle_j(angles=angles, is_radian=False), "set_servo_angle_j")


def connect(ip):
    """The arm at `ip` through UFACTORY's SDK: errors cleared, motors and gripper enabled."""
    if not ip:
        sys.exit("--ip is required (or --dry-run)")
    try:
        from xarm.wrapper import XArmAPI
    except ImportError:
        sys.exit("the xArm SDK's Python module is not installed: pip install xarm-python-sdk "
                 "(UFACTORY's; not a Debian package)")
    arm = XArmAPI(ip)
    arm.clean_error()
    arm.motion_enable(enable=True)
    arm.set_gripper_enable(True)
    return arm


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("files", nargs="+")
    parser.add_argument("--ip", help="the xArm controller's address")
    parser.add_argument("--dry-run", action="store_true", help="read and check the files, move nothing")
    args = parser.parse_args()
    try:
        moves = [(path, read_moves(path)) for path in args.files]
    except MotionFileError as e:
        sys.exit(str(e))
    if args.dry_run:
        for path, rows in moves:
            print(f"{path}: {describe(rows)}")
        return
    arm = connect(args.ip)
    interrupted = []
    for signum in (signal.SIGINT, signal.SIGTERM):  # seen within POLL_S, and the arm stopped
        signal.signal(signum, lambda number, frame: interrupted.append(signal.Signals(number).name))
    stopped = False
    try:
        for path, rows in moves:
            print(f"playing {path}", file=sys.stderr)
            try:
                play(arm, rows, lambda: bool(interrupted))
            except Stopped:
                stopped = True
                print(f"{path}: {interrupted[0]}: the arm was stopped (emergency_stop)", file=sys.stderr)
                sys.exit(130)
            except ArmFault as e:
                arm.set_state(4)  # stopped where it is
                stopped = True
                sys.exit(f"{path}: {e}")
    except BaseException:
        if not stopped:
            arm.emergency_stop()
            stopped = True
        raise
    finally:
        if not stopped:
            arm.set_mode(0)
            arm.set_state(0)
        arm.disconnect()


if __name__ == "__main__":
    main()
