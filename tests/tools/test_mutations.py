"""Structured mutations of valid records, fed to every program that reads streams (a property
test): a field removed, its dtype or shape changed, NaN, infinity or an extreme value in it.
Each run must end in one of two ways: exit 0 with a valid stream (or its text output), or exit
1 with one line on stderr naming the record's position; never a signal, a hang (timeout) or a
file left behind.

The inputs are made here by the programs themselves (a 32x32 reach_target demonstration, its
transitions, a learner checkpoint, the agent's actions, the planner's trajectory). Per program
a seeded sample of QTE_MUTATIONS (default 12) of its cases runs; QTE_MUTATIONS=all runs every case
(4,818 runs: an hour or more on 2 cores, most of it in the network programs)."""
import os, random, re, struct, subprocess, sys, tempfile, time, zlib

import numpy as np

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(SOURCE, "lib", "python"))
import qte_stream as read_stream  # noqa: E402

TOOLS = os.environ.get("QTE_TOOLS") or os.path.join(SOURCE, "build", "tools")
LIMIT = os.environ.get("QTE_MUTATIONS", "12")
TIMEOUT_S = 120
tmp = tempfile.mkdtemp(prefix="qte_mutations_")
failures = []
POSITION = re.compile(r"record \d+ at byte \d+")


OUTPUT_LIMIT = 256 << 20  # bytes of standard output kept; a program writing more is stopped


class Unbounded(Exception):
    pass


def tool(name, *args, stdin=None, timeout=TIMEOUT_S):
    """Runs a program with its output held in files (a runaway writer is stopped at OUTPUT_LIMIT)."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        p = subprocess.Popen([os.path.join(TOOLS, name), *args], stdin=subprocess.PIPE if stdin else subprocess.DEVNULL,
                             stdout=out, stderr=err)
        if stdin:
            p.stdin.write(stdin)
            p.stdin.close()
        deadline = time.monotonic() + timeout
        while p.poll() is None:
            if os.fstat(out.fileno()).st_size > OUTPUT_LIMIT:
                p.kill()
                p.wait()
                raise Unbounded()
            if time.monotonic() > deadline:
                p.kill()
                p.wait()
                raise subprocess.TimeoutExpired(name, timeout)
            time.sleep(0.01)
        out.seek(0)
        err.seek(0)
        return subprocess.CompletedProcess(p.args, p.returncode, out.read(), err.read())


def made(name, *args, stdin=None):
    r = tool(name, *args, stdin=stdin)
    assert r.returncode == 0, f"{name} {args}: {r.stderr.decode()}"
    return r.stdout


# -- writing records (the reader is lib/python/qte_stream.py; this is its inverse) ---------------
CODES = {np.dtype(v): k for k, v in read_stream.DTYPES.items() if k != read_stream.STR}


def pad(b):
    return b + b"\0" * (-len(b) % 64)


def encode(rtype, fields):
    payload = b""
    for name, value in fields.items():
        if isinstance(value, str):
            code, shape, data = read_stream.STR, (len(value.encode("utf-8", "surrogateescape")),), \
                value.encode("utf-8", "surrogateescape")
        else:
            value = np.ascontiguousarray(value)
            code, shape, data = CODES[value.dtype.newbyteorder("<")], value.shape, value.astype(value.dtype.newbyteorder("<")).tobytes()
        descriptor = struct.pack("<BBBBHHQ", code, len(shape), 0, 0, len(name), 0, len(data))
        descriptor += struct.pack(f"<{len(shape)}q", *shape) + name.encode()
        payload += pad(descriptor) + pad(data)
    header = read_stream.MAGIC + struct.pack("<HHI16sQII12s", 1, 0, len(fields), rtype.encode(), len(payload),
                                             zlib.crc32(payload), 0, b"")
    return header + struct.pack("<I", zlib.crc32(header)) + payload


def records(data):
    path = os.path.join(tmp, "parse.rec")
    with open(path, "wb") as f:
        f.write(data)
    return [(r.type, dict(r.fields)) for r in read_stream.read_records(path)]


def stream(recs):
    return b"".join(encode(t, f) for t, f in recs)


# -- the mutations -------------------------------------------------------------------------------
def field_mutations(fields):
    """(description, a function making the new fields) for each structured change of each field:
    made only when a case runs (a checkpoint's cases would fill the memory)."""
    for name, value in fields.items():
        for what, new in value_mutations(value):
            def make(name=name, new=new):
                out = dict(fields)
                if new is None:
                    del out[name]
                else:
                    out[name] = new()
                return out
            yield f"{name}: {what}", make


def value_mutations(value):
    """(description, a function making the new value, or None to remove the field)."""
    yield "removed", None
    if isinstance(value, str):
        yield "empty text", lambda: ""
        yield "text replaced by float32[3]", lambda: np.zeros(3, np.float32)
        yield "300 odd characters", lambda: "\xff" * 300
        return
    kind = value.dtype.kind
    yield f"dtype {value.dtype} changed", \
        lambda: value.astype(np.float64 if kind != "f" or value.dtype.itemsize == 4 else np.float32)
    if kind == "f":
        yield "to int32", lambda: value.astype(np.int32) if np.all(np.isfinite(value)) else value.astype(np.float64)
    yield "flattened", lambda: value.reshape(-1)
    yield "one element, 0-d", lambda: value.reshape(-1)[:1].reshape(()) if value.size else np.zeros((), value.dtype)
    yield "empty along its first dimension", lambda: np.zeros((0,) + value.shape[1:], value.dtype)
    yield "one element longer, 1-d", \
        lambda: np.concatenate([value.reshape(-1), value.reshape(-1)[:1]]) if value.size else value.reshape(-1)
    if not value.size:
        return
    if kind == "f":
        specials = ((np.nan, "NaN"), (np.inf, "infinity"), (-np.inf, "minus infinity"),
                    (np.finfo(value.dtype).max, "largest finite"), (-1e30, "-1e30"))
    else:
        info = np.iinfo(value.dtype)
        specials = ((info.max, "largest"), (info.min, "smallest"), (-1 if kind == "i" else info.max // 2, "-1 or half max"))
    for special, what in specials:
        def with_special(special=special):
            new = value.copy()
            new.reshape(-1)[0] = special
            new.reshape(-1)[-1] = special
            return new
        yield f"first and last elements {what}", with_special


def cases(recs, pick):
    """Mutations of the records `pick` chooses (indices), each as (description, bytes)."""
    for i in pick:
        rtype, fields = recs[i]
        for what, make in field_mutations(fields):
            def data(i=i, rtype=rtype, make=make):
                mutated = list(recs)
                mutated[i] = (rtype, make())
                return stream(mutated)
            yield f"record {i} ({rtype}) {what}", data


def first_of(recs, rtype):
    return [next(i for i, (t, _) in enumerate(recs) if t == rtype)]


# -- checking one run ----------------------------------------------------------------------------
def check(program, description, argv, data, output=None, stdout_stream=True, workdir=None):
    path = os.path.join(tmp, "input.rec")
    with open(path, "wb") as f:
        f.write(data)
    args = [a.replace("INPUT", path) for a in argv]
    label = f"{program} [{description}]"
    try:
        r = tool(program, *args)
    except subprocess.TimeoutExpired:
        failures.append(f"{label}: no end within {TIMEOUT_S} s (a hang)")
        return
    except Unbounded:
        failures.append(f"{label}: wrote more than {OUTPUT_LIMIT >> 20} MB (stopped)")
        return
    err = r.stderr.decode(errors="replace").strip("\n")
    if r.returncode < 0 or r.returncode > 1:
        failures.append(f"{label}: exit {r.returncode} ({'signal' if r.returncode < 0 else 'not 0 or 1'}): {err[-300:]!r}")
    elif r.returncode == 1:
        lines = err.split("\n")
        if len(lines) != 1 or not POSITION.search(lines[-1]):
            failures.append(f"{label}: exit 1 but not one positioned line: {err[-400:]!r}")
        if output and os.path.exists(output):
            failures.append(f"{label}: exit 1 left {output} behind")
        for directory in (png_dir, xarm_dir, npy_dir):  # several files: all or none
            if os.path.exists(directory):
                failures.append(f"{label}: exit 1 left {directory} behind: {sorted(os.listdir(directory))[:5]}")
    else:
        if output and os.path.isdir(output):  # a checkpoint directory
            output = os.path.join(output, "latest.rec")
        produced = r.stdout if stdout_stream else (open(output, "rb").read() if output and os.path.exists(output) else b"")
        if stdout_stream or (output and not output.endswith((".mp4", ".csv"))):  # those are not streams
            try:
                records(produced)
            except read_stream.StreamError as e:
                failures.append(f"{label}: exit 0 with an invalid stream: {e}")
    if workdir:
        left = [n for n in os.listdir(workdir) if ".tmp." in n]
        if left:
            failures.append(f"{label}: temporaries left: {left}")
    for name in os.listdir(tmp):  # nothing of ours beside the inputs
        if ".tmp." in name:
            failures.append(f"{label}: temporary {name} left in the output directory")
    for made_here in (out, png_dir, ckpt_out, video, xarm_dir, npy_dir):
        subprocess.run(["rm", "-rf", made_here])


total = 0  # cases there are, sampled or not


def sample(all_cases, salt):
    global total
    all_cases = list(all_cases)
    total += len(all_cases)
    if LIMIT == "all" or len(all_cases) <= int(LIMIT):
        return all_cases
    return random.Random(salt).sample(all_cases, int(LIMIT))


# -- the valid inputs ----------------------------------------------------------------------------
demo = made("demo-record", "--task", "reach_target", "--episodes", "1", "--seed", "1", "--image-size", "32x32")
demo_recs = records(demo)
transitions = made("keyframe", stdin=demo)
transition_recs = records(transitions)
ckpt_dir = os.path.join(tmp, "ckpt")
made("qattn-train", "--steps", "1", "--start-after", "0", "--checkpoint-every", "1", "--seed", "1",
     "--checkpoint-dir", ckpt_dir, "-", stdin=transitions)
checkpoint = os.path.join(ckpt_dir, "latest.rec")
obs_recs = [r for r in demo_recs if r[0] == "obs"]
first_obs = stream(obs_recs[:1])
acted = made("qte-select", "--checkpoint", checkpoint, "--k", "2", "--seed", "1", stdin=first_obs)
acted_recs = records(acted)  # obs, action
planned = made("plan-path", "--seed", "1", stdin=acted)
planned_recs = records(planned)  # obs, action, trajectory
trajectory = [r for r in planned_recs if r[0] == "trajectory"]
assert trajectory, "plan-path planned no trajectory for the fixture"
reset = ("reset", {"task": "reach_target", "variation": np.array(0, np.int32), "seed": np.array(3, np.int64)})
sim_input = [reset] + trajectory

out = os.path.join(tmp, "out.rec")
png_dir = os.path.join(tmp, "png")
ckpt_out = os.path.join(tmp, "ckpt-out")
video = os.path.join(tmp, "episode.mp4")
xarm_dir = os.path.join(tmp, "xarm")
npy_dir = os.path.join(tmp, "npy")
trajectory_index = [i for i, r in enumerate(planned_recs) if r[0] == "trajectory"][0]
runs = [
    # program, argv (INPUT: the mutated file), records to mutate, which of them, output file, stream on stdout?
    ("stream-dump", ["INPUT"], acted_recs, [0, 1], None, False),
    ("stream-dump", ["--summary", "--npy", npy_dir, "--pcd", npy_dir, "INPUT"], obs_recs[:2], [0, 1], None, False),
    ("stream-cat", ["INPUT", "--output", out], acted_recs, [1], out, False),
    ("episode-stats", ["INPUT"], obs_recs[:3], [1], None, False),
    ("stream-png", ["--depth", "--dir", png_dir, "INPUT"], obs_recs[:1], [0], None, False),
    ("stream-png", ["--video", video, "INPUT"], obs_recs[:2], [0, 1], video, False),
    ("voxelize", ["INPUT"], obs_recs[:1], [0], None, True),
    ("voxelize", ["--crop", "-1,-1,0,1,1,2", "--outliers", "8,2", "--downsample", "0.01", "INPUT"], obs_recs[:1], [0], None, True),
    ("keyframe", ["--output", out, "INPUT"], demo_recs, first_of(demo_recs, "obs") + first_of(demo_recs, "episode"), out, False),
    ("plan-path", ["--seed", "1", "INPUT"], acted_recs, [0, 1], None, True),
    ("xarm-export", ["--dir", xarm_dir, "INPUT"], planned_recs, [0, trajectory_index],
     os.path.join(xarm_dir, f"{trajectory_index:06d}.xarm.csv"), False),
    ("qte-select", ["--checkpoint", checkpoint, "--k", "2", "--seed", "1", "INPUT"], acted_recs[:1], [0], None, True),
    ("qattn-train", ["--steps", "2", "--start-after", "0", "--checkpoint-every", "1", "--seed", "1",
                     "--checkpoint-dir", ckpt_out, "INPUT"], transition_recs,
     first_of(transition_recs, "frame") + first_of(transition_recs, "transition"), ckpt_out, False),
    ("sim-step", ["--task", "reach_target", "--episodes", "1", "--image-size", "32x32", "INPUT"], sim_input, [0, 1], None, True),
]

ran = 0
for program, argv, recs, pick, output, stdout_stream in runs:
    for description, data in sample(cases(recs, pick), program):
        check(program, description, argv, data(), output, stdout_stream)
        ran += 1

# The checkpoint qte-select reads, mutated (its first record: the online networks and settings).
ckpt_recs = records(open(checkpoint, "rb").read())
for description, data in sample(cases(ckpt_recs, [0]), "checkpoint"):
    with open(os.path.join(tmp, "bad-checkpoint.rec"), "wb") as f:
        f.write(data())
    check("qte-select", "checkpoint " + description,
          ["--checkpoint", os.path.join(tmp, "bad-checkpoint.rec"), "--k", "2", "INPUT"], first_obs, None, True)
    ran += 1


# Cameras that see nothing, and matrices that are not a camera's: refused with one positioned line
# or passed on (the general rule above); qte-select never chooses an action on such a scene.
def camera_cases(recs, index):
    rtype, fields = recs[index]
    cameras = [n[: -len(".intrinsics")] for n in fields if n.endswith(".intrinsics")]

    def changed(what, edit):
        new = {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in fields.items()}
        for camera in cameras:
            edit(new[camera + ".intrinsics"], new[camera + ".extrinsics"])
            if what.startswith("every camera") and camera + ".points" in new:  # the stored points with it
                new[camera + ".points"] = new[camera + ".points"] + np.float32(100.0)
        out = list(recs)
        out[index] = (rtype, new)
        return what, lambda out=out: stream(out)

    def far_away(K, E):
        E[:3, 3] += 100.0

    yield changed("every camera 100 m away (nothing seen)", far_away)
    yield changed("zero focal lengths", lambda K, E: K.__setitem__((slice(0, 2), slice(0, 2)), 0))
    yield changed("negative focal length", lambda K, E: K.__setitem__((0, 0), -K[0, 0]))
    yield changed("singular extrinsic rotation", lambda K, E: E.__setitem__((slice(0, 3), slice(0, 3)), 0))
    yield changed("a reflection, not a rotation", lambda K, E: E.__setitem__((slice(0, 3), 0), -E[:3, 0]))
    yield changed("turned round (looking away)", lambda K, E: E.__setitem__((slice(0, 3), slice(1, 3)), -E[:3, 1:3]))


camera_runs = [
    ("qte-select", ["--checkpoint", checkpoint, "--k", "2", "--seed", "1", "INPUT"], acted_recs[:1], 0, True),
    ("voxelize", ["INPUT"], obs_recs[:1], 0, False),
    ("plan-path", ["--seed", "1", "INPUT"], acted_recs, 0, False),
    ("qattn-train", ["--steps", "1", "--start-after", "0", "--seed", "1", "--checkpoint-dir", ckpt_out, "INPUT"],
     transition_recs, first_of(transition_recs, "frame")[0], False),
]
for program, argv, recs, index, must_refuse_empty in camera_runs:
    for description, data in camera_cases(recs, index):
        before = len(failures)
        check(program, "camera " + description, argv, data(), ckpt_out if program == "qattn-train" else None, True)
        ran += 1
        if must_refuse_empty and "nothing seen" in description and len(failures) == before:
            r = tool(program, *[a.replace("INPUT", os.path.join(tmp, "input.rec")) for a in argv])
            if r.returncode != 1:
                failures.append(f"{program} [camera {description}]: exit {r.returncode}: an action chosen on an empty scene")

# Appends onto foreign bytes, a torn last record, damage, or the input itself: exit 0 with the old
# bytes kept as the start of a readable stream, or exit 1 with one positioned line and the file as
# it was.
whole = stream(obs_recs[:2])
appended_to = {
    "foreign bytes": b"this is not a record stream, only some text. " * 4,
    "a torn last record": whole[: len(whole) - 37],
    "a damaged first header": whole[:3] + bytes([whole[3] ^ 0xFF]) + whole[4:],
    "a whole stream": whole,
    "an empty file": b"",
}
target = os.path.join(tmp, "appended.rec")
appenders = [
    ("stream-cat", ["INPUT", "--append", "--output", target]),
    ("stream-pack", ["obs", "a:i32=1", "--append", "--output", target]),
    ("keyframe", ["--append", "--output", target, "INPUT"]),
]
for program, argv in appenders:
    for what, old in list(appended_to.items()) + ([("its own input", None)] if "INPUT" in argv else []):
        with open(os.path.join(tmp, "input.rec"), "wb") as f:
            f.write(demo if program == "keyframe" else whole)
        same = old is None
        path = os.path.join(tmp, "input.rec") if same else target
        if not same:
            with open(target, "wb") as f:
                f.write(old)
        before = open(path, "rb").read()
        args = [a.replace("INPUT", os.path.join(tmp, "input.rec")).replace(target, path) for a in argv]
        label = f"{program} --append onto {what}"
        try:
            r = tool(program, *args, timeout=60)
        except (subprocess.TimeoutExpired, Unbounded):
            failures.append(f"{label}: no end, or unbounded output")
            continue
        after = open(path, "rb").read()
        err = r.stderr.decode(errors="replace").strip("\n")
        if r.returncode == 0 and not same:
            try:
                records(after)
                if not after.startswith(before) or len(after) == len(before):
                    failures.append(f"{label}: exit 0 but the old bytes are not kept, or nothing was added")
            except read_stream.StreamError as e:
                failures.append(f"{label}: exit 0 leaving an unreadable file: {e}")
        elif r.returncode == 1:
            if len(err.split("\n")) != 1 or path not in err:
                failures.append(f"{label}: exit 1 but not one line naming {path}: {err[-300:]!r}")
            if after != before:
                failures.append(f"{label}: refused, but the file was changed")
        else:
            failures.append(f"{label}: exit {r.returncode}: {err[-300:]!r}")
        ran += 1

print("\n".join(failures[:60]))
print(f"{ran} mutated inputs of {total} cases (QTE_MUTATIONS={LIMIT} per program), {len(failures)} failures")
sys.exit(1 if failures else 0)
