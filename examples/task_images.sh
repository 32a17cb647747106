#!/usr/bin/env bash
# Regenerates examples/images/<task>.png and <task>.overhead.png: the first front-camera and
# over-the-shoulder frames of each task at 256x256 (seed 1); for Task Set 1 also
# <task>.solved.png, the last over-the-shoulder frame of the expert's demonstration.
set -euo pipefail
dir=$(dirname "$0")/images
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# The tasks and their sets from tasks.txt (the Makefile's table); Task Set 1 but for the first two.
tasks=$(sed -n 's/^\([a-z_]\{1,\}\) *|.*/\1/p' "$(dirname "$0")/tasks.txt")
task_set_1=$(sed -n 's/^\([a-z_]\{1,\}\) *| *1 *|.*/\1/p' "$(dirname "$0")/tasks.txt" | grep -vx 'reach_target\|pick_and_lift')
for task in $tasks; do
  sim-step --task "$task" --seed 1 --image-size 256x256 --cameras front,overhead < /dev/null \
    | stream-png --dir "$tmp/$task"
  cp "$tmp/$task/000000.front.rgb.png" "$dir/$task.png"
  cp "$tmp/$task/000000.overhead.rgb.png" "$dir/$task.overhead.png"
done
for task in $task_set_1; do
  demo-record --task "$task" --episodes 1 --seed 1 --image-size 256x256 --cameras overhead --no-points 2> /dev/null \
    | stream-png --dir "$tmp/$task-demo"
  cp "$(ls "$tmp/$task-demo"/*.overhead.rgb.png | tail -1)" "$dir/$task.solved.png"
done
