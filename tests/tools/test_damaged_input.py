"""Every kind of damage the format document lists, fed to the programs: each must exit 1 with
one line on stderr naming the file, record index and byte offset and what was expected, and
leave no output file (and no temporary file) behind."""
import os, struct, subprocess, sys, tempfile, zlib

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOOLS = os.environ.get("QTE_TOOLS") or os.path.join(SOURCE, "build", "tools")
tmp = tempfile.mkdtemp(prefix="qte_damage_")
failures = []


def tool(name, *args, stdin=None):
    return subprocess.run([os.path.join(TOOLS, name), *args], input=stdin, capture_output=True)


def pack(*fields, compress=False):
    r = tool("stream-pack", *fields, *(["--compress"] if compress else []))
    assert r.returncode == 0, r.stderr
    return r.stdout


first = pack("reset", "task=reach_target", "variation:i32=0", "seed:i64=7")
second = pack("obs", "depth:f32[4,4]=" + ",".join(str(i) for i in range(16)), "step:i32=1")
good = first + second
R1 = len(first)  # byte offset of record 1


def reseal_header(b, at):
    b[at + 60:at + 64] = struct.pack("<I", zlib.crc32(bytes(b[at:at + 60])))


def reseal_payload(b, at):
    n = struct.unpack_from("<Q", b, at + 32)[0]
    b[at + 40:at + 44] = struct.pack("<I", zlib.crc32(bytes(b[at + 64:at + 64 + n])))
    reseal_header(b, at)


def damaged(edit):
    b = bytearray(good)
    edit(b)
    return bytes(b)


def set_at(at, fmt, value, reseal=None):
    def edit(b):
        struct.pack_into(fmt, b, at, value)
        if reseal == "header": reseal_header(b, R1)
        if reseal == "payload": reseal_payload(b, R1)
    return edit


cases = {
    # name: (bytes, expected record, expected byte offset, expected words)
    "truncated header": (good[:R1 + 40], 1, R1, "truncated stream: expected a 64-byte record header"),
    "truncated payload": (good[:-10], 1, R1, "truncated stream"),
    "wrong magic": (damaged(set_at(R1 + 1, "B", ord("X"))), 1, R1, "bad magic"),
    "unsupported version": (damaged(set_at(R1 + 8, "<H", 9, "header")), 1, R1, "unsupported format version 9.0"),
    "header checksum": (damaged(set_at(R1 + 17, "B", ord("x"))), 1, R1, "header checksum mismatch"),
    "payload checksum": (damaged(set_at(len(good) - 64, "B", 0x55)), 1, R1, "payload checksum mismatch"),
    "absurd payload length": (damaged(set_at(R1 + 32, "<Q", 1 << 52, "header")), 1, R1, "absurd payload length"),
    "unknown dtype": (damaged(set_at(R1 + 64, "B", 42, "payload")), 1, R1 + 64, "unknown dtype code 42"),
    "shape vs bytes": (damaged(set_at(R1 + 64 + 16, "<q", 5, "payload")), 1, R1 + 64, "needs 80 bytes, stored 64"),
    "not a stream": (b"hello, I am a text file\n" * 4, 0, 0, "bad magic"),
}

for name, (data, index, offset, words) in cases.items():
    path = os.path.join(tmp, name.replace(" ", "_") + ".rec")
    with open(path, "wb") as f:
        f.write(data)
    out = os.path.join(tmp, "out.rec")
    for argv in (["stream-cat", path, "--output", out], ["stream-dump", path]):
        r = tool(*argv)
        err = r.stderr.decode()
        lines = err.strip("\n").split("\n")
        where = f"{path}: record {index} at byte {offset}"
        if r.returncode != 1:
            failures.append(f"{name}: {argv[0]} exit {r.returncode}, expected 1")
        if len(lines) != 1:
            failures.append(f"{name}: {argv[0]} printed {len(lines)} lines: {err!r}")
        if where not in err or words not in err:
            failures.append(f"{name}: {argv[0]} said {err!r}, expected '{where}' and '{words}'")
    leftovers = [p for p in os.listdir(tmp) if p.startswith("out.rec")]
    if leftovers:
        failures.append(f"{name}: stream-cat left {leftovers} behind")

# A field a program needs that is missing: the same one-line error with position.
r = tool("stream-pack", "reset", "x=@" + os.path.join(tmp, "missing.npy"))
if r.returncode != 1 or b"missing.npy" not in r.stderr:
    failures.append(f"missing input file: exit {r.returncode}, {r.stderr!r}")

# .npy headers whose shape is not an array a record can hold: refused, not wrapped or misread.
def npy(shape_text, data=b""):
    header = ("{'descr': '<f4', 'fortran_order': False, 'shape': " + shape_text + ", }").encode()
    header += b" " * (63 - (10 + len(header)) % 64) + b"\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header + data
for shape_text, data in [("(-1,)", b"\0" * 4), ("(4294967296, 4294967296, 4)", b""), ("(2, x)", b""),
                         ("(99999999999999999999,)", b"")]:
    path = os.path.join(tmp, "bad.npy")
    with open(path, "wb") as f:
        f.write(npy(shape_text, data))
    r = tool("stream-pack", "reset", "x=@" + path)
    if r.returncode != 1 or b"bad.npy" not in r.stderr or r.stdout:
        failures.append(f".npy shape {shape_text}: exit {r.returncode}, {r.stderr!r}, {len(r.stdout)} bytes out")
with open(os.path.join(tmp, "good.npy"), "wb") as f:
    f.write(npy("(2,)", struct.pack("<2f", 1.5, 2.5)))
r = tool("stream-pack", "reset", "x=@" + os.path.join(tmp, "good.npy"))
if r.returncode != 0:
    failures.append(f"a good .npy was refused: {r.stderr!r}")

# Good input still passes, byte for byte.
r = tool("stream-cat", "-", stdin=good)
if r.returncode != 0 or r.stdout != good:
    failures.append(f"good stream did not pass through unchanged: {r.stderr!r}")

print("\n".join(failures) or f"{len(cases)} kinds of damage rejected correctly")
sys.exit(1 if failures else 0)
