#!/usr/bin/env bash
# failure_reasons.sh for every finished run under RUNS/<takeaway>/<task>/<label>-seed<N>/ that
# has no failures.csv (runs made by a learn.sh that did not end with it, such as the takeaway 3
# runs pinned to an older build), copied to results/<takeaway>/failures/ as learn.sh's would be.
# The run's task, K (from its label), image size (from its demonstrations) and planner options
# (its plan_options, learn.sh's PLAN_OPTIONS) decide the replay.
# Usage: failures_of_runs.sh RUNS   (the built programs on PATH; make -C examples failures)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
for run in "$1"/takeaway*/*/*-seed*/; do
  run=${run%/}
  [ -f "$run/eval.csv" ] && [ -f "$run/eval/checkpoint.rec" ] || continue
  name=$(basename "$run") task=$(basename "$(dirname "$run")") takeaway=$(basename "$(dirname "$(dirname "$run")")")
  label=${name%-seed*} seed=${name##*-seed}
  out=$here/results/$takeaway/failures/${task}_$name.csv
  [ -f "$run/failures.csv" ] || [ -f "$out" ] && continue
  read -r -a k <<< "$(acting_k_of_label "$label")"
  image=$(stream-cat --type obs --head 1 "$run/demos.rec" | stream-dump | awk '$1 ~ /\.rgb$/ { gsub(/[\[\],]/, ""); print $3 "x" $4; exit }')
  episodes=$(awk -F, 'NR == 2 { for (i = 1; i <= NF; i++) if (h[i] == "episodes") print $i } NR == 1 { for (i = 1; i <= NF; i++) h[i] = $i }' "$run/eval.csv")
  echo "$takeaway $task $name: K ${k[*]}, $image, $episodes episodes" >&2
  mkdir -p "$(dirname "$out")"
  PLAN_OPTIONS=$(cat "$run/plan_options" 2>/dev/null || true) bash "$here/failure_reasons.sh" "$task" "$run/eval/checkpoint.rec" "${k[0]}" "$image" "$episodes" "$label" "$seed" \
    "${k[@]:1}" > "$out.tmp" && mv "$out.tmp" "$out"
done
