#!/usr/bin/env bash
# Where a checkpoint's greedy agent goes on the held-out evaluation scenes and why each episode
# fails, against the expert on the same scenes (failure_reasons.py): successes, distractors,
# the target missed, elsewhere; and a reason per episode (wrong object, grasp missed, dropped,
# the planner's or the simulator's refusal, out of steps), counted per reason.
# Usage: failure_reasons.sh TASK CHECKPOINT K [IMAGE] [EPISODES] [LABEL] [SEED] [QTE-SELECT OPTIONS...]
#        (the built programs on PATH). CHECKPOINT `keyframes`: no networks, the expert's own
#        keyframes on these scenes as keyframe(1) discretizes them for the learner (NET_OPTIONS:
#        its --depths and --offset), acted with qte-select --keyframes: the discretized expert
#        acting open-loop, a reference for what this grid, planner and task allow. The scenes are learn.sh's evaluation scenes: VARIATION
#        (0), EVAL_SEED (1000000) and PLAN_OPTIONS as there; SCENES=demo with EVAL_SEED and EPISODES a run's SEED and
#        DEMOS acts on the scenes of its demonstrations instead (has the agent learned the scenes it was shown?).
#        FAILURE_EPISODES=1: a line per episode on stderr. AGENT_STREAM=FILE keeps the agent's
#        episodes (sim-step --objects | qte-select | plan-path) in FILE, for analysis/first_actions.py.
# The expert's episodes of the scenes are recorded once per task, VARIATION, EVAL_SEED,
# EPISODES, IMAGE and demo-record program (its checksum: a rebuilt expert records again) and
# kept in EXPERT_CACHE, by default expert-cache/ beside the run directory (the checkpoint's
# directory's parent: RUNS/<takeaway>/<task>/expert-cache for learn.sh's runs, shared by
# every method and seed of the task; with CHECKPOINT `keyframes` nothing unless EXPERT_CACHE is
# set); EXPERT_CACHE= (empty) keeps nothing.
set -euo pipefail
task=$1 checkpoint=$2 k=$3 image=${4:-256x256} episodes=${5:-50} label=${6:-k$3} seed=${7:-}
shift $(( $# < 7 ? $# : 7 ))
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
scenes=(--task "$task" --variation "${VARIATION:-0}" --episodes "$episodes" --seed "${EVAL_SEED:-1000000}" --scenes "${SCENES:-eval}"
        --image-size "$image")
if [ "$checkpoint" = keyframes ]; then cache=${EXPERT_CACHE-}; else
  cache=${EXPERT_CACHE-$(dirname "$(dirname "$checkpoint")")/../expert-cache}; fi
if [ -n "$cache" ]; then
  other_scenes=$([ "${SCENES:-eval}" = eval ] || echo "_${SCENES}-scenes")
  build=$(sha256sum "$(command -v demo-record)" | cut -c1-12)
  experts=$cache/${task}${other_scenes}_variation${VARIATION:-0}_seed${EVAL_SEED:-1000000}_episodes${episodes}_${image}_demo-record-$build.rec
else
  experts=$tmp/experts.rec
fi
if [ ! -f "$experts" ]; then  # demo-record writes its --output whole or not at all (renamed into place)
  mkdir -p "$(dirname "$experts")"
  demo-record "${scenes[@]}" --objects --no-points --compress --output "$experts" 2>/dev/null
fi
if [ "$checkpoint" = keyframes ]; then
  # Every scene's demonstration, failed or not (episode n acts with demonstration n), on the
  # grids an acting network uses (no crop augmentation).
  keyframe ${NET_OPTIONS:-} --keep-failed --no-crop-augmentation --output "$tmp/keyframes.rec" "$experts" \
    2> "$tmp/keyframe.err" || { echo "failure_reasons.sh: keyframe: $(tail -1 "$tmp/keyframe.err")" >&2; exit 1; }
  grep -q "^keyframe: $episodes/$episodes episodes converted" "$tmp/keyframe.err" || {
    echo "failure_reasons.sh: $experts: keyframe converted fewer than the $episodes episodes" \
      "(each scene needs its demonstration): $(grep -v '^ ' "$tmp/keyframe.err" | tail -2 | tr '\n' ' ')" >&2; exit 1; }
  agent=(--keyframes "$tmp/keyframes.rec")
else
  agent=(--checkpoint "$checkpoint" --k "$k" --threads 1)
fi
agent_loop "$tmp/loop" \
  sim-step "${scenes[@]}" --objects \
  qte-select "${agent[@]}" "$@" \
  plan-path ${PLAN_OPTIONS:-} > "$tmp/agent.rec"
if [ -n "${AGENT_STREAM:-}" ]; then cp "$tmp/agent.rec" "$AGENT_STREAM.tmp" && mv "$AGENT_STREAM.tmp" "$AGENT_STREAM"; fi
"$PYTHON" "$here/analysis/failure_reasons.py" --label "$label" --seed "$seed" ${FAILURE_EPISODES:+--episodes} \
  "$experts" "$tmp/agent.rec"
