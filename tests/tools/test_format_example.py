#!/usr/bin/env python3
"""The worked example of formats/record-stream.md is what stream-pack writes today: the
```hexdump block (xxd -g1 lines) rebuilds byte for byte the output of
`stream-pack reset task=reach_target variation:i32=0 seed:i64=7`, and stream-dump reads it back."""
import json
import os
import re
import subprocess
import sys

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOOLS = os.environ.get("QTE_TOOLS") or os.path.join(SOURCE, "build", "tools")
DOC = os.path.join(SOURCE, "formats", "record-stream.md")
LINE = re.compile(r"([0-9a-f]{8}): ((?:[0-9a-f]{2} ){0,15}[0-9a-f]{2}) +(.{1,16})")


def fail(message):
    sys.exit(f"FAIL: {message}")


def tool(name, *args, stdin=None):
    r = subprocess.run([os.path.join(TOOLS, name), *args], input=stdin, capture_output=True)
    if r.returncode != 0:
        fail(f"{name} {' '.join(args)} exited {r.returncode}: {r.stderr.decode()}")
    return r.stdout


with open(DOC, encoding="utf-8") as f:
    blocks = re.findall(r"^```hexdump\n(.*?)^```$", f.read(), re.S | re.M)
if len(blocks) != 1:
    fail(f"{DOC}: expected one ```hexdump block, found {len(blocks)}")

data = bytearray()
for number, line in enumerate(blocks[0].splitlines(), 1):
    m = LINE.fullmatch(line)
    if not m:
        fail(f"hexdump line {number} is not in `xxd -g1` form: {line!r}")
    if int(m[1], 16) != len(data):
        fail(f"hexdump line {number} starts at offset {m[1]}, expected {len(data):08x}")
    chunk = bytes.fromhex(m[2])
    ascii_column = "".join(chr(b) if 0x20 <= b < 0x7f else "." for b in chunk)
    if m[3] != ascii_column:
        fail(f"hexdump line {number}: text column {m[3]!r} does not match its bytes")
    data += chunk

written = tool("stream-pack", "reset", "task=reach_target", "variation:i32=0", "seed:i64=7")
if bytes(data) != written:
    at = next((i for i, (a, b) in enumerate(zip(data, written)) if a != b),
              min(len(data), len(written)))
    fail(f"the documented example ({len(data)} bytes) differs from what stream-pack writes now "
         f"({len(written)} bytes), first at byte {at}: regenerate it in {DOC}")

lines = tool("stream-dump", "--json", "-", stdin=bytes(data)).decode().splitlines()
if len(lines) != 1:
    fail(f"stream-dump --json printed {len(lines)} lines, expected 1")
record = json.loads(lines[0])
fields = {f["name"]: f for f in record["fields"]}
checks = [
    (record["type"], "reset"),
    (record["index"], 0),
    (record["offset"], 0),
    (record["bytes"], len(data)),
    (list(fields), ["task", "variation", "seed"]),
    ((fields["task"]["dtype"], fields["task"]["shape"], fields["task"]["value"]),
     ("str", [12], "reach_target")),
    ((fields["variation"]["dtype"], fields["variation"]["shape"], fields["variation"]["values"]),
     ("int32", [], [0])),
    ((fields["seed"]["dtype"], fields["seed"]["shape"], fields["seed"]["values"]),
     ("int64", [], [7])),
]
for got, want in checks:
    if got != want:
        fail(f"stream-dump --json of the example: got {got!r}, expected {want!r}")
print(f"the {len(data)}-byte example of formats/record-stream.md matches stream-pack and "
      "stream-dump")
