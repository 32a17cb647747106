#!/usr/bin/env bash
# Slow (label 'slow'; make check-slow): the scripted experts, executed through the planner,
# succeed in >= 95% of 50 seeded episodes of each task, and of each variation that changes
# what the expert does (the coarse-ambiguity tasks' shapes, stack heights, checker counts;
# colours do not change it, so stack_blocks' variations 0-2 are its three heights).
set -uo pipefail
tools=${QTE_TOOLS:?}
export PATH="$tools:$PATH"
status=0
for run in reach_target:random pick_and_lift:random lift_numbered_block:random reach_prism:0 \
           pick_and_lift_small:0 pick_and_lift_small:1 pick_and_lift_small:2 pick_and_lift_small:3 \
           pick_and_lift_small:4 stack_blocks:0 stack_blocks:1 stack_blocks:2 \
           setup_checkers:0 setup_checkers:1 setup_checkers:2 take_lid_off_saucepan:0 pick_up_cup:random \
           put_rubbish_in_bin:0 stack_wine:0 phone_on_base:0 take_umbrella_out_of_umbrella_stand:0; do
  task=${run%%:*} variation=${run#*:}
  line=$(demo-record --task "$task" --episodes 50 --variation "$variation" --seed 7 --output /dev/null 2>&1 | tail -n 1)
  echo "$task variation $variation: $line"
  n=$(sed -n 's/.*expert success \([0-9]*\)\/50.*/\1/p' <<<"$line")
  [ -n "$n" ] && [ "$n" -ge 48 ] || { echo "FAIL: $task variation $variation: expert success below 95%"; status=1; }
done
exit $status
