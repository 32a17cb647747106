#!/usr/bin/env bash
# examples/learn.sh with ACTORS=2: one learner, two actor pipelines side by side on their
# chunks (scenes per chunk: tests/unit/sim_step); one actor killed mid-chunk costs only its
# chunk, which runs again in a new pipeline, and the run completes with every chunk and every
# episode accounted for.
source "$(dirname "$0")/common.sh"
learn=${QTE_SOURCE:?}/examples/learn.sh
run=$tmp/run
export SEED=0 DEMOS=2 IMAGE=48x48 ACT_K=1 TARGET_K=0 ENV_STEPS=30 CHUNK_EPISODES=3 EVAL_EVERY=1000 \
  EVAL_EPISODES=1 BATCH=4 PRETRAIN=2 RATIO=0.2 CHECKPOINT_EVERY=1 START_AFTER=0 ACTORS=2

bash "$learn" reach_target "$run" 2> "$tmp/learn.log" &
learn_pid=$!
# Actor 1 runs chunks 1, 3, ...: kill its simulator once chunk 1 has started, and meanwhile
# check that the run never has more than one learner: the supervisor's children that are
# qattn-train (LeakSanitizer's tracer, a child of the learner with its command line, shows up
# under make sanitize: not counted).
learners_now() {
  local supervisor
  supervisor=$(pgrep -P $learn_pid -f supervise.py) || { echo 0; return; }
  pgrep -c -P "$supervisor" -f "qattn-train --follow .*$run/replay.rec" || true
}
killed=0 learners=0
for _ in $(seq 1 2400); do
  now=$(learners_now)
  learners=$(( now > learners ? now : learners ))
  if [ $killed = 0 ] && [ -f "$run/actors/gate-1/0001.go" ] && pkill -9 -f "sim-step .*--task reach_target .*--first-chunk 1 --chunk-stride 2"; then
    killed=1
  fi
  kill -0 $learn_pid 2>/dev/null || break
  sleep 0.05
done
wait $learn_pid || fail "learn.sh with ACTORS=2: exit $?: $(tail -5 "$tmp/learn.log")"
[ $killed = 1 ] || fail "chunk 1's actor never ran"
[ "$learners" = 1 ] || fail "$learners learners at once"
grep -q "actor 1 failed in chunk 1 (attempt 1): sim-step killed by signal KILL" "$tmp/learn.log" \
  || fail "no failed chunk: $(cat "$tmp/learn.log")"
[ -f "$run/eval.csv" ] || fail "no eval.csv"

# Every chunk up to the last finished, each actor's own.
chunks=$(ls "$run"/actors/gate-*/ | grep -c '\.steps$')
[ "$chunks" -ge 2 ] || fail "$chunks chunks"
for ((c = 0; c < chunks; c++)); do
  [ -f "$run/actors/gate-$((c % 2))/$(printf '%04d' $c).steps" ] || fail "chunk $c missing: $(ls "$run"/actors/gate-*)"
done
# Nothing lost: the replay holds a transition for every action of every finished chunk (and
# those of the killed attempt's finished episodes besides).
actions=$(cat "$run"/actors/gate-*/*.steps | awk '{ n += $1 } END { print n }')
count() { stream-dump --summary | awk '$1 == "transition" { print $2 }'; }
agent=$(( $(count < "$run/replay.rec") - $(stream-cat --type transition --where demo=1 "$run/replay.rec" | count) ))
[ "$agent" -ge "$actions" ] || fail "$agent agent transitions in the replay for $actions actions"
echo "ok: $chunks chunks, $actions actions, $agent agent transitions"
