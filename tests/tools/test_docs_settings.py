#!/usr/bin/env python3
"""The learner's settings table (docs/learner.md, section "Settings") agrees with the program:
every `--option value` of its option column is qattn-train's default as `qattn-train --help`
prints it, and every `--option` named there exists. The defaults live in the code; the table
says which are published and why the others differ, so it must not drift from them."""
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
    for line in text.splitlines():
        m = re.match(r"^  (--[a-z0-9-]+)\b", line)
        if m:
            name = m.group(1)
            options[name] = ""
        elif name and line.startswith("      "):
            options[name] += " " + line.strip()
        elif not line.strip():
            name = None
    return {o: (re.search(r"\(default: ([^)]*)\)", d).group(1) if "(default:" in d else None)
            for o, d in options.items()}


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
if checked < 10:
    failures.append(f"only {checked} '--option value' entries found in the settings table")
print("\n".join(failures) or f"{checked} defaults of docs/learner.md's settings table are qattn-train's")
if failures:
    sys.exit(f"FAIL ({len(failures)})")
