#!/usr/bin/env python3
"""The xArm 7's driver for the robot spool (formats/robot-spool.md): executes robot-step's motions.

    python3 examples/robot/xarm_driver.py --spool spool --ip 192.168.1.185
    python3 examples/robot/xarm_driver.py --spool spool --dry-run        # no SDK, no robot

Watches the spool for motion-<session>-<n>.xarm.csv and executes each in the order robot-step
wrote them, with UFACTORY's Python SDK (pip install xarm-python-sdk; not a dependency of the
toolkit). Each file is checked again before anything moves (examples/robot/xarm_play.py's read_moves:
header, finite numbers, times from 0 and increasing, joint limits and speeds); its first row is
reached slowly, then the rows are streamed at their times (xarm_play.py's play). A motion of
several rows must start where the arm is, within --start-tolerance degrees (robot-step plans it
from the joints the last answer gave; the way to a first row elsewhere was never checked); one
row is a move there (a reset), reached slowly in joint space: watch it. The answer is
motion-...-n.done, the joints reached (degrees) and the gripper (units), or motion-...-n.fault,
one line: the file's fault naming its line (nothing moved) or the controller's error or warning
in words (the arm left stopped where it is). A controller error left by a fault is cleared
before the next motion, which robot-step sends only after the scene was reset.

The slow moves (the first row, the gripper) are commanded without the SDK's waiting and watched
every 20 ms; `stop` in the spool is checked then, before each motion and between streamed rows:
the arm is stopped at once (emergency_stop; the gripper held where it is) and the driver exits
without answering anything more (status 0). SIGINT (Ctrl-C) or SIGTERM do the same (status 130)
and write `stop` in the spool, saying why, so that robot-step stops at once and withdraws the
request left unanswered (a driver started again beside `stop` exits at once: a person looks
first). An error of any other kind while a motion is executed is answered with its .fault (the
error's type and words) and the arm is left stopped; one outside a motion (the spool, or the
arm not answering even the stop) ends the driver after it has stopped the arm and written
`stop`, saying why. The gripper's position in a .done is a whole number of units in 0..850 (a
gripper may report 851 open), and a motion after which the arm does not come to rest within
5 s is answered with a .fault, not with joints still moving.

--dry-run imports no SDK: it checks each file, prints one line per motion (rows, duration, start
and end joints, gripper) and answers .done as a perfect arm would: the last row's joints and
gripper (with the same start check against the joints it last reached). --pace 1 makes it take
the motion's own time (stop is then checked between rows as on the arm); 0, the default,
answers at once.
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import robot_spool  # noqa: E402
import xarm_play  # noqa: E402  the one home for reading and playing xarm-export files


class PerfectArm:
    """The dry run's arm: the SDK calls play() makes, answered at once; it ends where told."""

    def __init__(self):
        self.angles, self.gripper = None, None

    def set_mode(self, mode):
        return 0

    def set_state(self, state):
        return 0

    def set_servo_angle(self, angle, **_):
        self.angles = list(angle)
        return 0

    def set_servo_angle_j(self, angles, **_):
        self.angles = list(angles)
        return 0

    def set_gripper_position(self, position, **_):
        self.gripper = position
        return 0

    # What play() watches during the slow moves: the perfect arm is there at once.
    def get_servo_angle(self, **_):
        return 0, list(self.angles)

    def get_gripper_position(self, **_):
        return 0, self.gripper

    def get_is_moving(self):
        return False

    def get_err_warn_code(self, **_):
        return 0, [0, 0]

    def emergency_stop(self):
        return 0


def numbers(joints, gripper):
    """The .done line: joints in degrees, the gripper a whole number of units in 0..850 (a real
    gripper reports 851 open, and robot-step refuses a value out of range)."""
    units = min(max(int(round(gripper)), 0), xarm_play.GRIPPER_OPEN_UNITS)
    return ",".join(f"{q:.6f}" for q in joints) + f",{units}"


class Driver:
    def __init__(self, spool, arm, dry_run, pace, start_tolerance_deg):
        self.spool, self.dry_run, self.pace = spool, dry_run, pace
        self.arm = PerfectArm() if dry_run else arm
        self.start_tolerance_deg = start_tolerance_deg
        self.fault_left = False  # the last motion ended in a controller fault, not cleared yet

    def away_from_start(self, rows, joints):
        """A motion of several rows starts where the arm is (robot-step planned it from the
        joints the last answer gave): the way to a first row far away was never checked, so
        such a motion is refused, in words. A one-row motion (a reset) is reached slowly."""
        if len(rows) == 1 or joints is None:
            return None
        offsets = [abs(a - b) for a, b in zip(rows[0][1], joints)]
        k = max(range(7), key=offsets.__getitem__)
        if offsets[k] <= self.start_tolerance_deg:
            return None
        words = (f"the motion starts {offsets[k]:.1f} deg from where the arm is (j{k + 1} at {joints[k]:.3f} deg, "
                 f"the first row {rows[0][1][k]:.3f} deg; more than {self.start_tolerance_deg:g}): not moved")
        print(f"refused: {words}", flush=True)
        return words

    def handle(self, stem, name):
        path = self.spool.path(name)
        try:
            rows = xarm_play.read_moves(path)
        except xarm_play.MotionFileError as e:
            words = " ".join(str(e).replace(path, name, 1).split())  # the request's name, not the driver's path
            print(f"refused: {words}", flush=True)
            self.spool.answer(name, stem, "fault", words)
            return
        print(f"{name}: {xarm_play.describe(rows)}", flush=True)
        if self.dry_run:
            far = self.away_from_start(rows, self.arm.angles)
            if far:
                self.spool.answer(name, stem, "fault", far)
                return
            try:
                xarm_play.play(self.arm, rows, self.spool.stopped, self.pace)
            except xarm_play.Stopped:
                return
            self.spool.answer(name, stem, "done", numbers(self.arm.angles, self.arm.gripper))
            return
        try:
            if self.fault_left:
                clear(self.arm)
                self.fault_left = False
            far = self.away_from_start(rows, xarm_play.joints_deg(self.arm))
            if far:
                self.spool.answer(name, stem, "fault", far)
                return
            xarm_play.play(self.arm, rows, self.spool.stopped)
            wait_until_still(self.arm, self.spool.stopped)
            error, _ = xarm_play.error_codes(self.arm)
            if error:  # an error raised after the last command was taken (a late collision)
                raise xarm_play.ArmFault(xarm_play.controller_state(self.arm))
            angles = xarm_play.joints_deg(self.arm)
            gripper = xarm_play.gripper_units(self.arm)
        except xarm_play.Stopped:  # the arm was stopped at once; nothing more is answered
            return
        except Exception as e:  # noqa: BLE001 - the SDK's, the network's, or a fault of this program
            # Stopped where it is before anything else; if even that fails, the driver ends
            # (Spool.serve writes `stop`, main stops the arm).
            self.arm.set_state(4)
            self.fault_left = True
            words = robot_spool.in_words(e, xarm_play.ArmFault)
            print(f"{name}: fault: {words}", flush=True)
            self.spool.answer(name, stem, "fault", words)
            return
        self.spool.answer(name, stem, "done", numbers(angles, gripper))


def clear(arm):
    """Clears the error a faulted motion left, so the reset motion can run."""
    print(f"clearing the controller's state left by the last fault: {xarm_play.controller_state(arm)}",
          file=sys.stderr)
    arm.clean_error()
    arm.clean_warn()
    arm.motion_enable(enable=True)
    arm.set_mode(0)
    arm.set_state(0)


def wait_until_still(arm, stopped, timeout_s=5.0):
    """The motion has ended once the arm no longer moves (the last servo row takes a moment); an
    arm still moving after timeout_s is a fault, not a motion done."""
    deadline = time.monotonic() + timeout_s
    time.sleep(0.05)
    while arm.get_is_moving():
        if stopped():
            xarm_play.stop_now(arm)
        if time.monotonic() > deadline:
            raise xarm_play.ArmFault(f"the arm did not come to rest within {timeout_s:g} s of the motion's last row; "
                                     f"{xarm_play.controller_state(arm)}")
        time.sleep(xarm_play.POLL_S)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--spool", required=True, help="the spool directory robot-step writes to")
    parser.add_argument("--ip", help="the xArm controller's address")
    parser.add_argument("--dry-run", action="store_true", help="no SDK and no robot: check, print, answer as a perfect arm")
    parser.add_argument("--pace", type=float, default=0.0,
                        help="with --dry-run: play at this multiple of the motions' own time (default 0: at once)")
    parser.add_argument("--start-tolerance", type=float, default=2.0,
                        help="degrees a motion's first row may be from the arm's joints (default 2)")
    parser.add_argument("--poll", type=float, default=0.02, help="seconds between looks at the spool (default 0.02)")
    args = parser.parse_args()
    spool = robot_spool.Spool(args.spool, "motion", ["done", "fault"], args.poll)
    arm = None
    if not args.dry_run:
        arm = xarm_play.connect(args.ip)
        arm.set_mode(0)
        arm.set_state(0)
    try:
        status = spool.serve(Driver(spool, arm, args.dry_run, args.pace, args.start_tolerance).handle, "xarm_driver")
    finally:
        if arm is not None:  # however the driver ends (stop, a signal, an error), the arm stands still
            arm.emergency_stop()
            arm.disconnect()
    sys.exit(status)


if __name__ == "__main__":
    main()
