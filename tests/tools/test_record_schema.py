#!/usr/bin/env python3
"""The record schema has one content in three places, and the programs write it:
(a) the tables of section 12 of formats/record-stream.md and the registry in lib/stream
(`stream-dump --schema`) list the same record types and, per type, the same fields with the same
dtype, shape and optionality; (b) records the programs write (stream-pack, sim-step, demo-record,
voxelize, keyframe, qattn-train, qte-select, plan-path), read with the Python reader
(lib/python/qte_stream.py), hold every required field of their type with the schema's dtype and a
shape that fits its rule (letters such as H, W, N match any size, numbers must match; a letter
used twice in one shape matches one size). Run with a python3 that has NumPy (ctest uses
/usr/bin/python3)."""
import os
import re
import shutil
import subprocess
import sys
import tempfile

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOOLS = os.environ.get("QTE_TOOLS") or os.path.join(SOURCE, "build", "tools")
DOC = os.path.join(SOURCE, "formats", "record-stream.md")
sys.path.insert(0, os.path.join(SOURCE, "lib", "python"))
import qte_stream  # noqa: E402

failures, notes = [], []
# Types no program writes yet (section 12 does not mark them final): checked in (a) only.
NOT_WRITTEN = set()
# Fields that section 12 introduces as a group present only in some records of their type: they
# appear whole or not at all, and at least one record here has them.
GROUPS = {
    ("obs", "objects."): "with sim-step --objects or demo-record --objects",
    ("checkpoint", "hierarchy."): "in the online networks' record",
}
# Required fields that section 12 says are absent when another field is present.
ABSENT_WITH = {("trajectory", "failure"): {"time_s", "joint_positions"}}


def fail(message):
    failures.append(message)


def tool(name, *args, stdin=None):
    r = subprocess.run([os.path.join(TOOLS, name), *args], input=stdin, capture_output=True)
    if r.returncode != 0:
        sys.exit(f"FAIL: {name} {' '.join(args)} exited {r.returncode}: {r.stderr.decode()}")
    return r.stdout


# --- the specification: section 12's "### `type`" sections and their tables ---------------------
def parse_doc():
    """{type: {field: (dtype, shape, optional)}} in the document's order. A row naming several
    fields gives each its own entry: `a`, `b` with "int32, int64" pairs the dtypes (and
    "[3, 3], [4, 4]" the shapes) in order, else all share them; a name starting with '.' replaces
    the last part of the name before it (`x.exp_avg`, `.exp_avg_sq`). A row with neither dtype
    nor shape whose meaning is "as in `T`" takes type T's."""
    text = open(DOC, encoding="utf-8").read()
    m = re.search(r"^## 12\..*?(?=^## 13\.)", text, re.S | re.M)
    if not m:
        sys.exit(f"FAIL: {DOC}: no section 12 followed by a section 13")
    types = {}
    for section in re.finditer(r"^### `([a-z0-9_]+)`.*?(?=^### |\Z)", m.group(0), re.S | re.M):
        fields = types.setdefault(section.group(1), {})
        for row in re.findall(r"^\| `.*\|$", section.group(0), re.M):
            cells = [c.strip() for c in row.strip("|").split("|")]
            if len(cells) != 4:
                sys.exit(f"FAIL: {DOC}, type '{section.group(1)}': a row without 4 cells: {row}")
            names, dtype, shape, meaning = cells
            full = []
            for name in re.findall(r"`([^`]+)`", names):
                full.append(full[-1].rsplit(".", 1)[0] + name if name.startswith(".") else name)
            dtypes = [d.strip() for d in dtype.split(",")]
            shapes = re.findall(r"\[[^\]]*\]", shape)
            optional = meaning.startswith("optional")
            for i, name in enumerate(full):
                d = dtypes[i] if len(dtypes) == len(full) else dtype
                s = shapes[i] if len(shapes) == len(full) > 1 else shape
                like = re.fullmatch(r"as in `([a-z0-9_]+)`", meaning)
                if not dtype and not shape and like:
                    d, s, _ = types.get(like.group(1), {}).get(name, ("?", "?", None))
                if name in fields:
                    fail(f"{DOC}, type '{section.group(1)}': field '{name}' listed twice")
                fields[name] = (d, s, optional)
    return types


def parse_schema():
    """`stream-dump --schema`: a line TYPE<tab>..., then <tab>NAME<tab>DTYPE<tab>SHAPE<tab>optional|required<tab>MEANING."""
    types, current = {}, None
    for line in tool("stream-dump", "--schema").decode("utf-8").splitlines():
        cells = line.split("\t")
        if not line.startswith("\t"):
            current = types.setdefault(cells[0], {})
            continue
        if current is None or len(cells) != 6 or cells[4] not in ("optional", "required"):
            sys.exit(f"FAIL: stream-dump --schema: a line not in the documented form: {line!r}")
        if cells[1] in current:
            fail(f"stream-dump --schema, type '{list(types)[-1]}': field '{cells[1]}' listed twice")
        current[cells[1]] = (cells[2], cells[3], cells[4] == "optional")
    return types


doc, schema = parse_doc(), parse_schema()

# --- (a) the specification and the registry --------------------------------------------------
if list(doc) != list(schema):
    fail(f"record types: formats/record-stream.md lists {list(doc)}, stream-dump --schema {list(schema)}")
for rtype in doc.keys() & schema.keys():
    for name in doc[rtype].keys() | schema[rtype].keys():
        if name not in schema[rtype]:
            fail(f"type '{rtype}': field '{name}' is in formats/record-stream.md, not in the registry (stream-dump --schema)")
        elif name not in doc[rtype]:
            fail(f"type '{rtype}': field '{name}' is in the registry (stream-dump --schema), not in formats/record-stream.md")
        else:
            for what, a, b in zip(("dtype", "shape", "optional"), doc[rtype][name], schema[rtype][name]):
                if a != b:
                    fail(f"type '{rtype}', field '{name}': {what} {a!r} in formats/record-stream.md, {b!r} in the registry")
    if not failures and list(doc[rtype]) != list(schema[rtype]):
        fail(f"type '{rtype}': the fields are in another order in formats/record-stream.md than in the registry")


# --- (b) what the programs write, read by the Python reader ------------------------------------
def pattern(name):
    """A schema name as a regular expression: <camera> one name part, <d> a number, other <...> anything."""
    parts = re.split(r"(<[a-z]+>)", name)
    return "".join({"<camera>": r"[A-Za-z0-9_-]+", "<d>": r"[0-9]+"}.get(p, ".+") if p.startswith("<")
                   else re.escape(p) for p in parts)


def fits(shape, rule):
    """Whether a shape (a tuple) fits a rule: "[]", "[7]", "[H, W, 3]", "[depths − 1]", "its shape"."""
    if not rule.startswith("["):
        return True  # "its shape": whatever the parameter's is
    dims = [d.strip() for d in rule[1:-1].split(",")] if rule != "[]" else []
    if len(dims) != len(shape):
        return False
    bound = {}
    for dim, size in zip(dims, shape):
        if dim.isdigit():
            if int(dim) != size:
                return False
        elif bound.setdefault(dim, size) != size:
            return False
    return True


def check(rtype, record, where):
    fields = schema[rtype]
    exact = {n for n in fields if "<" not in n}
    templates = [(n, re.compile(pattern(n))) for n in fields if "<" in n]
    matched = {}  # schema name -> names in the record
    for name, value in record.fields.items():
        entry = name if name in exact else next((n for n, p in templates if p.fullmatch(name)), None)
        if entry is None:
            notes.append(f"{where}: field '{name}' is not in the schema of '{rtype}'")
            continue
        matched.setdefault(entry, []).append(name)
        present.add((rtype, entry))
        dtype, rule, _ = fields[entry]
        if dtype == "str":
            if not isinstance(value, str):
                fail(f"{where}, field '{name}' ({entry}): {value.dtype.name} {list(value.shape)}, the schema says str")
            continue
        if isinstance(value, str) or value.dtype.name != dtype or not fits(value.shape, rule):
            got = "str" if isinstance(value, str) else f"{value.dtype.name} {list(value.shape)}"
            fail(f"{where}, field '{name}' ({entry}): {got}, the schema says {dtype} {rule}")
    groups = {prefix for (t, prefix) in GROUPS if t == rtype and any(n.startswith(prefix) for n in matched)}
    for prefix in groups:
        seen_groups.add((rtype, prefix))
    excused = set().union(*[names for (t, field), names in ABSENT_WITH.items() if t == rtype and field in matched])
    for entry, (_, _, optional) in fields.items():
        if optional or entry in matched or entry in excused:
            continue
        group = next((p for (t, p) in GROUPS if t == rtype and entry.startswith(p)), None)
        if group and group not in groups:
            continue
        fail(f"{where}: required field '{entry}' of '{rtype}' is missing")
    # Every camera has every per-camera field.
    cameras = {n.split(".", 1)[0] for e, names in matched.items() if e.startswith("<camera>.") for n in names}
    for entry, (_, _, optional) in fields.items():
        if entry.startswith("<camera>.") and not optional:
            for camera in sorted(cameras - {n.split(".", 1)[0] for n in matched.get(entry, [])}):
                fail(f"{where}: camera '{camera}' has no '{camera}.{entry.split('.', 1)[1]}' ({entry})")


tmp = tempfile.mkdtemp(prefix="qte_schema_")
try:
    def path(name):
        return os.path.join(tmp, name)

    def write(name, data):
        with open(path(name), "wb") as f:
            f.write(data)
        return path(name)

    reset = tool("stream-pack", "reset", "task=reach_target", "variation:i32=0", "seed:i64=7")
    files = [
        write("reset.rec", reset),
        write("sim.rec", tool("sim-step", "--image-size", "32x32", "--cameras", "front,wrist", stdin=reset)),
        write("demo.rec", tool("demo-record", "--task", "reach_target", "--episodes", "1", "--seed", "3",
                               "--image-size", "32x32", "--cameras", "front,wrist", "--objects")),
    ]
    obs = tool("stream-cat", "--type", "obs", "--head", "2", path("demo.rec"))
    files.append(write("voxels.rec", tool("voxelize", "--centre", "0.1,0,0.8", stdin=obs)))
    files.append(write("voxels0.rec", tool("voxelize", stdin=obs)))
    files.append(write("replay.rec", tool("keyframe", path("demo.rec"))))
    tool("qattn-train", "--steps", "1", "--batch", "1", "--start-after", "1", "--seed", "1",
         "--checkpoint-dir", path("ckpt"), path("replay.rec"))
    files.append(path("ckpt/latest.rec"))
    files.append(write("acted.rec", tool("qte-select", "--checkpoint", path("ckpt/latest.rec"), stdin=obs)))
    files.append(write("planned.rec", tool("plan-path", "--time-budget", "0.3", path("acted.rec"))))
    # A pose plan-path reaches (40 cm above the table, gripper down), for a trajectory that is not a failure.
    first = tool("stream-cat", "--type", "obs", "--head", "1", path("demo.rec"))
    action = tool("stream-pack", "action", "pose:f64=0.1,0.0,1.15,1,0,0,0", "gripper_open:u8=1")
    reached = write("reached.rec", tool("plan-path", "--seed", "3", stdin=first + action))
    files.append(reached)  # its action is stream-pack's, which may carry only pose and the flags (section 12)

    seen, seen_groups, present = {}, set(), set()
    for file in files:
        try:
            for record in qte_stream.read_records(file):
                where = f"{os.path.basename(file)} record {record.index} ('{record.type}')"
                if file == reached and record.type == "action":
                    continue
                if record.type not in schema:
                    fail(f"{where}: type '{record.type}' is not in the registry")
                    continue
                seen[record.type] = seen.get(record.type, 0) + 1
                check(record.type, record, where)
        except qte_stream.StreamError as e:
            if "zstandard" not in str(e):
                raise
            notes.append(f"{os.path.basename(file)}: not read past a compressed field ({e}): install python3-zstandard")
    for rtype in schema:
        if rtype not in seen and rtype not in NOT_WRITTEN:
            fail(f"no record of type '{rtype}' was written here: add the program that writes it to this test")
    for rtype in seen:
        for entry, (_, _, optional) in schema[rtype].items():
            if not optional and (rtype, entry) not in present:
                fail(f"no '{rtype}' record written here held the required field '{entry}'")
    for group, why in GROUPS.items():
        if group not in seen_groups:
            fail(f"no '{group[0]}' record held the fields {group[1]}* ({why})")
finally:
    shutil.rmtree(tmp, ignore_errors=True)

for note in sorted(set(notes)):
    print("note: " + note)
if failures:
    print("\n".join("FAIL: " + f for f in failures))
    sys.exit(1)
print(f"ok: {len(schema)} record types, {sum(map(len, schema.values()))} fields alike in formats/record-stream.md "
      f"and the registry; {sum(seen.values())} records of {len(seen)} types as the programs write them fit it")
