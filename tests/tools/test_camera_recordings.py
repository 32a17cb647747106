#!/usr/bin/env python3
"""Camera recordings in: sim-step's frames written out as a camera would save them (colour PNG,
16-bit depth PNG in mm: stream-png --depth-mm) and packed again by obs-pack give the voxels of the
observation itself with its depth rounded to millimetres (that record made here with NumPy and
stream-pack, not by obs-pack): voxel grids equal bit for bit. The joint CSV gives the gripper
pose sim-step reported (forward kinematics); .pcd clouds from stream-dump --pcd, moved into the
camera frame here, come back as the same world points. Bad inputs: one line, exit 1, no output.
Run with a python3 that has NumPy (ctest uses /usr/bin/python3)."""
import importlib.util
import os
import subprocess
import sys
import tempfile

import numpy as np

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOOLS = os.environ.get("QTE_TOOLS") or os.path.join(SOURCE, "build", "tools")
tmp = tempfile.mkdtemp(prefix="qte_camrec_")
sys.path.insert(0, os.path.join(SOURCE, "lib", "python"))
import qte_stream  # noqa: E402


def run(name, *args, stdin=None, ok=True):
    r = subprocess.run([os.path.join(TOOLS, name), *map(str, args)], input=stdin, capture_output=True)
    if ok and r.returncode != 0:
        sys.exit(f"FAIL: {name} {' '.join(map(str, args))} exited {r.returncode}: {r.stderr.decode()}")
    return r


def records(path, kind):
    return [r for r in qte_stream.read_records(path) if r.type == kind]


def numbers(values):  # repr() round-trips float64 exactly
    return ",".join(repr(float(v)) for v in np.asarray(values).reshape(-1))


def p(name):
    return os.path.join(tmp, name)


# The first observation of a pick_and_lift episode, 96 x 64 pixels.
with open(p("obs.rec"), "wb") as f:
    f.write(run("sim-step", "--task", "pick_and_lift", "--seed", 3, "--image-size", "96x64", stdin=b"").stdout)
observations = records(p("obs.rec"), "obs")
obs = observations[0]
run("stream-png", "--depth-mm", "--dir", p("png"), p("obs.rec"))

K = obs.fields["front.intrinsics"]
E = obs.fields["front.extrinsics"]
q = obs.fields["joint_positions"]
opening = float(obs.fields["gripper_opening_m"])
with open(p("joints.csv"), "w") as f:
    f.write("j1,j2,j3,j4,j5,j6,j7,gripper_m\n" + numbers(list(q) + [opening]) + "\n")
index = obs.index
packed = run("obs-pack", "--rgb", p("png/%06d.front.rgb.png"), "--depth", p("png/%06d.front.depth_mm.png"),
             "--start", index, "--count", 1, "--intrinsics", numbers([K[0, 0], K[1, 1], K[0, 2], K[1, 2]]),
             "--extrinsics", numbers(E), "--joints", p("joints.csv"), "--task", "pick_and_lift").stdout
with open(p("packed.rec"), "wb") as f:
    f.write(packed)
(back,) = records(p("packed.rec"), "obs")

failures = []
# Colour and depth as saved.
if not np.array_equal(back.fields["front.rgb"], obs.fields["front.rgb"]):
    failures.append("colour image changed on the way through PNG")
depth = obs.fields["front.depth"].astype(np.float64)
mm = np.clip(np.floor(depth * 1000.0 + 0.5), 0, 65535).astype(np.uint16)  # rounding to nearest
if not np.array_equal(back.fields["front.depth_mm"], mm):
    failures.append("depth in mm differs from the rounded float depth")
for name in ("front.intrinsics", "front.extrinsics", "joint_positions"):
    if not np.array_equal(back.fields[name], obs.fields[name]):
        failures.append(f"{name} differs")
if not np.allclose(back.fields["gripper_pose"][:3], obs.fields["gripper_pose"][:3], atol=1e-9) or \
        abs(abs(np.dot(back.fields["gripper_pose"][3:], obs.fields["gripper_pose"][3:])) - 1) > 1e-9:
    failures.append(f"gripper pose by FK {back.fields['gripper_pose']} != sim's {obs.fields['gripper_pose']}")
if int(back.fields["gripper_open"]) != int(obs.fields["gripper_open"]):
    failures.append("gripper_open differs")

# The reference: the observation itself with millimetre depth, packed by stream-pack from NumPy.
np.save(p("rgb.npy"), obs.fields["front.rgb"])
np.save(p("mm.npy"), mm)
np.save(p("K.npy"), K)
np.save(p("E.npy"), E)
reference = run("stream-pack", "obs", "front.rgb=@" + p("rgb.npy"), "front.depth_mm=@" + p("mm.npy"),
                "front.intrinsics=@" + p("K.npy"), "front.extrinsics=@" + p("E.npy")).stdout


def grids(stream):
    (v,) = [r for r in qte_stream.read_records(tempfile_with(stream)) if r.type == "voxels"]
    return v.fields["depth0.grid"], v.fields["depth1.grid"]


def tempfile_with(data):
    fd, path = tempfile.mkstemp(dir=tmp)
    os.write(fd, data)
    os.close(fd)
    return path


crop = ["--centre", "0.2,0.0,0.8"]
want = grids(run("voxelize", *crop, stdin=reference).stdout)
got = grids(run("voxelize", *crop, stdin=packed).stdout)
for d in range(2):
    if not np.array_equal(want[d], got[d]):
        failures.append(f"depth {d} voxels differ in {int((want[d] != got[d]).sum())} values")
if want[0][..., 9].sum() < 20:
    failures.append("too few occupied voxels for the comparison to mean much")
# And against the float-depth observation itself: rounding to mm moves few points across voxels.
direct = grids(run("voxelize", *crop, stdin=open(p("obs.rec"), "rb").read()).stdout)
moved = int((direct[0][..., 9] != got[0][..., 9]).sum())
print(f"occupancy at depth 0: {int(got[0][..., 9].sum())} voxels, {moved} differ from float depth's")

# .pcd: world clouds from stream-dump --pcd, moved into the camera frame as a sensor saves them.
run("stream-dump", "--summary", "--pcd", p("pcd"), p("obs.rec"))
pcd_path = p(f"pcd/{index:06d}.front.pcd")
with open(pcd_path, "rb") as f:
    header = f.read().split(b"DATA binary\n")[0].decode()
if "FIELDS x y z rgb" not in header or f"WIDTH {96}" not in header or f"HEIGHT {64}" not in header:
    failures.append(f"unexpected .pcd header:\n{header}")
world_points = obs.fields["front.points"].reshape(-1, 3).astype(np.float64)
R, t = E[:3, :3], E[:3, 3]
camera_points = (world_points - t) @ R  # R^T (p - t), row-wise
cam_pcd = p("camera_frame.pcd")
with open(pcd_path, "rb") as f:
    data = f.read()
head, body = data.split(b"DATA binary\n", 1)
packed_points = np.frombuffer(body, dtype=np.float32).reshape(-1, 4).copy()
packed_points[:, :3] = camera_points.astype(np.float32)
with open(cam_pcd, "wb") as f:
    f.write(head + b"DATA binary\n" + packed_points.tobytes())
os.rename(cam_pcd, p("cloud_000007.pcd"))
from_pcd = run("obs-pack", "--pcd", p("cloud_%06d.pcd"), "--start", 7, "--extrinsics", numbers(E)).stdout
(pc,) = [r for r in qte_stream.read_records(tempfile_with(from_pcd)) if r.type == "obs"]
got_points = pc.fields["front.points"].reshape(-1, 3)
finite = np.isfinite(world_points[:, 0])
if not np.array_equal(np.isfinite(got_points[:, 0]), finite):
    failures.append("no-return pixels moved in the .pcd round trip")
elif np.abs(got_points[finite] - world_points[finite]).max() > 2e-6:
    failures.append(f".pcd round trip moved points by {np.abs(got_points[finite] - world_points[finite]).max()} m")
if not np.array_equal(pc.fields["front.rgb"], obs.fields["front.rgb"]):
    failures.append(".pcd colours differ")

# Bad inputs: one line naming the problem, exit 1 (2 for usage), nothing written.
cases = [
    (["--rgb", p("png/%06d.front.rgb.png"), "--depth", p("png/%06d.front.rgb.png"), "--intrinsics", "1,1,1,1",
      "--camera-pose", "0,0,0,0,0,0,1"], 1, "16-bit"),
    (["--rgb", p("png/%06d.front.rgb.png"), "--depth", p("png/%06d.front.depth_mm.png"),
      "--camera-pose", "0,0,0,0,0,0,1"], 2, "--intrinsics"),
    (["--rgb", p("none_%d.png"), "--depth", p("none_%d.png"), "--intrinsics", "1,1,1,1",
      "--camera-pose", "0,0,0,0,0,0,1"], 1, "no such frame"),
    (["--pcd", p("pcd/%06d.front.pcd"), "--camera-pose", "0,0,0,0,0,0,2"], 2, "unit quaternion"),
    (["--pcd", p("pcd/%s.front.pcd"), "--camera-pose", "0,0,0,0,0,0,1"], 2, "one integer conversion"),
    (["--pcd", p("pcd/%06d.front.pcd"), "--start", index, "--camera-pose", "0,0,0,0,0,0,1", "--joints", p("deg.csv")],
     1, "degrees"),
]
with open(p("deg.csv"), "w") as f:
    f.write("0,45,0,90,0,45,0\n")
for args, status, words in cases:
    r = run("obs-pack", *args, "--output", p("bad.rec"), ok=False)
    err = r.stderr.decode()
    if r.returncode != status or words not in err or err.count("\n") != 1 or os.path.exists(p("bad.rec")):
        failures.append(f"obs-pack {args}: exit {r.returncode}, stderr {err!r}")

if failures:
    print("\n".join("FAIL: " + f for f in failures))
    sys.exit(1)
print("ok: PNG and .pcd round trips give the direct voxels and points")
