#!/usr/bin/env bash
# Regenerates examples/images/<task>.png: the first front-camera frame of each task at 256x256.
set -euo pipefail
dir=$(dirname "$0")/images
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for task in reach_target pick_and_lift lift_numbered_block reach_prism pick_and_lift_small stack_blocks setup_checkers; do
  sim-step --task "$task" --seed 1 --image-size 256x256 --cameras front,overhead < /dev/null \
    | stream-png --dir "$tmp/$task"
  cp "$tmp/$task/000000.front.rgb.png" "$dir/$task.png"
  cp "$tmp/$task/000000.overhead.rgb.png" "$dir/$task.overhead.png"
done
