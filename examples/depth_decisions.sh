#!/usr/bin/env bash
# Which depth decided, for a checkpoint's greedy agent on the held-out evaluation scenes
# (depth_decisions.py): per depth, how often the chosen voxel lies on the target, on a lookalike
# or elsewhere, and how often a finer depth overruled depth 0's argmax (tree expansion, K > 1).
# Usage: depth_decisions.sh TASK CHECKPOINT K [IMAGE] [EPISODES] [LABEL] [QTE-SELECT OPTIONS...]
#        (the built programs on PATH). The scenes are learn.sh's evaluation scenes: VARIATION
#        (0), EVAL_SEED (1000000) and PLAN_OPTIONS as there, as failure_reasons.sh replays them. DECISION_STEP=N:
#        only the decisions at step N of each episode (0: the first). AGENT=FILE keeps the
#        episodes' records there. PICTURES=DIR: to look at the decisions, DIR/actions.csv (a row
#        per action: where each depth's voxel lies, whether depth 0 was overruled, what the
#        gripper held; see depth_decisions.py --actions), DIR/attention/<action>.depth<d>.png (qte-select --png:
#        each depth's Q values, the chosen voxel outlined) and DIR/frames/<obs_record>.*.rgb.png
#        (the cameras' view the action was chosen on).
set -euo pipefail
task=$1 checkpoint=$2 k=$3 image=${4:-256x256} episodes=${5:-50} label=${6:-k$3}
shift $(( $# < 6 ? $# : 6 ))
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
agent=${AGENT:-$tmp/agent.rec}
[ -z "${PICTURES:-}" ] || mkdir -p "$PICTURES"
agent_loop "$tmp/loop" \
  sim-step --task "$task" --variation "${VARIATION:-0}" --episodes "$episodes" --seed "${EVAL_SEED:-1000000}" \
    --scenes eval --image-size "$image" --objects \
  qte-select --checkpoint "$checkpoint" --k "$k" "$@" --threads 1 ${PICTURES:+--png "$PICTURES/attention"} \
  plan-path ${PLAN_OPTIONS:-} > "$agent"
if [ -n "${PICTURES:-}" ]; then stream-png --dir "$PICTURES/frames" "$agent"; fi
"$PYTHON" "$here/analysis/depth_decisions.py" --label "$label" ${DECISION_STEP:+--step "$DECISION_STEP"} \
  ${PICTURES:+--actions "$PICTURES/actions.csv"} "$agent"
