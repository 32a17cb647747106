#!/usr/bin/env bash
# failure_reasons.sh for every finished run under RUNS/<takeaway>/<task>/<label>-seed<N>/ that
# has no failures.csv (runs made by a learn.sh that did not end with it, such as the takeaway 3
# runs pinned to an older build), copied to results/<takeaway>/failures/ as learn.sh's would be.
# The run's task, K (from its label), image size (from its demonstrations) and planner options
# (its plan_options, learn.sh's PLAN_OPTIONS) decide the replay (common.sh's finished_run_settings).
# Usage: failures_of_runs.sh RUNS   (the built programs on PATH; make -C examples failures)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
for run in "$1"/takeaway*/*/*-seed*/; do
  finished_run_settings "$run" || continue
  takeaway=$(basename "$(dirname "$(dirname "$run")")")
  out=$here/results/$takeaway/failures/${run_task}_$run_name.csv
  [ -f "$run/failures.csv" ] || [ -f "$out" ] && continue
  echo "$takeaway $run_task $run_name: K ${run_k[*]}, $run_image, $run_episodes episodes" >&2
  mkdir -p "$(dirname "$out")"
  if ! PLAN_OPTIONS=$run_plan_options write_once "$out" bash "$here/failure_reasons.sh" "$run_task" "$run/eval/checkpoint.rec" \
      "${run_k[0]}" "$run_image" "$run_episodes" "$run_label" "$run_seed" "${run_k[@]:1}"; then
    echo "failures_of_runs.sh: failure_reasons.sh failed for $run" >&2
    exit 1
  fi
done
