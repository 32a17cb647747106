#!/usr/bin/env python3
"""What makes a task coarsely ambiguous, by numbers: the objects in the first observation of a
demonstration, the target being the one the task names (in streams without objects.*, the one
the expert first closes the gripper over or, if it never does, the one its last pose is over).

    ambiguity.py centres DEMO.rec               one line per object, x,y,z (target first,
                                                then its lookalikes)
    ambiguity.py places DEMO.rec                where the expert first releases what it holds
                                                (the target), then 4 cm along x and 4 cm along
                                                x and y from there (setup_checkers' neighbours)
    ambiguity.py compare VOXELS.rec             after voxelize --centre <each of them>: the
                                                depth-0 voxel of each object (its 10 channels)
                                                and the top view of its depth-1 grid

Objects are the task's own, with their roles, where the observations carry them (demo-record
--objects, as ambiguity.sh records): the target first, then its lookalikes (the distractors),
each at its bounding box's centre. In streams without them, objects are the points 3 mm to
10 cm above the table top inside the task region, grouped by distance (5 cm), and the target
is the one the expert goes for; the table top is at 0.752 m (DESIGN's layout).

The rule for where an action went, shared with failure_reasons.py and depth_decisions.py
(object_at): a point lies on an object when, in the object's frame, it is inside the object's
bounding box grown by a margin on every side and reaching `ABOVE_M` (10 cm) higher — poses
above an object, from which it is grasped or reached, count as on it. Among several, targets
and distractors come before other objects (zones, bins, boards), then the nearest in plan view
to the box's centre. Run with Debian's python3."""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "lib", "python"))  # or installed: make install
from qte_stream import read_records, scene_objects  # noqa: E402

TABLE_Z, REGION = 0.752, ((-0.05, 0.35), (-0.3, 0.3))
ABOVE_M = 0.1


def rotation(pose):
    """The rotation matrix of a pose's quaternion (x, y, z, w)."""
    x, y, z, w = np.asarray(pose[3:7], np.float64) / np.linalg.norm(pose[3:7])
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def box_centre(obj):
    """An object's bounding-box centre in the world frame."""
    return np.asarray(obj.pose[:3]) + rotation(obj.pose) @ ((np.asarray(obj.box_min) + np.asarray(obj.box_max)) / 2)


def lies_on(obj, point, margin_m):
    """The point (world frame) inside the object's box grown by margin_m, and ABOVE_M upwards."""
    local = rotation(obj.pose).T @ (np.asarray(point[:3], np.float64) - np.asarray(obj.pose[:3]))
    low = np.asarray(obj.box_min) - margin_m
    high = np.asarray(obj.box_max) + margin_m + np.array([0, 0, ABOVE_M])
    return bool(np.all(local >= low) and np.all(local <= high))


def object_at(found, point, margin_m):
    """The SceneObject the point lies on (see the module's text), or None."""
    on = [o for o in found if lies_on(o, point, margin_m)]
    if not on:
        return None
    rank = {"target": 0, "distractor": 0}
    return min(on, key=lambda o: (rank.get(o.role, 1), np.linalg.norm(box_centre(o)[:2] - np.asarray(point[:2]))))


def task_objects(obs):
    """The observation's targets and distractors (SceneObjects), the first target first, then
    the distractors, then the other targets; None for a stream without objects.*."""
    found = scene_objects(obs)
    if found is None:
        return None
    targets = [o for o in found if o.role == "target"]
    return targets[:1] + [o for o in found if o.role == "distractor"] + targets[1:]


def objects(obs):
    """Object centres of an observation: its task objects' (task_objects) where it carries them,
    else groups of points above the table."""
    found = task_objects(obs)
    if found is not None:
        return [box_centre(o) for o in found]
    points = np.asarray(obs.fields["front.points"]).reshape(-1, 3)
    points = points[np.isfinite(points).all(1)]
    keep = ((points[:, 2] > TABLE_Z + 0.003) & (points[:, 2] < TABLE_Z + 0.1) &
            (points[:, 0] > REGION[0][0]) & (points[:, 0] < REGION[0][1]) &
            (np.abs(points[:, 1]) < REGION[1][1]))
    groups = []  # [sum, count]
    for p in points[keep]:
        for g in groups:
            if np.linalg.norm(g[0] / g[1] - p) < 0.05:
                g[0] += p
                g[1] += 1
                break
        else:
            groups.append([p.astype(np.float64).copy(), 1])
    return [g[0] / g[1] for g in groups if g[1] >= 10]


def centres(path):
    records = [r for r in read_records(path) if r.type == "obs"]
    found = task_objects(records[0])
    if found is not None:  # the target, then its lookalikes
        for o in [found[0]] + [o for o in found if o.role == "distractor"]:
            c = box_centre(o)
            print(f"{c[0]:.4f},{c[1]:.4f},{c[2]:.4f}")
        return
    found = objects(records[0])
    closed = [r for r in records if not int(np.asarray(r.fields["gripper_open"]).reshape(-1)[0])]
    over = np.asarray((closed or records[-1:])[0].fields["gripper_pose"])[:2]
    found.sort(key=lambda c: np.linalg.norm(c[:2] - over))  # the target first
    for c in found:
        print(f"{c[0]:.4f},{c[1]:.4f},{c[2]:.4f}")


def places(path):
    records = [r for r in read_records(path) if r.type == "obs"]
    opened = [int(np.asarray(r.fields["gripper_open"]).reshape(-1)[0]) for r in records]
    release = next(i for i in range(1, len(records)) if opened[i] and not opened[i - 1])
    target = np.asarray(records[release].fields["gripper_pose"])[:3]
    for shift in ((0, 0), (0.04, 0), (0.04, 0.04)):
        c = target + np.array([shift[0], shift[1], 0.0])
        print(f"{c[0]:.4f},{c[1]:.4f},{c[2]:.4f}")


def compare(path):
    voxels = next(r for r in read_records(path) if r.type == "voxels")
    coarse, coarse_bounds = np.asarray(voxels.fields["depth0.grid"]), np.asarray(voxels.fields["depth0.bounds"])
    fine, fine_bounds = np.asarray(voxels.fields["depth1.grid"]), np.asarray(voxels.fields["depth1.bounds"])
    n = coarse.shape[0]
    names = ["target"] + [f"distractor {i}" for i in range(1, fine.shape[0])]
    print("depth 0 (%.2f cm voxels): each object's voxel, channels mean x y z | r g b | index x y z | occupied"
          % (100 * coarse_bounds[3] / n))
    for k, name in enumerate(names):
        centre = fine_bounds[k][:3] + fine_bounds[k][3] / 2
        index = np.floor((centre - coarse_bounds[:3]) / coarse_bounds[3] * n).astype(int)
        c = coarse[tuple(index)]
        print(f"  {name:13s} voxel {tuple(index)}: " + " ".join(f"{v:+.3f}" for v in c))
    print("depth 1 (%.2f cm voxels): top view of each object's grid (# occupied in some layer above the table)"
          % (100 * fine_bounds[0][3] / n))
    views = []
    for k in range(fine.shape[0]):
        occupied = fine[k, ..., 9] > 0
        z0 = int(np.floor((TABLE_Z + 0.003 - fine_bounds[k][2]) / fine_bounds[k][3] * n)) + 1
        views.append(occupied[4:12, 4:12, max(z0, 0):].any(axis=2))
    for row in range(8):
        print("  " + "   ".join("".join("#" if v[row, col] else "." for col in range(8)) for v in views))
    print("  " + "   ".join(f"{name[:8]:8s}" for name in names))
    for k, name in enumerate(names):
        # Occupied voxels above the table in the grid's middle 4 x 4 columns (7.5 cm square: the
        # object's, which the grid is centred on; neighbours are 10 cm away).
        above = np.zeros(fine.shape[1:4], bool)
        z0 = max(int(np.floor((TABLE_Z + 0.003 - fine_bounds[k][2]) / fine_bounds[k][3] * n)) + 1, 0)
        above[6:10, 6:10, z0:] = fine[k, 6:10, 6:10, z0:, 9] > 0
        means = fine[k][above][:, :3]
        extent = 100 * (means.max(0) - means.min(0)) if len(means) else np.zeros(3)
        layers = np.bincount(np.nonzero(above)[2])
        cells = ", ".join(f"{v:d}" for v in layers[layers > 0])
        print(f"  {name:13s} {int(above.sum()):2d} occupied voxels above the table (per layer: {cells}); "
              f"their points' mean positions span {extent[0]:.1f} x {extent[1]:.1f} x {extent[2]:.1f} cm")
    for k, name in enumerate(names):
        # What the grid's centre column shows from above: its highest occupied voxel.
        column = fine[k, n // 2, n // 2]
        occupied = np.nonzero(column[:, 9] > 0)[0]
        if len(occupied):
            top = column[occupied[-1]]
            print(f"  {name:13s} centre column's top voxel: mean z {top[2]:.3f} m, r g b "
                  + " ".join(f"{v:+.3f}" for v in top[3:6]))
    for k in range(1, len(views)):
        print(f"  target vs {names[k]}: {np.sum(views[0] != views[k])} of 64 top-view cells differ")


if __name__ == "__main__":
    {"centres": centres, "places": places, "compare": compare}[sys.argv[1]](sys.argv[2])
