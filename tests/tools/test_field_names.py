#!/usr/bin/env python3
"""Every program names a record field and a record type through lib/stream/field_names.hpp,
never by a string literal: no call of a record's accessors (set, set_scalar, set_string, array,
scalar, string, has, field, find, fail, remove, require_finite) in lib/ or tools/ takes a literal
that is a field name of formats/record-stream.md, no per-camera or per-depth suffix (".rgb",
".index") is written as a literal, and no record type is compared with, built from or listed as
a literal (`type() == "obs"`, `stream::Record r("obs")`, `return {"obs"};`). The check is first tried on sample lines, so that it is known to catch
what it looks for. Command-line options (`args.has("task")`) are not fields and pass."""
import os
import re
import sys

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
HEADER = os.path.join(SOURCE, "lib", "stream", "field_names.hpp")
# Where names are spelt by design: the constants and the registry's patterns.
OWN_HOMES = {os.path.join("lib", "stream", "field_names.hpp"), os.path.join("lib", "stream", "record_types.cpp")}

text = open(HEADER).read()


def listed(macro):
    body = text.split("#define " + macro)[1].split("\n\n")[0]
    return {name for _, name in re.findall(r'X\((\w+), "([^"]+)"\)', body)}


names = listed("QTE_FIELD_NAMES(X)")
suffixes = listed("QTE_CAMERA_FIELD_SUFFIXES(X)") | listed("QTE_DEPTH_FIELD_SUFFIXES(X)")
types = listed("QTE_RECORD_TYPES(X)")
assert len(names) > 40 and len(suffixes) == 12 and len(types) == 10, (len(names), len(suffixes), len(types))

ACCESSOR = re.compile(
    r'\b(\w+)(?:\([^()]*\))?(?:\.|->)'
    r'(?:set|set_raw|set_scalar|set_string|array|scalar|string|has|field|find|fail|remove|require_finite)'
    r'(?:<[^<>]*>)?\(\s*"([^"]*)"')
LITERAL = re.compile(r'"((?:[^"\\]|\\.)*)"')
TYPE_USE = re.compile(r'(?:type\(\)\s*[!=]=\s*|Record\s+\w+\s*[({]\s*|Record\s*[({]\s*|return\s*\{\s*)"([a-z_]+)"')


def problems(line):
    """What is wrong with one line of C++ (comments already removed)."""
    found = []
    for receiver, literal in ACCESSOR.findall(line):
        if receiver != "args" and literal in names:
            found.append(f'field "{literal}" named by a literal')
    for literal in LITERAL.findall(line):
        if literal in suffixes:
            found.append(f'suffix "{literal}" written as a literal')
    for literal in TYPE_USE.findall(line):
        if literal in types:
            found.append(f'record type "{literal}" written as a literal')
    return found


# The check itself, on lines it must catch and lines it must let pass.
for line in ['  obs.set_scalar<uint8_t>("gripper_open", 1);', '  if (record->has("failure")) return;',
             '  t.fail("step", "a step");', '  out.remove(camera + ".depth_mm");',
             '  const auto q = replay.transition(last).scalar<int32_t>("step");',
             '  a.set<int32_t>("depth0" ".index", {3}, x);', '  if (record->type() != "obs") return;',
             '  stream::Record t("transition");', '  stream::Record record{"voxels"};',
             '  std::vector<std::string> reads() const override { return {"obs"}; }']:
    assert problems(line), line
for line in ['  obs.set_scalar<uint8_t>(fields::gripper_open, 1);', '  if (args.has("task")) run();',
             '  save(path + ".png");', '  std::string("success") + rest;',
             '  if (record.type() == record_type::obs) return;', '  run("reset");']:
    assert not problems(line), line


def code_lines(path):
    """The file's lines with // comments removed (a // inside a string literal is kept)."""
    for number, line in enumerate(open(path, encoding="utf-8"), 1):
        out, in_string, i = "", False, 0
        while i < len(line):
            c = line[i]
            if in_string and c == "\\":
                out += line[i:i + 2]
                i += 2
                continue
            if c == '"':
                in_string = not in_string
            elif not in_string and line.startswith("//", i):
                break
            out += c
            i += 1
        yield number, out


failures = []
checked = 0
for top in ("lib", "tools"):
    for directory, _, files in os.walk(os.path.join(SOURCE, top)):
        for name in files:
            if not name.endswith((".cpp", ".hpp")):
                continue
            path = os.path.join(directory, name)
            relative = os.path.relpath(path, SOURCE)
            if relative in OWN_HOMES:
                continue
            checked += 1
            for number, line in code_lines(path):
                failures += [f"{relative}:{number}: {p} (use fields::… or record_type::… from stream/field_names.hpp)"
                             for p in problems(line)]

assert checked > 100, checked
for f in failures:
    print("FAIL:", f)
if failures:
    sys.exit(1)
print(f"ok: {checked} files name record fields and types through stream/field_names.hpp")
