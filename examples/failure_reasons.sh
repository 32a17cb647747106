#!/usr/bin/env bash
# Where a checkpoint's greedy agent goes on the held-out evaluation scenes, against the expert
# on the same scenes (failure_reasons.py): successes, distractors, the target missed, elsewhere.
# Usage: failure_reasons.sh TASK CHECKPOINT K [IMAGE] [EPISODES] [LABEL]   (the built programs
#        on PATH; the scenes are learn.sh's evaluation scenes: --seed 1000000 --scenes eval)
set -euo pipefail
task=$1 checkpoint=$2 k=$3 image=${4:-256x256} episodes=${5:-50} label=${6:-k$3}
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
scenes=(--task "$task" --episodes "$episodes" --seed 1000000 --scenes eval --image-size "$image")
demo-record "${scenes[@]}" --compress --output "$tmp/experts.rec" 2>/dev/null
mkfifo "$tmp/loop"
sim-step "${scenes[@]}" < "$tmp/loop" | qte-select --checkpoint "$checkpoint" --k "$k" --threads 1 \
  | plan-path | tee "$tmp/loop" > "$tmp/agent.rec"
/usr/bin/python3 "$here/failure_reasons.py" --label "$label" ${FAILURE_EPISODES:+--episodes} "$tmp/experts.rec" "$tmp/agent.rec"
