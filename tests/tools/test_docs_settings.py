#!/usr/bin/env python3
"""The learner's settings table (docs/learner.md, section "Settings") agrees with the program:
every `--option value` of its option column is qattn-train's default as `qattn-train --help`
prints it, and every `--option` named there exists; the man page (man/qattn-train.1) gives every
option the default --help gives. The defaults live in the settings structs (lib/learner, lib/replay:
the option groups of learner_options.cpp read them); the table says which are published and why
the others differ, so it must not drift from them."""
import os
import re
import subprocess
import sys

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TOOLS = os.environ.get("QTE_TOOLS") or os.path.join(SOURCE, "build", "tools")


def help_defaults():
    """{option: default or None} from qattn-train --help."""
    text = subprocess.run([os.path.join(TOOLS, "qattn-train"), "--help"], capture_output=True,
                          text=True, check=True).stdout
    options, name = {}, None
    text = text.split("\nOptions:\n", 1)[1].split("\nExamples:\n", 1)[0]
    for line in text.splitlines():
        m = re.match(r"^  (--[a-z0-9-]+)\b", line)
        if m:
            name = m.group(1)
            options[name] = ""
        elif name and line.startswith("      "):
            options[name] += " " + line.strip()
        elif not line.strip():
            name = None
    return {o: (re.search(r"[(;] ?default: ([^)]*)\)", d).group(1) if "default: " in d else None)
            for o, d in options.items()}


def man_defaults():
    """{option: default or None} from man/qattn-train.1 (.B \\-\\-name ... then its help line)."""
    with open(os.path.join(SOURCE, "man", "qattn-train.1"), encoding="utf-8") as f:
        lines = f.read().splitlines()
    options = {}
    for i, line in enumerate(lines):
        m = re.match(r"^\.B (\\-\\-[a-z0-9\\-]+)", line)
        if m and i + 1 < len(lines):
            name = m.group(1).replace("\\-", "-")
            d = re.search(r"[(;] ?default: ([^)]*)\)", lines[i + 1])
            options[name] = d.group(1).replace("\\-", "-") if d else None
    return options


def table_rows():
    with open(os.path.join(SOURCE, "docs", "learner.md"), encoding="utf-8") as f:
        section = f.read().split("\n## Settings\n", 1)[1].split("\n## ", 1)[0]
    rows = [line for line in section.splitlines() if line.startswith("| ") and not line.startswith("|---")]
    header = [c.strip() for c in rows[0].strip("|").split("|")]
    column = next(i for i, c in enumerate(header) if c.startswith("option"))
    return [[c.strip() for c in re.split(r"(?<!\\)\|", row.strip().strip("|"))] for row in rows[1:]], column


defaults = help_defaults()
rows, column = table_rows()
failures, checked = [], 0
for row in rows:
    for code in re.findall(r"`([^`]*)`", row[column]):
        parts = code.split()
        if not parts or not parts[0].startswith("--"):
            continue
        option = parts[0]
        if option not in defaults:
            failures.append(f"'{row[0]}': qattn-train has no option {option}")
        elif len(parts) > 1:
            checked += 1
            if defaults[option] != parts[1]:
                failures.append(f"'{row[0]}': the table says {option} {parts[1]}, "
                                f"qattn-train --help says {defaults[option]}")
man = man_defaults()
for option, default in defaults.items():
    if option in ("--help", "--version", "--help-man"):
        continue
    if man.get(option, "missing") != default:
        failures.append(f"man/qattn-train.1 gives {option} the default {man.get(option, '(no such option)')}, "
                        f"--help {default}")
if checked < 10:
    failures.append(f"only {checked} '--option value' entries found in the settings table")
print("\n".join(failures) or f"{checked} defaults of docs/learner.md's settings table are qattn-train's")
if failures:
    sys.exit(f"FAIL ({len(failures)})")
