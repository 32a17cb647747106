#!/usr/bin/env bash
# Slow (label 'slow'; make check-slow): the scripted experts, executed through the planner,
# succeed in >= 95% of 50 seeded episodes of each task.
set -uo pipefail
tools=${QTE_TOOLS:?}
export PATH="$tools:$PATH"
status=0
for task in reach_target pick_and_lift lift_numbered_block reach_prism pick_and_lift_small stack_blocks; do
  line=$(demo-record --task "$task" --episodes 50 --variation random --seed 7 --output /dev/null 2>&1 | tail -n 1)
  echo "$task: $line"
  n=$(sed -n 's/.*expert success \([0-9]*\)\/50.*/\1/p' <<<"$line")
  [ -n "$n" ] && [ "$n" -ge 48 ] || { echo "FAIL: $task expert success below 95%"; status=1; }
done
exit $status
