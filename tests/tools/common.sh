# Sourced by the command tests: the built programs on PATH, a scratch directory removed on
# exit, and `fail MESSAGE`.
set -uo pipefail
tools=${QTE_TOOLS:?set QTE_TOOLS to the directory of the built programs}
export PATH="$tools:$PATH"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
