#!/usr/bin/env bash
# Prints the actor's cost per environment step, end to end: the closed pipeline learn.sh runs
# (sim-step < fifo | qte-select --k K | plan-path | tee fifo) on pick_and_lift exploration
# scenes, with networks trained briefly on 5 demonstrations (so that the moves are real
# ones: untrained networks fail at once, and a failed move costs next to nothing), and the
# CPU time of the three programs together per step.
# Usage: bench_actor [TOOLS_DIR] [EPISODES] [K] [IMAGE]   (defaults: the build's tools, 10, 10, 128x128)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
tools=${1:-$here/../../tools} episodes=${2:-10} k=${3:-10} image=${4:-128x128}
export PATH=$tools:$PATH
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

demo-record --task pick_and_lift --episodes 5 --seed 1 --image-size "$image" --output "$tmp/demo.rec" 2>/dev/null
keyframe --output "$tmp/replay.rec" "$tmp/demo.rec" 2>/dev/null
qattn-train --steps 150 --start-after 0 --checkpoint-every 150 --seed 1 --threads 2 --checkpoint-dir "$tmp/ckpt" "$tmp/replay.rec" \
  2>/dev/null

# (No wrapper around a program of the loop: one holding the pipe open would keep the loop
# from winding down. The shell's own `time` of the whole pipeline holds nothing.)
mkfifo "$tmp/loop"
TIMEFORMAT='%R %U %S'
{ time sim-step --task pick_and_lift --episodes "$episodes" --seed 7 --scenes explore --image-size "$image" \
    --compress < "$tmp/loop" 2>/dev/null \
  | qte-select --checkpoint "$tmp/ckpt/latest.rec" --k "$k" --epsilon 0.1 --seed 7 --threads 1 2>/dev/null \
  | plan-path 2>/dev/null | tee "$tmp/loop" > "$tmp/episodes.rec"; } 2> "$tmp/time"
steps=$(stream-dump --summary "$tmp/episodes.rec" | awk '$1 == "action" { print $2 }')
read -r wall user system < "$tmp/time"
# Moves executed: trajectory records that are not just a failure (failure, ignore_collisions).
trajectories=$(stream-dump "$tmp/episodes.rec" | grep ' trajectory (' | grep -vc ' (2 fields' || true)
awk -v w="$wall" -v u="$user" -v s="$system" -v n="$steps" -v e="$episodes" -v k="$k" -v image="$image" -v moved="$trajectories" 'BEGIN {
  printf "actor pipeline, pick_and_lift %s, K = %s: %d environment steps (%d episodes, %d moves executed) in %.1f s: %.1f ms per step\n", image, k, n, e, moved, w, 1000 * w / n
  printf "  CPU per step, the three programs together: %.1f ms (user %.1f, system %.1f)\n", 1000 * (u + s) / n, 1000 * u / n, 1000 * s / n }'
