#!/usr/bin/env bash
# `make demo`: runs the toolkit's main job on the built-in simulated tasks and says what it
# did: simulation, planning, demonstrations, keyframe transitions, voxel grids, and a short
# but real run of the learning loop (learner, actor through a FIFO, evaluation, curve).
set -euo pipefail
out=${QTE_DEMO_DIR:-out/demo}
rm -rf "$out" && mkdir -p "$out"
say() { printf '\n== %s\n' "$*" >&2; }

say "1. one episode start per task: the simulator's observations (sim-step), as PNG (stream-png)"
for task in reach_target pick_and_lift lift_numbered_block; do
  sim-step --task "$task" --seed 1 --image-size 256x256 --cameras front,wrist,overhead \
    --output "$out/$task.rec" < /dev/null
  stream-png --depth --dir "$out/$task" "$out/$task.rec"
  echo "$task: $(stream-dump --summary "$out/$task.rec")" >&2
done

say "2. a trajectory through a pipe: reset + joint waypoints in, an observation every 50 ms out"
# From the ready pose, turn the base and lean forward over the table (radians, 2 s).
ready="0,-0.35,0,0.75,0,1.1,0"
lean="0.5,0.1,0,0.9,0,0.8,0"
{ stream-pack reset task=pick_and_lift variation:i32=0 seed:i64=1
  stream-pack trajectory time_s:f64=0,2 "joint_positions:f64[2,7]=$ready,$lean" gripper_open:u8=1
} | sim-step --every-step --image-size 128x128 --output "$out/motion.rec"
stream-png --every 8 --dir "$out/motion" "$out/motion.rec"
stream-dump --type obs --values 3 "$out/motion.rec" > "$out/motion.txt"
grep -E "^#|joint_positions|terminal|failure" "$out/motion.txt" | tail -6 >&2

say "3. expert demonstrations through the planner (demo-record), keyframe transitions (keyframe)"
for task in reach_target pick_and_lift lift_numbered_block; do
  demo-record --task "$task" --episodes 3 --seed 1 --variation random --compress --output "$out/demos_$task.rec"
  keyframe --seed 1 --output "$out/transitions_$task.rec" "$out/demos_$task.rec"
done
ls -l "$out"/demos_*.rec "$out"/transitions_*.rec >&2

say "4. what the agent sees: the voxel grid at depth 0 and the depth-1 grid around a fixed centre, 0.1, 0, 0.8 m (voxelize)"
stream-cat --type obs --head 1 "$out/demos_lift_numbered_block.rec" \
  | voxelize --png "$out/voxels" --centre 0.1,0.0,0.8 --output "$out/voxels.rec"
ls "$out/voxels" >&2

say "5. the format: any stream prints as text or JSON Lines, and exports to NumPy"
stream-dump --json --values 2 "$out/motion.rec" > "$out/motion.jsonl"
head -c 400 "$out/motion.jsonl" >&2; echo " ..." >&2
stream-dump --npy "$out/npy" --type obs "$out/reach_target.rec" > /dev/null
ls "$out/npy" >&2

say "6. the learning loop, short: 5 demos, 60 learner steps on them, at least 30 exploring steps (whole chunks of 5 episodes), greedy evaluation"
# The same loop as `make -C examples reach_target`, on a budget of about two minutes (the
# full run is 10 demos and 2,000 environment steps). See examples/learn.sh.
make -s -C examples reach_target RUNS="$(realpath "$out")/runs" BUILD="$(dirname "$(command -v sim-step)")/.." \
  DEMOS=5 PRETRAIN=60 ENV_STEPS=30 EVAL_EVERY=30 CHUNK_EPISODES=5 EVAL_EPISODES=10 CHECKPOINT_EVERY=20 BATCH=16
run=$out/runs/reach_target/$(make -s -C examples --no-print-directory label)-seed0
cat "$run/eval.csv" >&2
stream-cat --type obs --where step=0 --head 1 "$run/demos.rec" \
  | qte-select --checkpoint "$run/ckpt/latest.rec" --k 10 --png "$out/attention" > /dev/null
ls "$run/curve.png" "$out"/attention/*.png >&2

say "done: streams (.rec), PNG frames, .npy arrays, a learning run (eval.csv, curve.png) are in $out/"
echo "Ran: sim-step, demo-record (with plan-path's planner), keyframe, voxelize, stream-png," >&2
echo "stream-pack, stream-cat, stream-dump, qattn-train, qte-select, episode-stats, plot-curves." >&2
