#!/usr/bin/env bash
# examples/learn.sh under a CPU budget: the actor is paced by the learner (the learner steps a
# run has taken follow from its environment steps and the replay ratio, whatever the machine's
# load), one actor pipeline (one qte-select, one LibTorch start) serves the whole run, the CSV
# splits the processor time by role, and a learner that dies stops the run at once with a line
# naming it, as does a learner that stops making progress (STALL_SECONDS); the run then resumes to its end, its processor and wall-clock accounts kept across
# the kill (saved while it waits, ACCOUNT_EVERY seconds apart, not only before evaluations).
source "$(dirname "$0")/common.sh"
learn=${QTE_SOURCE:?}/examples/learn.sh
run=$tmp/run
# A learner 3 steps per agent transition: without pacing, the actor runs ahead of it.
export SEED=0 DEMOS=2 IMAGE=48x48 ACT_K=1 TARGET_K=0 ENV_STEPS=1000000 CHUNK_EPISODES=2 EVAL_EVERY=1000000 \
  EVAL_EPISODES=1 BATCH=4 PRETRAIN=2 RATIO=3 CHECKPOINT_EVERY=1 START_AFTER=0 CPU_BUDGET=1000000 ACCOUNT_EVERY=1

# 0. The supervision's pacing counts the steps allowed as qattn-train does.
for case in "0 200 0.5" "7 200 0.5" "3343 200 0.1" "1001 0 0.3" "45 2 3" "999999 100 0.7"; do
  read -r n pretrain ratio <<<"$case"
  ours=$("$py" "$QTE_SOURCE/examples/supervise.py" --steps-allowed "$n" --pretrain "$pretrain" --ratio "$ratio")
  [ "$ours" = "$(qattn-train --steps-allowed "$n" --pretrain "$pretrain" --replay-ratio "$ratio")" ] \
    || fail "steps allowed after $n transitions (pretrain $pretrain, ratio $ratio): supervise.py $ours"
done
export PRETRAIN=2 RATIO=3

# 1. Kill the learner once two chunks have ended: the run stops at once, naming it.
bash "$learn" reach_target "$run" 2> "$tmp/learn.log" &
learn_pid=$!
actors=()
for _ in $(seq 1 3000); do
  actors+=($(pgrep -f "qte-select --checkpoint $run/ckpt/latest.rec" || true))
  [ "$(ls "$run"/actors/gate-0/*.steps 2>/dev/null | wc -l)" -ge 2 ] && break
  kill -0 $learn_pid 2>/dev/null || fail "learn.sh ended early: $(tail -5 "$tmp/learn.log")"
  sleep 0.1
done
learner=$(pgrep -f "qattn-train --follow .*$run/replay.rec") || fail "no learner"
kill -9 "$learner"
for _ in $(seq 1 300); do kill -0 $learn_pid 2>/dev/null || break; sleep 0.1; done
kill -0 $learn_pid 2>/dev/null && fail "learn.sh still running 30 s after its learner died"
wait $learn_pid && fail "learn.sh exited 0 after its learner died"
grep -q "the learner (qattn-train, pid $learner) died, killed by signal KILL; last line of $run/train.log: " "$tmp/learn.log" \
  || fail "no line naming the dead learner: $(cat "$tmp/learn.log")"
# The run said at its start what it would do (its settings) and what its evaluations found, in words.
grep -q "reach_target .* seed 0: 2 demonstrations, [0-9]* environment steps in chunks of [0-9]* episodes, .*held-out scenes, processor budget [0-9]* s; networks in " "$tmp/learn.log" \
  || fail "no line of the run's settings: $(head -3 "$tmp/learn.log")"
grep -q "learner step [0-9]*: success [0-9.]* ([0-9]* of [0-9]* held-out episodes, 95% interval" "$tmp/learn.log" \
  || fail "no evaluation in words: $(grep 'learner step' "$tmp/learn.log")"
[ "$(sort -u <<<"${actors[*]// /$'\n'}" | grep -c .)" = 1 ] || fail "qte-select processes: ${actors[*]}"
sleep 1
pgrep -f "$run" > /dev/null && fail "programs of the run still running: $(pgrep -af "$run")"
# The accounts were saved while the chunks ran (the only evaluation came before them): the
# actors' processor time and the wall-clock of the first chunk survive the kill.
[ "$run/cpu_ticks" -nt "$run/actors/gate-0/0000.steps" ] && [ "$run/train_seconds" -nt "$run/actors/gate-0/0000.steps" ] \
  || fail "the accounts were last saved before the first chunk ended: $(ls -l --time-style=full-iso "$run" "$run/actors/gate-0")"
read -r -a saved < "$run/cpu_ticks"
[ "${saved[3]}" -gt 0 ] || fail "no actor time in the saved accounts: ${saved[*]}"

# 2. Resume with a budget this run has nearly spent: it ends by itself, with an evaluation. The
# replay first gets a torn last record, as an append killed half-way leaves: it is cut off.
replay_bytes=$(stat -c %s "$run/replay.rec")
head -c 100 "$run/replay.rec" >> "$run/replay.rec"
spent=$(awk -v t="$(getconf CLK_TCK)" '{ print int(($1 + $2 + $3 + $4 + $5) / t) }' "$run/cpu_ticks")
CPU_BUDGET=$(( spent + 3 )) ALSO_ACT_K=1,2 bash "$learn" reach_target "$run" 2> "$tmp/resume.log" \
  || fail "the resumed run failed: $(tail -5 "$tmp/resume.log")"
grep -q "repaired $run/replay.rec: record [0-9]* at byte $replay_bytes: cut off 100 bytes" "$tmp/resume.log" \
  || fail "the torn record was not cut off: $(grep -i repair "$tmp/resume.log")"
[ -f "$run/eval.csv" ] || fail "no eval.csv"
# The final networks acting with another K as well (ALSO_ACT_K; its own K = 1 is failures.csv).
[ -f "$run/failures.csv" ] && [ -f "$run/failures-act-k2.csv" ] && [ ! -f "$run/failures-act-k1.csv" ] \
  || fail "failure analyses: $(ls "$run")"
# The processor the run ran on, as results_table.py reads it: one line, the resumption on the
# same processor adding none.
awk -F, -v cores="$(nproc)" 'NF < 4 || $1 !~ /^20[0-9-]+T[0-9:]+Z$/ || $(NF - 1) !~ /^(avx512f|avx2|other)$/ || $NF != cores { bad = 1 }
  END { exit bad || NR != 1 }' "$run/machine" || fail "the run's machine record: $(cat "$run/machine")"
# And the toolkit's commit, as qattn-train --version names it, and the precision its networks
# ran in, as qattn-train --print-precision says: one line likewise.
commit=$(qattn-train --version | sed -n 's/.*, commit //p')
precision=$(qattn-train --precision auto --print-precision | cut -d' ' -f1)
[ -n "$commit" ] && [ "$(wc -l < "$run/builds")" = 1 ] && [ "$(cut -d, -f2- "$run/builds")" = "$commit,$precision" ] \
  && grep -Eq '^20[0-9-]+T[0-9:]+Z,[^,]+,(fp32|bf16)$' "$run/builds" || fail "the run's build record: $(cat "$run/builds")"
final=$(tail -1 "$run/eval.csv")
column() { awk -F, -v name="$1" 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i } NR == 2 { print $c[name] }' \
  <(head -1 "$run/eval.csv"; echo "$final"); }
env_steps=$(column env_steps) step=$(column train_step)
# Paced: at the start of the last chunk the learner had every step the replay allowed, and it
# cannot take more than the steps allowed for all the transitions.
last=$(cat "$(ls "$run"/actors/gate-0/*.steps | tail -1)")
low=$(qattn-train --steps-allowed $(( env_steps - last )) --pretrain $PRETRAIN --replay-ratio $RATIO)
high=$(qattn-train --steps-allowed "$env_steps" --pretrain $PRETRAIN --replay-ratio $RATIO)
[ "$step" -ge "$low" ] && [ "$step" -le "$high" ] \
  || fail "learner step $step after $env_steps environment steps (the last chunk $last): expected $low to $high"
# The processor time split by role adds up to cpu_s, and every role has some.
sum=$(awk "BEGIN { print $(column cpu_demos_s) + $(column cpu_pretrain_s) + $(column cpu_learner_s) + $(column cpu_actor_s) + $(column cpu_other_s) }")
awk "BEGIN { exit !($sum - $(column cpu_s) > -1.5 && $sum - $(column cpu_s) < 1.5) }" || fail "roles sum to $sum, cpu_s $(column cpu_s)"
for role in demos pretrain learner actor; do
  awk "BEGIN { exit !($(column "cpu_${role}_s") > 0) }" || fail "no processor time for the role $role: $final"
done
# A resume with other demonstrations' settings than the run's replay was made with is refused,
# naming both, before anything runs: its label would not tell the two apart.
CHAIN_STEPS=episode bash "$learn" reach_target "$run" 2> "$tmp/other.log" && fail "a resume with CHAIN_STEPS=episode ran"
grep -q "learn.sh: $run was started with DEMOS=2 IMAGE=48x48 VARIATION=0 CHAIN_STEPS=reset .*, not DEMOS=2 IMAGE=48x48 VARIATION=0 CHAIN_STEPS=episode" \
  "$tmp/other.log" || fail "no line naming the run's settings: $(cat "$tmp/other.log")"
[ "$(tail -1 "$run/eval.csv")" = "$final" ] || fail "the refused resume changed eval.csv"

# 3. A learner alive but stuck (stopped here with SIGSTOP) while the actor waits for it stops
# the run within STALL_SECONDS, with a line naming it; nothing of the run is left running.
stuck=$tmp/stuck
STALL_SECONDS=5 bash "$learn" reach_target "$stuck" 2> "$tmp/stuck.log" &
stuck_pid=$!
for _ in $(seq 1 3000); do
  [ -f "$stuck/ckpt/latest.rec" ] && break
  kill -0 $stuck_pid 2>/dev/null || fail "learn.sh (stuck) ended early: $(tail -5 "$tmp/stuck.log")"
  sleep 0.1
done
stuck_learner=$(pgrep -f "qattn-train --follow .*$stuck/replay.rec") || fail "no learner (stuck)"
kill -STOP "$stuck_learner"
for _ in $(seq 1 600); do kill -0 $stuck_pid 2>/dev/null || break; sleep 0.1; done
kill -0 $stuck_pid 2>/dev/null && { kill -CONT "$stuck_learner"; fail "learn.sh still waiting 60 s after its learner stopped"; }
wait $stuck_pid && fail "learn.sh exited 0 with a stuck learner"
grep -q "the learner (qattn-train, pid $stuck_learner) made no progress in 5 s" "$tmp/stuck.log" \
  || fail "no line naming the stuck learner: $(tail -3 "$tmp/stuck.log")"
sleep 1
pgrep -f "$stuck" > /dev/null && fail "programs of the stuck run still running: $(pgrep -af "$stuck")"
echo "ok: learner step $step after $env_steps environment steps (allowed $low..$high); cpu $(column cpu_s) s"
