#!/usr/bin/env bash
# The real-world loop end to end, with the simulator standing in for the robot, camera and
# person (tests/standin): 2 demonstrations recorded as a camera and joint log would record them
# (write_recording.py, packed by obs-pack), then examples/learn.sh acting and evaluating through
# robot-step. Every motion robot-step wrote was answered by the stand-in's driver, every frame
# it asked for was taken, the episodes' transitions reached the replay the learner follows, and
# the run evaluated its final networks through robot-step.
source "$(dirname "$0")/common.sh"
src=${QTE_SOURCE:?}
standin=${QTE_STANDIN:?set QTE_STANDIN to the built tests/standin/standin-world}
export SEED=0 DEMOS=2 IMAGE=48x48 ACT_K=1 TARGET_K=0 ENV_STEPS=12 CHUNK_EPISODES=2 EVAL_EVERY=1000 \
  EVAL_EPISODES=2 BATCH=4 PRETRAIN=2 RATIO=0.2 CHECKPOINT_EVERY=1 START_AFTER=0 LABEL=standin

demo-record --task reach_target --episodes 2 --seed 0 --scenes demo --image-size "$IMAGE" --output "$tmp/demos.rec" 2>/dev/null ||
  fail "demo-record exit $?"
"$py" "$src/tests/standin/write_recording.py" "$tmp/demos.rec" "$tmp/recording" "$tmp/recorded.rec" 2>/dev/null ||
  fail "write_recording.py exit $?"
# The simulated front camera's calibration at this size, as a real camera's would be given.
camera=$("$py" -c "
import sys; sys.path.insert(0, '$src/lib/python'); import qte_stream
o = next(r for r in qte_stream.read_records('$tmp/demos.rec') if r.type == 'obs')
K, E = o.fields['front.intrinsics'], o.fields['front.extrinsics']
print('--intrinsics %r,%r,%r,%r --extrinsics %s' % (K[0,0], K[1,1], K[0,2], K[1,2], ','.join(repr(float(v)) for v in E.reshape(-1))))")

spool=$tmp/spool
mkdir -p "$spool"
"$standin" --spool "$spool" --image-size "$IMAGE" 2> "$tmp/standin.log" &
standin_pid=$!
trap 'touch "$spool/stop"; wait $standin_pid; rm -rf "$tmp"' EXIT
STAGE="robot-step --spool $spool --judge 'STANDIN_SPOOL=$spool sh $src/tests/standin/judge.sh' $camera" \
  DEMOS_FROM=$tmp/recorded.rec timeout 600 bash "$src/examples/learn.sh" reach_target "$tmp/run" 2> "$tmp/learn.log" ||
  fail "learn.sh through robot-step: exit $?: $(tail -3 "$tmp/learn.log"; tail -3 "$tmp/run/actor.log")"

motions=$(ls "$spool" | grep -c '\.xarm\.csv$')
done_=$(ls "$spool" | grep -c '^motion-.*\.done$')
captures=$(ls "$spool" | grep -c '\.request$')
ready=$(ls "$spool" | grep -c '\.ready$')
[ "$motions" -gt 12 ] && [ "$motions" = "$done_" ] || fail "$motions motions written, $done_ answered"
[ "$captures" = "$ready" ] && [ "$captures" -ge "$motions" ] || fail "$captures captures asked for, $ready taken, $motions motions"
[ ! -e "$spool/stop" ] || fail "the spool was stopped: $(cat "$spool/stop")"
grep -q "the recorded demonstrations of $tmp/recorded.rec" "$tmp/learn.log" || fail "the run did not take the recorded demonstrations"
# Transitions of the demonstrations and of the actor's episodes.
transitions=$(stream-dump "$tmp/run/replay.rec" | grep -c ' transition ')
demo_transitions=$(keyframe --output - "$tmp/recorded.rec" 2>/dev/null | stream-dump | grep -c ' transition ')
[ "$transitions" -gt "$demo_transitions" ] || fail "the replay holds $transitions transitions, the demonstrations alone $demo_transitions"
final=$(tail -1 "$tmp/run/eval.csv")
[ "${final%%,*}" = standin ] && [ "$(cut -d, -f13 <<< "$final")" = 2 ] || fail "final evaluation: $final"
grep -q "robot-step: reach_target episode" "$tmp/run/actor.log" || fail "the actor did not act through robot-step"
echo "ok: learn.sh through robot-step and the stand-in world: $motions motions, $captures frames, $transitions transitions; final evaluation $final"
