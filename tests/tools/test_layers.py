#!/usr/bin/env python3
"""lib/ is layered as docs/design.md's table says: every `#include "dir/..."` of a file in
lib/<dir>/ names a directory of a strictly lower layer, and every directory of lib/ with C++ in
it has a layer. A dependency against the grain (the record stream reaching up to the command
line, the voxels to the planner) fails here, naming the file and its include."""
import os
import re
import sys

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
LIB = os.path.join(SOURCE, "lib")
failures = []

text = open(os.path.join(SOURCE, "docs", "design.md")).read()
layer_of = {}
for number, names in re.findall(r"^\s*\| (\d+) \| ((?:`[a-z_]+`(?:, )?)+) \|$", text, re.M):
    for name in re.findall(r"`([a-z_]+)`", names):
        if name in layer_of:
            failures.append(f"docs/design.md: {name} is in layers {layer_of[name]} and {number}")
        layer_of[name] = int(number)
if not layer_of:
    sys.exit("FAIL: no layer table in docs/design.md")

directories = sorted(d for d in os.listdir(LIB) if os.path.isdir(os.path.join(LIB, d))
                     and any(f.endswith((".cpp", ".hpp")) for f in os.listdir(os.path.join(LIB, d))))
for d in directories:
    if d not in layer_of:
        failures.append(f"lib/{d}: not in docs/design.md's layer table")
for name in layer_of:
    if name not in directories:
        failures.append(f"docs/design.md: layer table names {name}, which lib/ does not have")

include = re.compile(r'^\s*#\s*include\s+"([a-z_]+)/[^"]+"', re.M)
checked = 0
for d in directories:
    for f in sorted(os.listdir(os.path.join(LIB, d))):
        if not f.endswith((".cpp", ".hpp")):
            continue
        for target in include.findall(open(os.path.join(LIB, d, f)).read()):
            checked += 1
            if target == d or target not in layer_of or d not in layer_of:
                continue
            if layer_of[target] >= layer_of[d]:
                failures.append(f"lib/{d}/{f} includes {target}/ (layer {layer_of[target]}) from layer {layer_of[d]}")

if failures:
    print("\n".join("FAIL: " + f for f in failures))
    sys.exit(1)
print(f"ok: {checked} includes of {len(directories)} directories of lib/ go down the layers")
