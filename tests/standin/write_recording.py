#!/usr/bin/env python3
"""Simulated demonstrations written out as real ones are recorded, and packed again: what a
person with a camera and an arm's joint log hands to obs-pack, made from demo-record's stream.

    write_recording.py DEMOS.rec DIR OUTPUT.rec

For each episode of DEMOS.rec: its colour and 16-bit millimetre depth PNGs (stream-png
--depth-mm) in DIR/png, the frames' times on a recorder's clock of its own (DIR/eN.frames.csv)
and a 200 Hz joint log sampled at times that are not the frames' (DIR/eN.log.csv); then
obs-pack --joint-log --frame-times --success appends it to OUTPUT.rec. The simulator's joints
exist only at its frames, so the log is a cubic Hermite curve through the frames' joint
positions with the simulator's velocities as slopes; rows after frame k carry frame k+1's
gripper state. tests/tools/test_recorded_demo.py checks what this gives against the simulated
stream; the stand-in loop (compare_loops.sh) learns from it."""
import os
import subprocess
import sys

import numpy as np

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOOLS = os.environ.get("QTE_TOOLS") or os.path.join(SOURCE, "build", "tools")
sys.path.insert(0, os.path.join(SOURCE, "lib", "python"))
import qte_stream  # noqa: E402

LOG_PERIOD_S = 0.005
CLOCK_S = 1234.5  # the recorder's clock at the first frame


def run(name, *args, ok=True):
    r = subprocess.run([os.path.join(TOOLS, name), *map(str, args)], capture_output=True)
    if ok and r.returncode != 0:
        sys.exit(f"FAIL: {name} {' '.join(map(str, args))} exited {r.returncode}: {r.stderr.decode()}")
    return r


def numbers(values):  # repr() round-trips float64 exactly
    return ",".join(repr(float(v)) for v in np.asarray(values).reshape(-1))


def episodes_of(path):
    """The obs records of each episode of a stream (a new one at frame 0)."""
    episodes = []
    for r in qte_stream.read_records(path):
        if r.type == "obs":
            if not episodes or (int(r.fields["frame"]) == 0 and episodes[-1]):
                episodes.append([])
            episodes[-1].append(r)
    return episodes


def field(records, name):
    return np.array([np.asarray(r.fields[name], dtype=np.float64) for r in records])


def write_log(path, episode, rows_at=None):
    """The joint log of an episode: rows at `rows_at` (default 200 Hz from 12.3 ms before the
    first frame to past the last), a cubic Hermite curve through the frames."""
    t = field(episode, "time_s")
    q = field(episode, "joint_positions")
    v = field(episode, "joint_velocities")
    opening = field(episode, "gripper_opening_m")
    is_open = field(episode, "gripper_open")
    if rows_at is None:
        rows_at = t[0] - 0.0123 + LOG_PERIOD_S * np.arange(int((t[-1] - t[0] + 0.03) / LOG_PERIOD_S))
    k = np.clip(np.searchsorted(t, rows_at, side="left") - 1, 0, len(t) - 2)  # t[k] < s <= t[k+1]
    h = t[k + 1] - t[k]
    u = np.clip((rows_at - t[k]) / h, 0.0, 1.0)[:, None]
    hh = h[:, None]
    joints = ((2 * u**3 - 3 * u**2 + 1) * q[k] + (u**3 - 2 * u**2 + u) * hh * v[k] + (-2 * u**3 + 3 * u**2) * q[k + 1] +
              (u**3 - u**2) * hh * v[k + 1])
    fingers = np.interp(rows_at, t, opening)  # the fingers move through the interval
    after = np.clip(np.searchsorted(t, rows_at, side="left"), 0, len(t) - 1)  # the frame whose interval holds s
    with open(path, "w") as f:
        f.write("time_s,j1,j2,j3,j4,j5,j6,j7,gripper_m,gripper_open\n")
        for i, s in enumerate(rows_at):
            f.write(numbers([CLOCK_S + s, *joints[i], fingers[i], is_open[after[i]]]) + "\n")
    return rows_at


def write_frame_times(path, episode):
    with open(path, "w") as f:
        f.write("time_s\n" + "".join(repr(CLOCK_S + float(o.fields["time_s"])) + "\n" for o in episode))


def pack(png_dir, episode, log, times, output, *extra, ok=True):
    first = episode[0]
    K, E = first.fields["front.intrinsics"], first.fields["front.extrinsics"]
    return run("obs-pack", "--rgb", os.path.join(png_dir, "%06d.front.rgb.png"),
               "--depth", os.path.join(png_dir, "%06d.front.depth_mm.png"),
               "--start", first.index, "--intrinsics", numbers([K[0, 0], K[1, 1], K[0, 2], K[1, 2]]),
               "--extrinsics", numbers(E), "--joint-log", log, "--frame-times", times, "--no-points",
               "--task", first.fields["task"], "--episode-length", int(first.fields["episode_length"]),
               "--output", output, *extra, ok=ok)


def write_recordings(stream, directory, output):
    """Every episode of `stream` recorded into `directory` and packed onto `output`; returns the
    simulated episodes and each one's log times."""
    png = os.path.join(directory, "png")
    run("stream-png", "--depth-mm", "--dir", png, stream)
    simulated, log_times = episodes_of(stream), []
    for e, episode in enumerate(simulated):
        log, times = os.path.join(directory, f"e{e}.log.csv"), os.path.join(directory, f"e{e}.frames.csv")
        log_times.append(write_log(log, episode))
        write_frame_times(times, episode)
        pack(png, episode, log, times, output, "--success", int(episode[-1].fields["success"]), "--append")
    return simulated, log_times


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    os.makedirs(sys.argv[2], exist_ok=True)
    episodes, _ = write_recordings(*sys.argv[1:])
    print(f"write_recording.py: {len(episodes)} demonstrations packed onto {sys.argv[3]}", file=sys.stderr)
