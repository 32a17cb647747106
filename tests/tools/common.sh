# Sourced by the command tests: the built programs on PATH, a scratch directory removed on
# exit, `fail MESSAGE`, and `py`, the Python with NumPy (CMake's QTE_PYTHON, which ctest gives
# as PYTHON; Debian's python3 when run by hand).
set -uo pipefail
tools=${QTE_TOOLS:?set QTE_TOOLS to the directory of the built programs}
py=${PYTHON:-/usr/bin/python3}
export PATH="$tools:$PATH"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
