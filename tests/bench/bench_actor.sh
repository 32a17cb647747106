#!/usr/bin/env bash
# Prints the actor's cost per environment step, end to end, both ways learn.sh could run it:
#   per chunk:  a new closed pipeline for every chunk of 10 episodes
#               (sim-step --episodes 10 < fifo | qte-select | plan-path | tee fifo | keyframe),
#               so LibTorch and the simulator start once per chunk;
#   persistent: one pipeline for all the chunks, sim-step --chunk-episodes 10 --gate DIR (what
#               learn.sh runs), starting once.
# Same chunks (chunk c explores the scenes of seed 7 * 100000 + c either way), same networks
# (trained briefly on 5 demonstrations, so that the moves are real ones), alternated twice;
# CPU is the processor time of every program of the pipeline.
# Usage: bench_actor [TOOLS_DIR] [CHUNKS] [K] [IMAGE] [TASK]
#   (defaults: the build's tools, 3, 10, 128x128, pick_and_lift)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
tools=${1:-$here/../../tools} chunks=${2:-3} k=${3:-10} image=${4:-128x128} task=${5:-pick_and_lift}
export PATH=$tools:$PATH
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
seed=700000 episodes=10

demo-record --task "$task" --episodes 5 --seed 1 --image-size "$image" --scenes demo --output "$tmp/demo.rec" 2>/dev/null
keyframe --output "$tmp/replay.rec" "$tmp/demo.rec" 2>/dev/null
qattn-train --steps 150 --start-after 0 --checkpoint-every 150 --seed 1 --threads 2 --checkpoint-dir "$tmp/ckpt" "$tmp/replay.rec" \
  2>/dev/null
select_() { qte-select --checkpoint "$tmp/ckpt/latest.rec" --k "$k" --epsilon 0.1 --seed 7 --threads 1 2>/dev/null; }

per_chunk() {  # -> environment steps of the chunks, run a pipeline each
  local c
  for ((c = 0; c < chunks; c++)); do
    rm -f "$tmp/loop"; mkfifo "$tmp/loop"
    sim-step --task "$task" --episodes $episodes --seed $(( seed + c )) --scenes explore --image-size "$image" \
        --compress < "$tmp/loop" 2>/dev/null \
      | select_ | plan-path 2>/dev/null | tee "$tmp/loop" | keyframe --agent --append --output "$tmp/out.rec" 2>/dev/null
  done
}
persistent() {
  local c
  rm -rf "$tmp/loop" "$tmp/gate"; mkfifo "$tmp/loop"; mkdir "$tmp/gate"
  for ((c = 0; c < chunks; c++)); do touch "$tmp/gate/$(printf '%04d' $c).go"; done
  # The gate's stop file once the last chunk has ended: the pipeline winds down.
  ( while [ ! -f "$tmp/gate/$(printf '%04d' $(( chunks - 1 ))).steps" ]; do sleep 0.05; done; touch "$tmp/gate/stop" ) &
  sim-step --task "$task" --episodes 10000000 --seed $seed --scenes explore --chunk-episodes $episodes --gate "$tmp/gate" \
      --image-size "$image" --compress < "$tmp/loop" 2>/dev/null \
    | select_ | plan-path 2>/dev/null | tee >(stream-cat --type trajectory > "$tmp/loop") \
    | keyframe --agent --append --output "$tmp/out.rec" 2>/dev/null
  wait
}
measure() {  # MODE -> "cpu_seconds environment_steps"
  local before after
  rm -f "$tmp/out.rec"
  times > "$tmp/before"  # (the builtin, not in a pipeline: its children are those of this shell)
  "$1"
  times > "$tmp/after"
  before=$(awk 'NR == 2 { print $1 " " $2 }' "$tmp/before") after=$(awk 'NR == 2 { print $1 " " $2 }' "$tmp/after")
  steps=$(stream-dump --summary "$tmp/out.rec" | awk '$1 == "transition" { print $2 }')
  awk -v b="$before" -v a="$after" -v n="$steps" 'function sec(t, m) { split(t, m, "m"); return m[1] * 60 + m[2] }
    BEGIN { split(b, x, " "); split(a, y, " "); printf "%.3f %d\n", sec(y[1]) + sec(y[2]) - sec(x[1]) - sec(x[2]), n }'
}
echo "actor pipeline, $task $image, K = $k, $chunks chunks of $episodes episodes, each way twice, alternated:"
for round in 1 2; do
  for mode in per_chunk persistent; do
    read -r cpu steps <<<"$(measure $mode)"
    awk -v m=$mode -v c="$cpu" -v n="$steps" -v r=$round \
      'BEGIN { printf "  %-10s (round %d): %4d environment steps, %6.1f s CPU, %6.1f ms CPU per step\n", m, r, n, c, 1000 * c / n }'
    echo "$mode $cpu $steps" >> "$tmp/results"
  done
done
awk '{ cpu[$1] += $2; n[$1] += $3 } END {
  old = cpu["per_chunk"] / n["per_chunk"]; new = cpu["persistent"] / n["persistent"]
  printf "  CPU per step: persistent %.1f ms, per chunk %.1f ms: persistent / per chunk = %.3f\n", 1000 * new, 1000 * old, new / old
  printf "  start-up cost per chunk, per chunk - persistent: %.2f s CPU\n", (cpu["per_chunk"] - cpu["persistent"] * n["per_chunk"] / n["persistent"]) / (2 * '"$chunks"') }' "$tmp/results"
