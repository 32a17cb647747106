#!/usr/bin/env python3
"""Recorded demonstrations in: demo-record's simulated demonstrations written out as a real one is
recorded (colour and 16-bit millimetre depth PNGs: stream-png --depth-mm; a frame-times CSV on a
clock of its own; a joint log at 200 Hz, sampled at times that are not the frames') and packed
again by obs-pack --joint-log --frame-times --success give keyframe the same keyframes and
transitions as the simulated stream.

The simulator's joints exist only at its frames, so the 200 Hz log is a cubic Hermite curve
through the frames' joint positions with the simulator's velocities as slopes (0 where a motion
ends: the arm at rest), and rows after frame k carry frame k+1's gripper (the gripper acts at
the start of the interval). What may differ, and by how much at most (asserted):
- joint_positions: the log interpolated linearly between rows 5 ms apart: JOINT_TOLERANCE_RAD;
  gripper_pose and the transitions' target_pose follow by forward kinematics: POSE_TOLERANCE_M
  in position, 1 - |<q, q'>| <= QUATERNION_TOLERANCE in rotation.
- joint_velocities: the slope of the log over its 5 ms interval around the frame, not the mean
  over the 50 ms control step before it: VELOCITY_TOLERANCE_RAD_S (every simulated velocity that
  is not 0 is above 0.14 rad/s, so the 0.1 rad/s stop test decides alike).
- gripper_opening_m: interpolated between rows: OPENING_TOLERANCE_M; gripper_open is equal.
- depth: millimetres in both (keyframe's frame records round the simulated metres as
  stream-png does): equal; colour, camera matrices, frame, step, time_s (to 1e-9 s), reward,
  terminal, success: equal.
- ignore_collisions: 0 in a recording (it cannot tell), the expert's own in simulation.
- the episode key (a hash of the last gripper pose's bytes) differs.
Transitions: the same frames, steps, voxel indices at every depth, bounds, rotation bins,
gripper, reward and terminal flag. A log at the frames' rate only hides most stops (printed).
Bad inputs: one line, nonzero exit, nothing written (an append leaves the file as it was).
Run with a python3 that has NumPy and zstandard (ctest uses /usr/bin/python3)."""
import os
import sys
import tempfile

import numpy as np

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(SOURCE, "tests", "standin"))
from write_recording import CLOCK_S, episodes_of, field, run, write_log, write_recordings  # noqa: E402
import write_recording  # noqa: E402
import qte_stream  # noqa: E402  (on the path write_recording sets)

tmp = tempfile.mkdtemp(prefix="qte_recdemo_")
JOINT_TOLERANCE_RAD = 3e-4
POSE_TOLERANCE_M = 2e-4
QUATERNION_TOLERANCE = 1e-8
VELOCITY_TOLERANCE_RAD_S = 0.1
OPENING_TOLERANCE_M = 1e-3
failures = []


def p(name):
    return os.path.join(tmp, name)


def pack(episode, log, times, output, *extra, ok=True):  # pick_and_lift's frames
    return write_recording.pack(p("pick_and_lift/png"), episode, log, times, output, *extra, ok=ok)


def keyframe_output(stream):
    out = p(os.path.basename(stream) + ".transitions")
    err = run("keyframe", "--seed", 7, "--output", out, stream).stderr.decode().strip()
    frames, transitions = {}, []
    episode = -1
    for r in qte_stream.read_records(out):
        if r.type == "frame":
            if int(r.fields["frame"]) == 0:
                episode += 1
            frames[(episode, int(r.fields["frame"]))] = r
        elif r.type == "transition":
            transitions.append((episode, r))
    return frames, transitions, err


def quaternion_gap(a, b):
    return 1 - abs(float(np.dot(a, b)))


def compare_observations(task, e, sim, packed, log_times, worst):
    if len(sim) != len(packed):
        failures.append(f"{task} episode {e}: {len(packed)} frames packed, {len(sim)} simulated")
        return
    for name in ("frame", "step", "terminal", "success", "reward", "gripper_open", "episode_length"):
        if not np.array_equal(field(sim, name), field(packed, name)):
            failures.append(f"{task} episode {e}: {name} {field(packed, name)} != simulated {field(sim, name)}")
    for name in ("front.rgb", "front.intrinsics", "front.extrinsics"):
        if any(not np.array_equal(a.fields[name], b.fields[name]) for a, b in zip(sim, packed)):
            failures.append(f"{task} episode {e}: {name} differs")
    sim_mm = [np.clip(np.floor(a.fields["front.depth"].astype(np.float64) * 1000 + 0.5), 0, 65535) for a in sim]
    if any(not np.array_equal(m, b.fields["front.depth_mm"]) for m, b in zip(sim_mm, packed)):
        failures.append(f"{task} episode {e}: depth_mm is not the simulated depth rounded to mm")
    # Two frames inside one log interval (a motion's last control step can be 1 ms) get that
    # interval's slope, a mean over both: their velocities are not compared.
    t = field(sim, "time_s")
    j = np.searchsorted(log_times, t, side="left")
    others = [np.delete(t, i) for i in range(len(t))]
    apart = np.array([not np.any((o > log_times[j[i] - 1]) & (o < log_times[j[i]])) for i, o in enumerate(others)])
    velocity_gaps = np.abs(field(sim, "joint_velocities") - field(packed, "joint_velocities")).max(axis=1)
    worst["frames sharing a log interval"] = worst.get("frames sharing a log interval", 0) + int((~apart).sum())
    worst["their joint_velocities"] = max(worst.get("their joint_velocities", 0.0), float(velocity_gaps[~apart].max(initial=0)))
    gaps = {
        "time_s": np.abs(field(sim, "time_s") - field(packed, "time_s")).max(),
        "joint_positions": np.abs(field(sim, "joint_positions") - field(packed, "joint_positions")).max(),
        "joint_velocities": velocity_gaps[apart].max(),
        "gripper_opening_m": np.abs(field(sim, "gripper_opening_m") - field(packed, "gripper_opening_m")).max(),
        "gripper_pose position": np.linalg.norm(field(sim, "gripper_pose")[:, :3] - field(packed, "gripper_pose")[:, :3], axis=1).max(),
        "gripper_pose rotation": max(quaternion_gap(a, b) for a, b in
                                     zip(field(sim, "gripper_pose")[:, 3:], field(packed, "gripper_pose")[:, 3:])),
    }
    limits = {"time_s": 1e-9, "joint_positions": JOINT_TOLERANCE_RAD, "joint_velocities": VELOCITY_TOLERANCE_RAD_S,
              "gripper_opening_m": OPENING_TOLERANCE_M, "gripper_pose position": POSE_TOLERANCE_M,
              "gripper_pose rotation": QUATERNION_TOLERANCE}
    for name, gap in gaps.items():
        worst[name] = max(worst.get(name, 0.0), float(gap))
        if gap > limits[name]:
            failures.append(f"{task} episode {e}: {name} differs by {gap:.3g} (at most {limits[name]:.3g})")


def compare_transitions(task, sim, packed):
    sim_frames, sim_transitions, sim_err = sim
    packed_frames, packed_transitions, packed_err = packed
    print(f"{task}: keyframe on the simulated stream: {sim_err}\n{task}: keyframe on the packed recordings: {packed_err}")
    keyframes = sorted({(e, int(t.fields["next_frame"])) for e, t in sim_transitions})
    print(f"{task}: keyframes (episode, frame): {keyframes}")
    if len(sim_transitions) != len(packed_transitions) or not sim_transitions:
        failures.append(f"{task}: {len(packed_transitions)} transitions from the recordings, "
                        f"{len(sim_transitions)} from the simulated stream")
        return
    exact = ["frame", "next_frame", "step", "voxels", "rotation_bins", "gripper_open", "reward", "terminal", "demo",
             "depth0.index", "depth0.bounds", "depth1.index", "depth1.bounds"]
    ignore_collisions = 0
    for (e, a), (f, b) in zip(sim_transitions, packed_transitions):
        where = f"{task} episode {e} transition {int(a.fields['frame'])}->{int(a.fields['next_frame'])}"
        if e != f:
            failures.append(f"{where}: in episode {f} of the recordings")
        for name in exact:
            if not np.array_equal(a.fields[name], b.fields[name]):
                failures.append(f"{where}: {name} {b.fields[name]} != simulated {a.fields[name]}")
        gap = np.linalg.norm(a.fields["target_pose"][:3] - b.fields["target_pose"][:3])
        if gap > POSE_TOLERANCE_M or quaternion_gap(a.fields["target_pose"][3:], b.fields["target_pose"][3:]) > QUATERNION_TOLERANCE:
            failures.append(f"{where}: target_pose moved by {gap:.3g} m")
        if int(b.fields["ignore_collisions"]) != 0:
            failures.append(f"{where}: ignore_collisions set from a recording")
        ignore_collisions += int(a.fields["ignore_collisions"])
    print(f"{task}: {len(sim_transitions)} transitions alike; {ignore_collisions} simulated ones ignore collisions "
          f"(0 in the recordings)")
    if sorted(sim_frames) != sorted(packed_frames):
        failures.append(f"{task}: the frame records differ: {sorted(set(sim_frames) ^ set(packed_frames))}")
        return
    for key, a in sim_frames.items():
        b = packed_frames[key]
        for name in ("front.rgb", "front.depth_mm", "front.intrinsics", "front.extrinsics", "gripper_open", "task",
                     "episode_length", "variation"):
            if not np.array_equal(a.fields[name], b.fields[name]):
                failures.append(f"{task} frame record {key}: {name} differs")
        if np.abs(a.fields["joint_positions"] - b.fields["joint_positions"]).max() > JOINT_TOLERANCE_RAD:
            failures.append(f"{task} frame record {key}: joint_positions differ")


def check_task(task, episodes):
    stream = p(f"{task}.rec")
    run("demo-record", "--task", task, "--episodes", episodes, "--seed", 0, "--image-size", "48x40", "--no-points",
        "--output", stream)
    packed = p(f"{task}.packed.rec")
    os.makedirs(p(task), exist_ok=True)
    simulated, log_times = write_recordings(stream, p(task), packed)
    worst = {}
    for e, (sim, back) in enumerate(zip(simulated, episodes_of(packed))):
        compare_observations(task, e, sim, back, log_times[e], worst)
    print(f"{task}: largest differences of the packed observations: " +
          ", ".join(f"{name} {gap:.3g}" for name, gap in worst.items()))
    compare_transitions(task, keyframe_output(stream), keyframe_output(packed))
    return simulated


check_task("reach_prism", 1)
episodes = check_task("pick_and_lift", 2)

# Determinism: the same recording packs to the same bytes.
first = episodes[0]
log, times = p("pick_and_lift/e0.log.csv"), p("pick_and_lift/e0.frames.csv")
pack(first, log, times, p("once.rec"), "--success", 1)
pack(first, log, times, p("twice.rec"), "--success", 1)
if open(p("once.rec"), "rb").read() != open(p("twice.rec"), "rb").read():
    failures.append("the same recording packed twice gave different bytes")

# A log at the frames' own times (the camera's rate): the stops at the end of each motion are
# mostly not seen, the velocity being the mean over the frame interval that led there.
write_log(p("frame_rate.log.csv"), first, rows_at=field(first, "time_s"))
pack(first, p("frame_rate.log.csv"), times, p("frame_rate.rec"), "--success", 1)
_, at_frame_rate, _ = keyframe_output(p("frame_rate.rec"))
_, at_200_hz, _ = keyframe_output(p("once.rec"))
print(f"pick_and_lift episode 0: keyframes {sorted({int(t.fields['next_frame']) for _, t in at_200_hz})} from the "
      f"200 Hz log, {sorted({int(t.fields['next_frame']) for _, t in at_frame_rate})} from a log at the frames' times")

# Bad inputs: one line naming the problem, nonzero exit (2 for usage), nothing written.
rows = open(log).read().splitlines()
bad_files = {
    "backwards.csv": "\n".join(rows[:5] + [rows[6], rows[5]] + rows[7:]) + "\n",  # two rows swapped
    "short.csv": "\n".join(",".join(r.split(",")[:8]) for r in rows) + "\n",  # no gripper opening
    "half_open.csv": "\n".join(rows[:3] + [rows[3].rsplit(",", 1)[0] + ",0.5"] + rows[4:]) + "\n",
    "late_frames.csv": "".join(repr(CLOCK_S + 100 + i) + "\n" for i in range(len(first))),
    "more_frames.csv": open(times).read() + repr(CLOCK_S + float(first[-1].fields["time_s"]) + 0.001) + "\n",
}
for name, text in bad_files.items():
    with open(p(name), "w") as f:
        f.write(text)
cases = [
    ([p("backwards.csv"), times], 1, "backwards.csv: line 7: time"),
    ([p("short.csv"), times], 1, "short.csv: line 2: 8 columns, expected 9 or 10"),
    ([p("half_open.csv"), times], 1, "half_open.csv: line 4: column 10 is 0.500000, expected 1 (gripper open) or 0"),
    ([log, p("late_frames.csv")], 1, "late_frames.csv: line 1: frame time 1334.5 s is outside the joint log"),
    ([log, p("more_frames.csv")], 1, "no such frame"),
    # Endless inputs are bounded: a line of a joint log or of frame times is at most 4 KiB.
    (["/dev/zero", times], 1, "/dev/zero: line 1 is longer than 4 KiB"),
    ([log, "/dev/zero"], 1, "/dev/zero: line 1 is longer than 4 KiB"),
]
with open(p("kept.rec"), "wb") as f:
    f.write(open(p("once.rec"), "rb").read())
for (log_file, times_file), status, words in cases:
    for output, extra in ((p("bad.rec"), []), (p("kept.rec"), ["--append"])):
        r = pack(first, log_file, times_file, output, "--success", 1, *extra, ok=False)
        err = r.stderr.decode()
        if r.returncode != status or words not in err or err.count("\n") != 1:
            failures.append(f"obs-pack --joint-log {os.path.basename(log_file)} --frame-times "
                            f"{os.path.basename(times_file)}: exit {r.returncode}, stderr {err!r}")
if os.path.exists(p("bad.rec")):
    failures.append("a failed obs-pack left its output")
if open(p("kept.rec"), "rb").read() != open(p("once.rec"), "rb").read():
    failures.append("a failed append changed the file")
usage = run("obs-pack", "--pcd", p("x_%d.pcd"), "--camera-pose", "0,0,0,0,0,0,1", "--success", 1, ok=False)
if usage.returncode != 2 or b"--success needs --joint-log" not in usage.stderr:
    failures.append(f"--success without a joint log: exit {usage.returncode}, {usage.stderr!r}")

if failures:
    print("\n".join("FAIL: " + f for f in failures))
    sys.exit(1)
print("ok: recorded demonstrations give the simulated stream's keyframes and transitions")
