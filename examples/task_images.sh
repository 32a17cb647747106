#!/usr/bin/env bash
# Regenerates examples/images/<task>.png and <task>.overhead.png: the first front-camera and
# over-the-shoulder frames of each task at 256x256 (seed 1); for Task Set 1 also
# <task>.solved.png, the last over-the-shoulder frame of the expert's demonstration.
set -euo pipefail
dir=$(dirname "$0")/images
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
task_set_1="take_lid_off_saucepan pick_up_cup put_rubbish_in_bin stack_wine phone_on_base take_umbrella_out_of_umbrella_stand"
for task in reach_target pick_and_lift lift_numbered_block reach_prism pick_and_lift_small stack_blocks setup_checkers $task_set_1; do
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
