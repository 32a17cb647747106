#!/usr/bin/env bash
# The ceiling of learning on a task: the expert's own keyframes on the 50 held-out evaluation
# scenes, discretized as the networks' training targets (the voxel per depth, 5-degree rotation
# bins, the gripper command) and acted through the same planner as the agents (qte-select
# --keyframes), each episode sorted by failure_reasons.py. The discretized expert acting
# open-loop: a reference, not a strict bound (a network acts closed-loop and may retry). A task
# whose agents stay far below it is limited by learning, one whose ceiling is low by the grid,
# the planner or the task.
# Usage: ceiling.sh TASK OUT.csv   (the built programs on PATH; settings from the environment
#        as learn.sh's: IMAGE 128x128, NET_OPTIONS (--depths, --offset), PLAN_OPTIONS, VARIATION,
#        EVAL_SEED; EVAL_EPISODES 50; CEILING_LABEL keyframes; EXPERT_CACHE to keep the
#        expert's recording; CEILING_OPTIONS, qte-select's for the keyframes agent: e.g.
#        "--rotation-offset 0,0,1", every action's yaw one bin off). An existing OUT.csv is kept.
set -euo pipefail
task=$1 out=$2
[ ! -s "$out" ] || exit 0
mkdir -p "$(dirname "$out")"
trap 'rm -f "$out.tmp"' EXIT  # a failed analysis leaves no half-written CSV
bash "$(dirname "$0")/failure_reasons.sh" "$task" keyframes 1 "${IMAGE:-128x128}" "${EVAL_EPISODES:-50}" \
  "${CEILING_LABEL:-keyframes}" "" ${CEILING_OPTIONS:-} > "$out.tmp"
mv "$out.tmp" "$out"
