# Sourced by the command tests: the built programs on PATH, no make of the caller's, a scratch
# directory removed on exit, `fail MESSAGE`, and `py`, the Python with NumPy (CMake's
# QTE_PYTHON, which ctest gives as PYTHON; Debian's python3 when run by hand).
set -uo pipefail
tools=${QTE_TOOLS:?set QTE_TOOLS to the directory of the built programs}
py=${PYTHON:-/usr/bin/python3}
export PATH="$tools:$PATH"
# A test's own `make -C examples ...` is a user's command line, not a sub-make of the `make check`
# that runs ctest: variables given there (make check CMAKE_FLAGS=...) would reach it through
# MAKEFLAGS, and examples/Makefile refuses names that are not its settings.
unset MAKEFLAGS MFLAGS MAKELEVEL
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
