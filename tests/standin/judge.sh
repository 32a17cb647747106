#!/bin/sh
# The person of the stand-in world, for robot-step --judge "sh judge.sh": puts the scene back by
# asking standin-world to rebuild it from the reset's scene seed, and says how each step went as
# the simulator judged it. STANDIN_SPOOL names the spool both serve.
set -eu
dir=$STANDIN_SPOOL/standin
case $1 in
  reset)
    request=$dir/reset-$$.request
    echo "$QTE_TASK $QTE_VARIATION $QTE_SEED" > "$request.tmp"
    mv "$request.tmp" "$request"
    tries=0
    until [ -f "$dir/reset-$$.ready" ]; do
      tries=$((tries + 1))
      [ "$tries" -lt 3000 ] || { echo "judge.sh: standin-world did not set up the scene" >&2; exit 1; }
      sleep 0.01
    done ;;
  outcome)
    if [ -z "$QTE_MOTION" ]; then echo continue; else cat "$dir/$QTE_MOTION.outcome"; fi ;;
  *) echo "judge.sh: reset or outcome, not '$1'" >&2; exit 2 ;;
esac
