#!/usr/bin/env bash
# Which depth decided (depth_decisions.sh) for the final agent of every finished run under
# RUNS_OF_A_TAKEAWAY/<task>/<label>-seed<N>/: acting with its own K on its own evaluation
# scenes (their number, the image size and planner options as the run had them: common.sh's
# finished_run_settings), the table written to OUT/<task>_<label>-seed<N>.csv. A run whose
# table is there is skipped.
# Usage: depths_of_runs.sh RUNS_OF_A_TAKEAWAY OUT   (the built programs on PATH;
#        make -C examples takeaway2-depths3 and takeaway2-long call it)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
mkdir -p "$2"
for run in "$1"/*/*-seed*/; do
  finished_run_settings "$run" || continue
  out=$2/${run_task}_$run_name.csv
  [ -f "$out" ] && continue
  echo "$(date +%T) depth decisions of $run_task $run_name: K ${run_k[*]}, $run_image, $run_episodes episodes" >&2
  if ! PLAN_OPTIONS=$run_plan_options write_once "$out" bash "$here/depth_decisions.sh" "$run_task" "$run/eval/checkpoint.rec" \
      "${run_k[0]}" "$run_image" "$run_episodes" "$run_label" "${run_k[@]:1}"; then
    echo "depths_of_runs.sh: depth_decisions.sh failed for $run" >&2
    exit 1
  fi
done
