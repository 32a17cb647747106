#!/usr/bin/env bash
# Our `light` training step (bench_nets --light) against the same network in PyTorch
# (torch_light_ref.py, Debian's python3-torch: the libtorch we link), alternated three times so
# that a noisy machine hits both alike; prints the medians and our time over theirs.
# Usage: bench_light_vs_torch [THREADS]   (default 2)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
threads=${1:-2}
source_dir=$(sed -n 's/^CMAKE_HOME_DIRECTORY:INTERNAL=//p' "$here/../../CMakeCache.txt")
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
for _ in 1 2 3; do
  "$here/bench_nets" --light --threads "$threads" | awk '{ print $(NF - 5) >> "'"$tmp"'/ours0"; print $(NF - 1) >> "'"$tmp"'/ours1" }'
  "${PYTHON:-/usr/bin/python3}" "$source_dir/tests/bench/torch_light_ref.py" "$threads" \
    | awk '{ print $(NF - 5) >> "'"$tmp"'/torch0"; print $(NF - 1) >> "'"$tmp"'/torch1" }'
done
median() { sort -g "$tmp/$1" | sed -n 2p; }
awk -v t="$threads" -v o0="$(median ours0)" -v r0="$(median torch0)" -v o1="$(median ours1)" -v r1="$(median torch1)" 'BEGIN {
  printf "light train step b32, %s threads, median of 3 alternated runs: depth 0 ours %.3f s, torch %.3f s (%.2fx); last depth ours %.3f s, torch %.3f s (%.2fx)\n", t, o0, r0, o0 / r0, o1, r1, o1 / r1 }'
