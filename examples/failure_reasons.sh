#!/usr/bin/env bash
# Where a checkpoint's greedy agent goes on the held-out evaluation scenes, against the expert
# on the same scenes (failure_reasons.py): successes, distractors, the target missed, elsewhere.
# Usage: failure_reasons.sh TASK CHECKPOINT K [IMAGE] [EPISODES] [LABEL] [SEED] [QTE-SELECT OPTIONS...]
#        (the built programs on PATH). The scenes are learn.sh's evaluation scenes: VARIATION
#        (0) and EVAL_SEED (1000000) as there. FAILURE_EPISODES=1: a line per episode on stderr.
set -euo pipefail
task=$1 checkpoint=$2 k=$3 image=${4:-256x256} episodes=${5:-50} label=${6:-k$3} seed=${7:-}
shift $(( $# < 7 ? $# : 7 ))
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
scenes=(--task "$task" --variation "${VARIATION:-0}" --episodes "$episodes" --seed "${EVAL_SEED:-1000000}" --scenes eval
        --image-size "$image")
demo-record "${scenes[@]}" --compress --output "$tmp/experts.rec" 2>/dev/null
agent_loop "$tmp/loop" \
  sim-step "${scenes[@]}" --objects \
  qte-select --checkpoint "$checkpoint" --k "$k" "$@" --threads 1 \
  plan-path > "$tmp/agent.rec"
"$PYTHON" "$here/failure_reasons.py" --label "$label" --seed "$seed" ${FAILURE_EPISODES:+--episodes} \
  "$tmp/experts.rec" "$tmp/agent.rec"
