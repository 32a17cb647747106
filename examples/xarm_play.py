#!/usr/bin/env python3
"""Plays xarm-export files on a real xArm 7 with UFACTORY's Python SDK.

    python3 examples/xarm_play.py --ip 192.168.1.185 moves/000004.xarm.csv [more.csv ...]
    python3 examples/xarm_play.py --dry-run moves/*.xarm.csv     # check the files, move nothing

The SDK is not a dependency of the toolkit; install it where the robot is reached from:
    pip install xarm-python-sdk        (https://github.com/xArm-Developer/xArm-Python-SDK)

Each file's first row is reached slowly in position mode (set_servo_angle, 20 deg/s), then the
rows are streamed in servo mode (mode 1, set_servo_angle_j) at the file's own times; the gripper
is moved (set_gripper_position, waiting) whenever its column changes. Keep a hand on the
emergency stop: the planner saw only what the camera saw.
"""
import argparse
import sys
import time


def read_moves(path):
    """(times, joint degrees, gripper units) rows of an xarm-export file; errors name the line."""
    rows, header_seen = [], False
    with open(path) as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            if not header_seen:
                if line != "time_s,j1_deg,j2_deg,j3_deg,j4_deg,j5_deg,j6_deg,j7_deg,gripper":
                    sys.exit(f"{path}: line {number}: expected xarm-export's header, got {line!r}")
                header_seen = True
                continue
            cells = line.split(",")
            if len(cells) != 9:
                sys.exit(f"{path}: line {number}: expected 9 columns, got {len(cells)}")
            values = [float(c) for c in cells]
            rows.append((values[0], values[1:8], int(values[8])))
    if not rows:
        sys.exit(f"{path}: no rows")
    return rows


def play(arm, rows):
    _, first, gripper = rows[0]
    arm.set_mode(0)  # position mode: reach the first row slowly
    arm.set_state(0)
    arm.set_servo_angle(angle=first, speed=20, is_radian=False, wait=True)
    arm.set_gripper_position(gripper, wait=True)
    arm.set_mode(1)  # servo mode: stream the rows
    arm.set_state(0)
    time.sleep(0.1)
    start = time.monotonic()
    for t, angles, g in rows:
        delay = start + t - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        if g != gripper:
            arm.set_gripper_position(g, wait=True)
            gripper = g
            start = time.monotonic() - t  # the gripper's wait shifts the remaining rows
        arm.set_servo_angle_j(angles=angles, is_radian=False)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("files", nargs="+")
    parser.add_argument("--ip", help="the xArm controller's address")
    parser.add_argument("--dry-run", action="store_true", help="read and check the files, move nothing")
    args = parser.parse_args()
    moves = [(path, read_moves(path)) for path in args.files]
    if args.dry_run:
        for path, rows in moves:
            print(f"{path}: {len(rows)} rows over {rows[-1][0]:.2f} s, gripper {rows[0][2]} -> {rows[-1][2]}")
        return
    if not args.ip:
        sys.exit("--ip is required (or --dry-run)")
    from xarm.wrapper import XArmAPI  # pip install xarm-python-sdk
    arm = XArmAPI(args.ip)
    arm.clean_error()
    arm.motion_enable(enable=True)
    arm.set_gripper_enable(True)
    try:
        for path, rows in moves:
            print(f"playing {path}", file=sys.stderr)
            play(arm, rows)
    finally:
        arm.set_mode(0)
        arm.set_state(0)
        arm.disconnect()


if __name__ == "__main__":
    main()
