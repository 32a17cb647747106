#!/usr/bin/env bash
# Prints what adaptive K costs and expands when acting, against fixed K: qte-select over the
# observations of 5 recorded expert demonstrations (held-out scenes), one thread, with a trained
# checkpoint — per setting the seconds per observation, the mean grids expanded at depth 1,
# and how often the chosen voxel differs from K = 10's. Then the same for the bootstrap target
# (tree_target_timing): the checkpoint's online and target networks on minibatches of those
# demonstrations' transitions, 2 threads.
# Usage: bench_adaptive_k [CHECKPOINT] [TASK] [IMAGE] [TOOLS_DIR]
#        (a checkpoint of TASK, e.g. a learn.sh run's ckpt/latest.rec; without one (or with
#        '-'), networks trained for 150 steps on 3 demonstrations, whose Q volumes say little;
#        defaults reach_prism, 256x256, the build's tools)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
checkpoint=${1:--} task=${2:-reach_prism} image=${3:-256x256} tools=${4:-$here/../../tools}
export PATH=$tools:$PATH
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
if [ "$checkpoint" = - ]; then
  demo-record --task "$task" --episodes 3 --seed 1 --image-size "$image" --output "$tmp/train.rec" 2>/dev/null
  keyframe --output "$tmp/replay.rec" "$tmp/train.rec" 2>/dev/null
  qattn-train --steps 150 --start-after 0 --checkpoint-every 150 --seed 1 --threads 2 --checkpoint-dir "$tmp/ckpt" \
    "$tmp/replay.rec" 2>/dev/null
  checkpoint=$tmp/ckpt/latest.rec
fi

demo-record --task "$task" --episodes 5 --seed 3 --scenes eval --image-size "$image" --output "$tmp/demo.rec" 2>/dev/null
# Every observation of the demonstrations (qte-select acts on each).
stream-cat --type obs "$tmp/demo.rec" > "$tmp/obs.rec"

printf '%-28s %10s %12s %14s\n' setting "s/obs" "branches d1" "voxel != K10"
run() {  # NAME ARGS...
  local name=$1; shift
  local start end
  start=$(date +%s.%N)
  qte-select --checkpoint "$checkpoint" --threads 1 "$@" "$tmp/obs.rec" > "$tmp/$name.rec" 2>/dev/null
  end=$(date +%s.%N)
  stream-dump --json --type action "$tmp/$name.rec" \
    | "${PYTHON:-/usr/bin/python3}" -c '
import json, sys
branches, pose = [], []
for line in sys.stdin:
    fields = {f["name"]: f["values"] for f in json.loads(line)["fields"]}
    branches.append(fields["branches"][0])
    pose.append(tuple(fields["pose"][:3]))
print(sum(branches) / len(branches), len(branches))
print(" ".join("%.4f,%.4f,%.4f" % p for p in pose))' > "$tmp/$name.stats"
  local mean n
  read -r mean n < "$tmp/$name.stats"
  local differ
  differ=$(paste <(sed -n 2p "$tmp/$name.stats" | tr ' ' '\n') <(sed -n 2p "$tmp/k10.stats" 2>/dev/null | tr ' ' '\n') \
    | awk '$1 != $2 { d++ } END { print d + 0 }')
  printf '%-28s %10.3f %12.2f %11s/%s\n' "$name" "$(echo "($end - $start) / $n" | bc -l)" "$mean" "$differ" "$n"
}
run k10 --k 10
run k1 --k 1
for m in 0.005 0.01 0.02 0.05; do run "margin$m" --k auto --k-margin "$m" --k-max 10; done
for p in 0.5 0.9; do run "mass$p" --k auto --k-mass "$p" --k-max 10; done

echo
echo "bootstrap targets (qattn-train --tree-target), learner checkpoint $checkpoint:"
keyframe --output "$tmp/transitions.rec" "$tmp/demo.rec" 2>/dev/null
"$here/tree_target_timing" "$checkpoint" "$tmp/transitions.rec" 10 2
