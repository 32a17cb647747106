#!/usr/bin/env bash
# Prints what a third depth costs the learner: processor seconds per qattn-train step at 2 and
# 3 depths (offsets 0.15 and 0.15,0.05: the published grid and make -C examples small-objects'),
# with the double-DQN target (C2F-ARM, --tree-target 0) and the tree target (QTE, K = 10), side
# by side on the same lift_numbered_block demonstrations, one thread, start-up included. The
# targets are 1-step so that every sample bootstraps (a sample whose chain ends needs no target).
# Usage: bench_learner_depths [DEMOS [IMAGE [STEPS [TOOLS_DIR]]]]   (defaults 5, 256x256, 40,
#        the build's tools)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
demos=${1:-5} image=${2:-256x256} steps=${3:-40} tools=${4:-$here/../../tools}
export PATH=$tools:$PATH
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
demo-record --task lift_numbered_block --episodes "$demos" --seed 1 --image-size "$image" --output "$tmp/demo.rec" 2>/dev/null
keyframe --depths 2 --offset 0.15 --output "$tmp/depths2.rec" "$tmp/demo.rec" 2>/dev/null
keyframe --depths 3 --offset 0.15,0.05 --output "$tmp/depths3.rec" "$tmp/demo.rec" 2>/dev/null
printf '%-8s %-12s %10s\n' depths target "s/step"
for setting in "2 0.15 0" "2 0.15 10" "3 0.15,0.05 0" "3 0.15,0.05 10"; do
  read -r depths offset k <<< "$setting"
  # bash's time: the processor seconds (user, system) of the step's process
  { TIMEFORMAT='%U %S'; time qattn-train --steps "$steps" --start-after 0 --checkpoint-every 100000 \
    --depths "$depths" --offset "$offset" --tree-target "$k" --n-step 1 --seed 0 --threads 1 \
    --checkpoint-dir "$tmp/ckpt-$depths-$k" "$tmp/depths$depths.rec" 2>/dev/null; } 2> "$tmp/time"
  printf '%-8s %-12s %10.3f\n' "$depths" "$([ "$k" = 0 ] && echo double-DQN || echo "tree K=$k")" \
    "$(awk -v n="$steps" '{print ($1 + $2) / n}' "$tmp/time")"
done
