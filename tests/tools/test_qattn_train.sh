#!/usr/bin/env bash
# qattn-train as a program: initial networks, training with metrics, checkpoints that resume
# byte for byte after an interruption or a kill, following a growing replay, bad input.
source "$(dirname "$0")/common.sh"

src=${QTE_SOURCE:?set QTE_SOURCE to the repository}
cp "$src/tests/data/lift_numbered_block_demo.rec" "$tmp/demos.rec"  # one demonstration (tests/data/make_data.sh)
keyframe --seed 1 --output "$tmp/tr.rec" "$tmp/demos.rec" 2>/dev/null || fail "keyframe"
# Options as arrays: a program started in the background must be the process $! names (a
# shell function would run it under a subshell, and kill -9 of that would leave it running).
train_options=(--batch 4 --start-after 4 --seed 5 --log-every 2)
train() { qattn-train "${train_options[@]}" "$@"; }

# The pacing rule, for scripts that wait on the learner (learn.sh): pretrain + floor(ratio * n).
[ "$(qattn-train --steps-allowed 7 --pretrain 3 --replay-ratio 0.5)" = 6 ] || fail "--steps-allowed"

# --steps 0: the initial networks, at once, for an actor to start with.
train --steps 0 --checkpoint-dir "$tmp/init" "$tmp/tr.rec" 2>/dev/null || fail "--steps 0"
[ -f "$tmp/init/step-00000000.rec" ] && [ -f "$tmp/init/latest.rec" ] || fail "no initial checkpoint"
stream-dump --summary "$tmp/init/latest.rec" | grep -q "^checkpoint	2 records" || fail "checkpoint records"
stream-dump --summary "$tmp/init/latest.rec" | grep -q "^learner	1 records" || fail "learner state"

# Six steps straight, and three + three with --resume: the same bytes.
train --steps 6 --checkpoint-every 3 --keep 2 --metrics "$tmp/a.csv" --checkpoint-dir "$tmp/a" "$tmp/tr.rec" \
  2> "$tmp/a.log" || fail "train: $(tail -3 "$tmp/a.log")"
grep -q "qattn-train: step 6/6  loss" "$tmp/a.log" || fail "no progress line: $(cat "$tmp/a.log")"
[ "$(ls "$tmp/a" | tr '\n' ' ')" = "latest.rec step-00000003.rec step-00000006.rec " ] || fail "kept: $(ls "$tmp/a")"
head -1 "$tmp/a.csv" | grep -q "^step,transitions,agent_transitions,replay,demos,loss,loss_d0,loss_d1,q_mean_d0" \
  || fail "metrics header: $(head -1 "$tmp/a.csv")"
[ "$(cut -d, -f1 "$tmp/a.csv" | tail -n +2 | tr '\n' ' ')" = "2 4 6 " ] || fail "metrics rows: $(cat "$tmp/a.csv")"
train --steps 3 --checkpoint-every 3 --metrics "$tmp/b.csv" --checkpoint-dir "$tmp/b" "$tmp/tr.rec" 2>/dev/null || fail "b"
train --steps 6 --checkpoint-every 3 --metrics "$tmp/b.csv" --checkpoint-dir "$tmp/b" --resume "$tmp/tr.rec" \
  2> "$tmp/b.log" || fail "resume: $(cat "$tmp/b.log")"
grep -q "resumed at step 3" "$tmp/b.log" || fail "$(cat "$tmp/b.log")"
cmp -s "$tmp/a/latest.rec" "$tmp/b/latest.rec" || fail "a resumed run differs from an uninterrupted one"
[ "$(cut -d, -f1 "$tmp/b.csv" | tr '\n' ' ')" = "step 2 3 4 6 " ] || fail "resumed metrics: $(cat "$tmp/b.csv")"

# The networks' layers: LibTorch's throughout with QTE_NETWORK_LAYERS=libtorch, the same bytes
# run after run; on a processor where oneDNN runs them (AVX2), other bytes than oneDNN's (the
# same sums in another order); any other value refused.
train --steps 4 --checkpoint-dir "$tmp/on" "$tmp/tr.rec" 2>/dev/null || fail "default layers"
for d in lt lt2; do
  QTE_NETWORK_LAYERS=libtorch train --steps 4 --checkpoint-dir "$tmp/$d" "$tmp/tr.rec" 2>/dev/null \
    || fail "QTE_NETWORK_LAYERS=libtorch"
done
cmp -s "$tmp/lt/latest.rec" "$tmp/lt2/latest.rec" || fail "LibTorch's layers: two runs differ"
if grep -qw avx2 /proc/cpuinfo; then
  cmp -s "$tmp/on/latest.rec" "$tmp/lt/latest.rec" && fail "QTE_NETWORK_LAYERS=libtorch made no difference"
fi
err=$(QTE_NETWORK_LAYERS=fast train --steps 4 --checkpoint-dir "$tmp/bad" "$tmp/tr.rec" 2>&1) \
  && fail "QTE_NETWORK_LAYERS=fast accepted"
grep -q "QTE_NETWORK_LAYERS must be libtorch or onednn, got 'fast'" <<<"$err" || fail "$err"

# Another seed or thread count would resume as another run: refused.
err=$(qattn-train --batch 4 --start-after 4 --seed 6 --steps 6 --checkpoint-every 3 --checkpoint-dir "$tmp/b" --resume \
  "$tmp/tr.rec" 2>&1) \
  && fail "resumed with another seed"
grep -q "started with --seed 5; resume it with the same, not 6" <<<"$err" || fail "$err"
err=$(train --steps 6 --checkpoint-every 3 --checkpoint-dir "$tmp/b" --resume --threads 1 "$tmp/tr.rec" 2>&1) \
  && fail "resumed with another thread count"
grep -q "started with --threads 2; resume it with the same, not 1" <<<"$err" || fail "$err"

# Killed mid-run: the last checkpoint is whole and the run resumes from it.
qattn-train "${train_options[@]}" --steps 1000 --checkpoint-every 2 --checkpoint-dir "$tmp/k" "$tmp/tr.rec" 2>/dev/null &
pid=$!
# (any checkpoint from step 4 on: --keep removes the older ones)
for _ in $(seq 600); do ls "$tmp/k" 2>/dev/null | grep -qE "^step-0+([4-9]|[1-9][0-9]+)\.rec$" && break; sleep 0.1; done
kill -9 $pid; wait $pid 2>/dev/null
kill -0 $pid 2>/dev/null && fail "the learner survived kill -9"
stream-dump --summary "$tmp/k/latest.rec" > /dev/null || fail "the checkpoint after a kill is damaged"
ls -a "$tmp/k" | grep -q tmp && fail "temporary files left: $(ls -a "$tmp/k")"
train --steps 5 --checkpoint-dir "$tmp/k" --resume "$tmp/tr.rec" 2> "$tmp/k.log" || fail "resume after kill: $(cat "$tmp/k.log")"
grep -Eq "resumed at step ([2-9]|[1-9][0-9]+) " "$tmp/k.log" || fail "$(cat "$tmp/k.log")"

# Following a replay file being appended to: trains as transitions arrive, stops on request.
stream-cat --head 3 "$tmp/tr.rec" > "$tmp/grow.rec"
qattn-train --follow --pretrain 4 --replay-ratio 1 --start-after 1 --batch 2 --steps 100 --stop-file "$tmp/stop" \
  --checkpoint-dir "$tmp/f" "$tmp/grow.rec" 2> "$tmp/f.log" &
pid=$!
stream-cat "$tmp/tr.rec" | stream-cat --append --output "$tmp/grow.rec"
touch "$tmp/stop"
for _ in $(seq 600); do kill -0 $pid 2>/dev/null || break; sleep 0.1; done
kill -0 $pid 2>/dev/null && { kill $pid; fail "--follow did not stop at --stop-file"; }
wait $pid || fail "follow run: $(cat "$tmp/f.log")"
[ -f "$tmp/f/step-00000004.rec" ] || fail "--pretrain 4 without agent transitions: $(ls "$tmp/f"; cat "$tmp/f.log")"

# --follow is deterministic: a run killed while following the actor, which resumes while
# the actor goes on appending, ends with the bytes of a run that found every chunk there
# from the start (each step learns from the agent transitions the replay ratio needs for it).
for c in 1 2 3; do keyframe --not-demo --seed 1$c --output "$tmp/agent$c.rec" "$tmp/demos.rec" 2>/dev/null || fail "agent $c"; done
follow_options=(--follow --pretrain 2 --replay-ratio 0.5 --start-after 1 --batch 2 --steps 1000 --seed 7
                --checkpoint-every 2)
cat "$tmp/tr.rec" "$tmp/agent1.rec" "$tmp/agent2.rec" "$tmp/agent3.rec" > "$tmp/all.rec"
touch "$tmp/stop-all"
qattn-train "${follow_options[@]}" --stop-file "$tmp/stop-all" --checkpoint-dir "$tmp/fa" "$tmp/all.rec" 2> "$tmp/fa.log" \
  || fail "follow, all at once: $(tail -3 "$tmp/fa.log")"
cp "$tmp/tr.rec" "$tmp/live.rec"
qattn-train "${follow_options[@]}" --stop-file "$tmp/stop-live" --checkpoint-dir "$tmp/fl" "$tmp/live.rec" 2> "$tmp/fl.log" &
pid=$!
stream-cat "$tmp/agent1.rec" | stream-cat --append --output "$tmp/live.rec"
for _ in $(seq 600); do ls "$tmp/fl" 2>/dev/null | grep -qE "^step-0+([4-9]|[1-9][0-9]+)\.rec$" && break; sleep 0.1; done
kill -9 $pid; wait $pid 2>/dev/null
kill -0 $pid 2>/dev/null && fail "the learner survived kill -9"
stream-cat "$tmp/agent2.rec" | stream-cat --append --output "$tmp/live.rec"
qattn-train "${follow_options[@]}" --resume --stop-file "$tmp/stop-live" --checkpoint-dir "$tmp/fl" "$tmp/live.rec" \
  2> "$tmp/fl2.log" &
pid=$!
sleep 1
stream-cat "$tmp/agent3.rec" | stream-cat --append --output "$tmp/live.rec"
touch "$tmp/stop-live"
wait $pid || fail "resumed follow run: $(tail -3 "$tmp/fl2.log")"
grep -q "resumed at step [1-9]" "$tmp/fl2.log" || fail "did not resume: $(cat "$tmp/fl2.log")"
state() { stream-dump --type learner "$1" | grep -E "^  (step|transitions_read|agent_transitions|max_priority) " | tr -s ' ' | tr '\n' ';'; }
cmp -s "$tmp/fa/latest.rec" "$tmp/fl/latest.rec" \
  || fail "a killed and resumed --follow run differs from one that had every chunk: $(state "$tmp/fa/latest.rec") vs" \
          "$(state "$tmp/fl/latest.rec"); $(grep resumed "$tmp/fl2.log"); $(cmp "$tmp/fa/latest.rec" "$tmp/fl/latest.rec")"

# Bad input: other settings, another grid or offset, non-finite loss, missing file, too few transitions.
err=$(train --steps 6 --architecture arm --base-channels 8 --checkpoint-dir "$tmp/a" --resume "$tmp/tr.rec" 2>&1) \
  && fail "another architecture resumed"
grep -q "trained with other settings.*\"architecture\": \"light\"" <<<"$err" || fail "$err"
keyframe --voxels 8 --no-crop-augmentation --seed 1 "$tmp/demos.rec" > "$tmp/tr8.rec" 2>/dev/null  # 12.5 cm voxels: the 0.15 m grid is too small to shift
err=$(train --steps 2 --checkpoint-dir "$tmp/v" "$tmp/tr8.rec" 2>&1) && fail "8-voxel transitions accepted"
grep -q "tr8.rec: record [0-9]* at byte [0-9]*: 'transition' record, field 'voxels': expected 16 voxels" <<<"$err" || fail "$err"
# Keyframed with another --offset: the learner's next-state grids would have other edges.
keyframe --offset 0.2 --seed 1 "$tmp/demos.rec" > "$tmp/tr01.rec" 2>/dev/null
err=$(train --steps 2 --checkpoint-dir "$tmp/o" "$tmp/tr01.rec" 2>&1) && fail "transitions of --offset 0.2 accepted"
grep -q "tr01.rec: record [0-9]* at byte [0-9]*: 'transition' record, field 'depth1.bounds': expected a grid edge of 0.3 m, as the learner's --offset (2 x offset); the transition has 0.4 m" \
  <<<"$err" || fail "$err"
# A fresh run that stops before it saved a trained checkpoint leaves nothing behind (its
# initial checkpoint and metrics file are removed); one that saved trained checkpoints keeps them.
[ ! -e "$tmp/v" ] || fail "a run refused on bad input left $(ls -A "$tmp/v") behind"
err=$(train --steps 40 --lr 1e30 --grad-clip-value 0 --checkpoint-every 1000 --metrics "$tmp/n.csv" \
  --checkpoint-dir "$tmp/n" "$tmp/tr.rec" 2>&1) && fail "a diverging run did not stop"
grep -Eq "step [0-9]*: (non-finite loss|the depth-[0-9] network gave a non-finite Q value).*tr.rec: record [0-9]* at byte.*no trained checkpoint was saved" \
  <<<"$(tail -1 <<<"$err")" || fail "$err"
[ ! -e "$tmp/n" ] && [ ! -e "$tmp/n.csv" ] || fail "a diverged run without a trained checkpoint left files behind"
err=$(train --steps 40 --lr 1e30 --grad-clip-value 0 --checkpoint-every 1 --checkpoint-dir "$tmp/n1" "$tmp/tr.rec" 2>&1) \
  && fail "a diverging run did not stop"
good=$(grep -o "last good checkpoint is [^ )]*" <<<"$err" | sed 's/.* is //')
[ -n "$good" ] && [ -f "$good" ] && [ -f "$tmp/n1/latest.rec" ] || fail "the last good checkpoint was not kept: $err"
err=$(train --steps 2 --checkpoint-dir "$tmp/m" "$tmp/missing.rec" 2>&1) && fail "missing file accepted"
grep -q "missing.rec" <<<"$err" || fail "$err"
[ ! -e "$tmp/m" ] || fail "a missing input left a checkpoint directory"
err=$(qattn-train --steps 2 --start-after 1000 --checkpoint-dir "$tmp/s" "$tmp/tr.rec" 2>&1) && fail "too few transitions"
grep -q "fewer than --start-after 1000" <<<"$err" || fail "$err"
[ ! -e "$tmp/s" ] || fail "too few transitions left a checkpoint directory"
echo "qattn-train ok"
