#!/usr/bin/env bash
# An episode of a trained agent as a video with its attention beside the camera:
#   examples/episode_video.sh CHECKPOINT TASK OUT.gif|OUT.mp4 [SEED [K [IMAGE]]]
# Runs one greedy episode on a held-out scene (sim-step --scenes eval) with qte-select's
# pictures saved, then replays the planned trajectories with sim-step --every-step so the video
# shows every 50 ms control step, each frame beside the depth-0/depth-1 Q-values of the action
# it carries out (its moves planned with PLAN_OPTIONS, as learn.sh). Prints the episode's success.
# The programs must be on PATH (make install, or
# PATH=build/tools:$PATH).
set -euo pipefail
ckpt=$1 task=$2 out=$3 seed=${4:-0} k=${5:-10} image=${6:-128x128}
source "$(dirname "$0")/common.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# The episode: its observations, actions and planned trajectories.
agent_loop "$tmp/loop" \
  sim-step --task "$task" --episodes 1 --seed "$seed" --scenes eval --image-size "$image" \
  qte-select --checkpoint "$ckpt" --k "$k" --png "$tmp/attention" \
  plan-path ${PLAN_OPTIONS:-} --seed "$seed" > "$tmp/planned.rec"
stream-cat --type trajectory "$tmp/planned.rec" \
  | sim-step --task "$task" --episodes 1 --seed "$seed" --scenes eval --image-size "$image" --every-step \
  > "$tmp/every_step.rec"
stream-png --video "$out" --fps 8 --height 256 --attention "$tmp/attention" "$tmp/every_step.rec"
episode-stats "$tmp/planned.rec" >&2
