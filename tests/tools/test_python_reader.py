#!/usr/bin/env python3
"""The installed qte_stream module (lib/python/qte_stream.py), stream-dump --json and stream-dump --npy
(per record, and stacked per record type and field as np.stack makes them) all give back, bit for bit,
what stream-pack wrote: every dtype (extremes, NaN, infinities, -0), 0-d scalars, empty arrays,
non-ASCII text and a zstd-compressed field. Damage makes the Python reader raise StreamError.
Run with a python3 that has NumPy (ctest uses /usr/bin/python3)."""
import importlib
import importlib.util
import io
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOOLS = os.environ.get("QTE_TOOLS") or os.path.join(SOURCE, "build", "tools")
tmp = tempfile.mkdtemp(prefix="qte_pyreader_")
failures = []

# The module as `make install` installs it (cmake --install, component python, into a scratch
# prefix): it lands in the dist-packages Debian's python3 searches under /usr/local.
BUILD = os.path.dirname(os.path.abspath(TOOLS))
prefix = os.path.join(tmp, "prefix")
r = subprocess.run(["cmake", "--install", BUILD, "--component", "python", "--prefix", prefix], capture_output=True, text=True)
if r.returncode != 0:
    sys.exit(f"FAIL: cmake --install --component python: {r.stderr}")
installed = [os.path.join(d, f) for d, _, files in os.walk(prefix) for f in files if f == "qte_stream.py"]
if len(installed) != 1:
    sys.exit(f"FAIL: the install put {len(installed)} qte_stream.py under {prefix}")
# Under the default prefix /usr/local that is on this python3's search path.
where = os.path.join("/usr/local", os.path.relpath(os.path.dirname(installed[0]), prefix))
if where not in sys.path:
    sys.exit(f"FAIL: make install would put qte_stream in {where}, which {sys.executable} does not search")
sys.path.insert(0, os.path.dirname(installed[0]))
import qte_stream as read_stream  # noqa: E402


def tool(name, *args, stdin=None):
    r = subprocess.run([os.path.join(TOOLS, name), *args], input=stdin, capture_output=True)
    if r.returncode != 0:
        sys.exit(f"FAIL: {name} {' '.join(args)} exited {r.returncode}: {r.stderr.decode()}")
    return r.stdout


def text(values):  # how stream-pack takes values: repr() round-trips float64 exactly
    return ",".join("nan" if v != v else repr(float(v)) if isinstance(v, np.floating)
                    else str(int(v)) for v in values.reshape(-1))


# --- what we write: (record type, {field name: expected value}) -------------------------------
records, specs = [], []
for name in "uint8 int8 uint16 int16 uint32 int32 uint64 int64 float32 float64".split():
    dt = np.dtype(name)
    if dt.kind == "f":
        fi = np.finfo(dt)
        special = [fi.max, -fi.max, fi.tiny, fi.eps, -0.0, np.nan, np.inf, -np.inf, 1 / 3]
        if dt == np.float32:
            special.append(fi.smallest_subnormal)  # float64 ones: from a .npy, below, as
            # stream-pack rejects them (std::stod reports a range error for subnormals)
        matrix = np.array(special + [np.pi] * (12 - len(special)), dt).reshape(3, 4)
        scalar = dt.type(-2.5)
    else:
        ii = np.iinfo(dt)
        matrix = np.array([ii.min, ii.max, 0, 1, ii.max - 1, ii.min + 1], dt).reshape(2, 1, 3)
        scalar = dt.type(ii.max)
    fields = {"matrix": matrix, "scalar": np.array(scalar, dt), "empty": np.zeros(0, dt),
              "deep": np.arange(4).astype(dt).reshape(1, 1, 1, 2, 1, 1, 2, 1)}
    args = [f"{k}:{name}" + (f"[{','.join(map(str, v.shape))}]" if v.ndim else "") + "="
            + text(v) for k, v in fields.items()]  # a 0-d field is written without a shape
    records.append((f"dt_{name}", fields))
    specs.append([f"dt_{name}"] + args)

subnormals = np.array([5e-324, -5e-324, 2.2250738585072009e-308], np.float64)
np.save(os.path.join(tmp, "sub.npy"), subnormals)
words = "héllo wörld, ∂x/∂t → 日本語 ✓"
records.append(("text", {"word": words, "empty": "", "f64sub": subnormals}))
specs.append(["text", f"word={words}", "empty=", "f64sub=@" + os.path.join(tmp, "sub.npy")])

depth = (np.arange(256 * 256, dtype=np.uint16) // 7 % 1000).reshape(256, 256)
np.save(os.path.join(tmp, "depth.npy"), depth)
compressed = ("obs", {"front.depth": depth, "step": np.array(3, np.int32)})
records.append(compressed)
specs.append(["obs", "front.depth=@" + os.path.join(tmp, "depth.npy"), "step:i32=3",
              "--compress"])

packed = [tool("stream-pack", *args) for args in specs]  # one record each
offsets = [sum(len(b) for b in packed[:i]) for i in range(len(packed))]
stream = b"".join(packed)
path = os.path.join(tmp, "all.rec")
with open(path, "wb") as f:
    f.write(stream)
if len(stream) >= depth.nbytes:
    failures.append(f"--compress did not compress: stream is {len(stream)} bytes")


def same(where, got, want):
    if isinstance(want, str):
        ok = got == want
    else:
        ok = (isinstance(got, np.ndarray) and got.dtype.str == want.dtype.str
              and got.shape == want.shape and got.tobytes() == want.tobytes())
    if not ok:
        failures.append(f"{where}: got {got!r}, expected {want!r}")


# --- 1. the Python reader ---------------------------------------------------------------------
try:
    have_zstd = bool(importlib.import_module("zstandard"))
except ImportError:
    have_zstd = False
if not have_zstd:
    print("note: Python module zstandard missing, so the compressed record is not read with "
          "qte_stream (install python3-zstandard)")
for source in (path, io.BytesIO(stream)):
    got = []
    try:
        for record in read_stream.read_records(source):
            got.append(record)
    except read_stream.StreamError as e:  # without zstandard: at the last (compressed) record
        if have_zstd or len(got) != len(records) - 1 or "zstandard" not in str(e):
            failures.append(f"qte_stream: {e}")
    if len(got) != len(records) - (0 if have_zstd else 1):
        failures.append(f"qte_stream read {len(got)} records of {len(records)}")
    for i, (record, (rtype, fields)) in enumerate(zip(got, records)):
        if (record.type, record.index, record.offset) != (rtype, i, offsets[i]):
            failures.append(f"record {i}: {record.type} #{record.index} @{record.offset}")
        if list(record.fields) != list(fields):
            failures.append(f"record {i}: fields {list(record.fields)}, expected {list(fields)}")
        for name, want in fields.items():
            same(f"qte_stream record {i} field {name}", record.fields.get(name), want)

# --- 2. stream-dump --json --all-values -------------------------------------------------------
SPECIAL = {"nan": np.nan, "inf": np.inf, "-inf": -np.inf}
lines = tool("stream-dump", "--json", "--all-values", path).decode("utf-8").splitlines()
if len(lines) != len(records):
    failures.append(f"stream-dump --json printed {len(lines)} lines for {len(records)} records")
for i, (line, (rtype, fields)) in enumerate(zip(lines, records)):
    obj = json.loads(line, parse_int=lambda s: -0.0 if s == "-0" else int(s))  # keep -0's sign
    if (obj["type"], obj["index"], obj["offset"]) != (rtype, i, offsets[i]):
        failures.append(f"json record {i}: {line[:80]}")
    if [f["name"] for f in obj["fields"]] != list(fields):
        failures.append(f"json record {i}: field names {[f['name'] for f in obj['fields']]}")
    for f in obj["fields"]:
        want = fields.get(f["name"])
        if f["dtype"] == "str":
            same(f"json record {i} field {f['name']}", f["value"], want)
            continue
        if not f["complete"]:
            failures.append(f"json record {i} field {f['name']}: values not complete")
        values = [SPECIAL[v] if isinstance(v, str) else v for v in f["values"]]
        try:  # JSON integers are exact; floats have enough digits to round-trip
            got = np.array(values, dtype=f["dtype"]).reshape(f["shape"])
        except (OverflowError, ValueError, TypeError) as e:
            got = f"unconvertible values ({e}): {f['values'][:8]}"
        same(f"json record {i} field {f['name']}", got, want)

# --- 3. stream-dump --npy --per-record: one file per record and field ------------------------
npy_dir = os.path.join(tmp, "npy")
tool("stream-dump", "--npy", npy_dir, "--per-record", path)
expected = {f"{i:06d}.{rtype}.{name}.npy": want
            for i, (rtype, fields) in enumerate(records) for name, want in fields.items()}
if sorted(os.listdir(npy_dir)) != sorted(expected):
    failures.append(f"--npy --per-record wrote {sorted(os.listdir(npy_dir))}, expected {sorted(expected)}")
for file, want in expected.items():
    if os.path.exists(os.path.join(npy_dir, file)):
        got = np.load(os.path.join(npy_dir, file))
        if isinstance(want, str):  # text is exported as one bytes string (|S<n>)
            got = got.item().decode("utf-8") if got.dtype.kind == "S" and got.ndim == 0 else got
        same(f"--npy --per-record {file}", got, want)


# --- 3b. stream-dump --npy: one stacked array per record type and field -----------------------
def stacked_expectation(stream_path, only_type=None):
    """The files --npy should write for a stream, from the Python reader and np.stack: a field in
    every record of its type with one dtype and shape (text: any length) is one array [N, ...];
    any other field is one file per record."""
    by_type = {}
    for record in read_stream.read_records(stream_path):
        if only_type in (None, record.type):
            by_type.setdefault(record.type, []).append(record)
    files = {}
    for rtype, recs in by_type.items():
        for name in dict.fromkeys(n for r in recs for n in r.fields):
            values = [r.fields.get(name) for r in recs]
            if all(isinstance(v, str) for v in values):
                width = max(1, max(len(v.encode()) for v in values))
                files[f"{rtype}.{name}.npy"] = np.array([v.encode() for v in values], f"S{width}")
            elif all(isinstance(v, np.ndarray) and v.dtype == values[0].dtype
                     and v.shape == values[0].shape for v in values):
                files[f"{rtype}.{name}.npy"] = np.stack(values)
            else:
                for r in recs:
                    if name in r.fields:
                        files[f"{r.index:06d}.{rtype}.{name}.npy"] = r.fields[name]
    return files


def check_stacked(what, stream_path, only_type=None):
    out = os.path.join(tmp, "stacked_" + what.replace(" ", "_"))
    tool("stream-dump", "--summary", "--npy", out, *(["--type", only_type] if only_type else []), stream_path)
    want_files = stacked_expectation(stream_path, only_type)
    if sorted(os.listdir(out)) != sorted(want_files):
        failures.append(f"--npy ({what}) wrote {sorted(os.listdir(out))}, expected {sorted(want_files)}")
    for file, want in want_files.items():
        if os.path.exists(os.path.join(out, file)):
            got = np.load(os.path.join(out, file))
            if isinstance(want, str):
                got = got.item().decode("utf-8") if got.dtype.kind == "S" and got.ndim == 0 else got
            same(f"--npy ({what}) {file}", got, want)
    return want_files


# Four observations and two episode records interleaved: equal fields stack; a field missing
# from the first observation, or whose shape changes, goes per record; text of any length stacks.
rng = np.random.default_rng(3)
mixed = []
for i in range(4):
    rgb = rng.integers(0, 256, (4, 5, 3), dtype=np.uint8)
    np.save(os.path.join(tmp, f"rgb{i}.npy"), rgb)
    ragged = ",".join(["0.5"] * (2 if i < 2 else 3))
    args = ["obs", "front.rgb=@" + os.path.join(tmp, f"rgb{i}.npy"), f"step:i32={i}",
            "task=" + "reach_target"[:i * 4], f"ragged:f32[{2 if i < 2 else 3}]={ragged}"]
    if i > 0:
        args.append(f"late:i16={-i}")
    mixed.append(tool("stream-pack", *args))
    if i % 2:
        mixed.append(tool("stream-pack", "episode", f"success:u8={i % 3}", f"seed:i64={10 ** 12 + i}"))
mixed_path = os.path.join(tmp, "mixed.rec")
with open(mixed_path, "wb") as f:
    f.write(b"".join(mixed))
files = check_stacked("mixed", mixed_path)
for name, shape in [("obs.front.rgb.npy", (4, 4, 5, 3)), ("obs.step.npy", (4,)), ("episode.seed.npy", (2,))]:
    if name not in files or files[name].shape != shape:
        failures.append(f"--npy (mixed): {name} not stacked to {shape}")
if not {"000000.obs.ragged.npy", "000001.obs.late.npy"} <= set(files):
    failures.append("--npy (mixed): ragged and late fields not written per record")
check_stacked("one record per type", path)  # every field of each record: N = 1
# A real episode of observations (zstd-compressed, when the reader can decompress them).
episode = os.path.join(tmp, "episode.rec")
tool("demo-record", "--task", "reach_target", "--episodes", "1", "--image-size", "32x32",
     *(["--compress"] if have_zstd else []), "--output", episode)
files = check_stacked("demo-record", episode, "obs")
if files.get("obs.front.rgb.npy", np.zeros(0)).shape[1:] != (32, 32, 3):
    failures.append("--npy (demo-record): no stacked obs.front.rgb.npy of shape [N, 32, 32, 3]")

# --- 4. damage: StreamError, nothing else -----------------------------------------------------
plain, second = stream[:offsets[-1]], offsets[1]  # all but the compressed record
flipped = bytearray(plain)
flipped[second + 64 + 100] ^= 0x01
for what, data, where in [("truncated payload", plain[:-5], f"record {len(records) - 2} at"),
                          ("truncated header", plain[:second + 30], f"record 1 at byte {second}"),
                          ("flipped payload byte", bytes(flipped), f"record 1 at byte {second}")]:
    damaged = os.path.join(tmp, "damaged.rec")
    with open(damaged, "wb") as f:
        f.write(data)
    try:
        list(read_stream.read_records(damaged))
        failures.append(f"{what}: no error")
    except read_stream.StreamError as e:
        if not str(e).startswith(f"{damaged}: {where}"):
            failures.append(f"{what}: message {e} does not name '{damaged}: {where}'")
    except Exception as e:  # noqa: BLE001 - any other exception is the failure tested for
        failures.append(f"{what}: {type(e).__name__} instead of StreamError: {e}")

# --- 5. the simulator's objects: scene_objects, None for streams without them -----------------
with_objects = tool("sim-step", "--task", "pick_and_lift", "--seed", "2", "--image-size", "16x16", "--objects",
                    stdin=b"")
found = read_stream.scene_objects(next(read_stream.read_records(io.BytesIO(with_objects)))) or []
if [(o.id, o.name, o.role) for o in found] != [(0, "target", "target"), (1, "distractor1", "distractor"),
                                               (2, "distractor2", "distractor"), (3, "success_zone", "other")]:
    failures.append(f"scene_objects: {[(o.id, o.name, o.role) for o in found]}")
elif not (np.allclose(np.concatenate([found[0].box_min, found[0].box_max]), [-0.025] * 3 + [0.025] * 3)
          and found[0].pose.shape == (7,) and abs(found[0].pose[2] - 0.777) < 0.002):  # a 5 cm block on the table
    failures.append(f"scene_objects: the block at {found[0].pose}, box {found[0].box_min} {found[0].box_max}")
old_obs = next(read_stream.read_records(os.path.join(SOURCE, "tests", "data", "pick_and_lift_obs.rec")))
if read_stream.scene_objects(old_obs) is not None:
    failures.append("scene_objects of a stream without objects is not None")

print("\n".join(failures) or f"{len(records)} records read back bit for bit by the installed qte_stream, "
      "stream-dump --json and stream-dump --npy (stacked and per record); damage raises StreamError; "
      "scene_objects decodes the simulator's objects")
if failures:
    sys.exit(f"FAIL ({len(failures)} mismatches; files kept in {tmp})")
shutil.rmtree(tmp)
