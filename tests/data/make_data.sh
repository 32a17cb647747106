#!/usr/bin/env bash
# The small saved streams the command tests start from (tests/data/*.rec), made by the built
# programs. Tests of one stage read these instead of running the stages upstream of it, so
# a broken upstream program fails its own tests, and test_saved_data, not every test.
#   tests/data/make_data.sh build/tools [DIR]    regenerate (DIR: where; default tests/data)
# test_saved_data runs this into a scratch directory and compares: when a change to the
# simulator, planner or format changes these bytes on purpose, run it and commit the files.
set -euo pipefail
tools=${1:?usage: make_data.sh TOOLS_DIR [DIR]}
dir=${2:-$(dirname "$0")}
export PATH="$tools:$PATH"
# One reach_target demonstration, every control step (keyframe, qattn-train, qte-select).
demo-record --task reach_target --episodes 1 --seed 1 --image-size 32x32 --compress \
  --output "$dir/reach_target_demo.rec" 2>/dev/null
# One lift_numbered_block demonstration: three keyframes, a textured block (keyframe, voxelize).
demo-record --task lift_numbered_block --episodes 1 --seed 3 --image-size 32x32 --compress \
  --output "$dir/lift_numbered_block_demo.rec" 2>/dev/null
# The first observation of a pick_and_lift scene (plan-path).
stream-pack reset task=pick_and_lift seed:i64=2 > "$dir/pick_and_lift_reset.rec"
sim-step --image-size 64x64 --output "$dir/pick_and_lift_obs.rec" < "$dir/pick_and_lift_reset.rec"
