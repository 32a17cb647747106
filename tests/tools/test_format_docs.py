#!/usr/bin/env python3
"""man/qte-stream.5 (written by hand, a summary) names what formats/record-stream.md (the full
specification) defines: every record type of section 12 has its paragraph in RECORD TYPES, and
every field of the type's tables is named there (<camera> written CAM, <d> as an italic d), and
the man page names no record type the specification lacks."""
import os
import re
import sys

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
spec = open(os.path.join(SOURCE, "formats", "record-stream.md"), encoding="utf-8").read()
man = open(os.path.join(SOURCE, "man", "qte-stream.5"), encoding="utf-8").read()

# The specification: "### `type` — ..." sections, each with tables whose first column names fields.
types = {}
for m in re.finditer(r"^### `([a-z0-9_]+)`.*?(?=^### |^## )", spec, re.S | re.M):
    fields = set()
    for row in re.findall(r"^\| (`[^|]+) \|", m.group(0), re.M):
        for name in re.findall(r"`([^`]+)`", row):
            fields.add(name)
    types[m.group(1)] = fields

# The man page's RECORD TYPES: ".B type" then its paragraph, roff escapes undone.
section = man.split(".SH RECORD TYPES", 1)[1].split("\n.SH ", 1)[0]
paragraphs = {}
for m in re.finditer(r"^\.B (\S+)\n(.*?)(?=^\.TP|\Z)", section, re.S | re.M):
    text = m.group(2).replace("\\fI", "").replace("\\fR", "").replace("\\-", "-").replace("\n", " ")
    paragraphs[m.group(1)] = text


def words(name):
    """How the man page spells a field: <camera> as CAM, <d> as d; a leading '.' continues the
    previous name (`.exp_avg_sq`), <parameter> stays as its word."""
    return name.replace("<camera>", "CAM").replace("<d>", "d").replace("<parameter>", "parameter").replace("<name>", "name")


failures = []
for rtype, fields in types.items():
    if rtype not in paragraphs:
        failures.append(f"man/qte-stream.5 has no paragraph for record type '{rtype}'")
        continue
    for field in sorted(fields):
        if field.startswith("<name>"):  # a placeholder: "one scalar per figure"
            continue
        spelled = words(field).lstrip(".")
        if spelled not in paragraphs[rtype]:
            failures.append(f"man/qte-stream.5, record type '{rtype}': no mention of field '{field}'")
for rtype in paragraphs:
    if rtype not in types:
        failures.append(f"man/qte-stream.5 describes record type '{rtype}', which formats/record-stream.md lacks")

if failures:
    print("\n".join("FAIL: " + f for f in failures))
    sys.exit(1)
print(f"ok: {len(types)} record types, {sum(map(len, types.values()))} fields named in both")
