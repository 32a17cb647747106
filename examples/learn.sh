#!/usr/bin/env bash
# The online learning loop of C2F-ARM (+QTE), assembled from the toolkit's programs:
#
#   demo-record | keyframe                      demonstrations -> replay.rec (once)
#   qattn-train --follow replay.rec &           the learner: trains as replay.rec grows,
#                                               writes ckpt/step-N.rec and ckpt/latest.rec
#   sim-step < loop | qte-select --reload | plan-path | tee loop | keyframe --agent --append
#                                               the actor: a closed pipeline through a FIFO;
#                                               every finished episode is appended to replay.rec
#                                               (ACTORS of them at once, each on its own chunk)
#   sim-step | qte-select (greedy) | plan-path | episode-stats
#                                               evaluation on held-out seeds after each chunk
#
# Scenes: demonstrations, exploration and evaluation come from disjoint scene sets by
# construction (--scenes demo / explore / eval); the evaluation scenes are the same for every
# SEED, so seeds and methods are compared on one held-out set.
#
# Usage: learn.sh TASK RUN_DIR   (settings from the environment; see examples/Makefile)
# Resumable: finished chunks and evaluations are kept, the learner resumes from its last
# checkpoint; an interrupted chunk is run again (its finished episodes stay in the replay).
#
# ACTORS=N runs N actor pipelines side by side, each on its own chunk of episodes (chunk c
# explores the scenes of seed SEED * 100000 + c, whichever actor runs it), all appending to
# the one replay file the learner follows (whole records under a lock; an episode's frames
# come before its transitions, and episodes are told apart by their keys). A machine with more
# cores collects experience N times as fast. With N > 1 the order in which episodes reach the
# replay depends on timing, so a run is no longer a function of its seed alone. An actor that
# dies (killed, out of memory) costs only its own chunk: the others finish theirs and the
# chunk is run again in the next round (twice failed: the run stops).
#
# ROLE=learner / ROLE=actor (ACTOR_INDEX=i of ACTORS) split one run over processes that meet
# only through RUN_DIR, for a cluster (examples/slurm/): the learner role records the
# demonstrations, trains and evaluates; actor i runs chunks i, i + ACTORS, ... and appends its
# episodes to its own replay file, actors/replay-i.rec, which the learner follows. No FIFO,
# PID or lock crosses roles; each role is resumable on its own. ROLE=all (the default) is the
# whole loop in this one process tree, as above. CPU_BUDGET is for ROLE=all only.
set -euo pipefail
task=$1 run=$2
: "${SEED:=0}" "${DEMOS:=10}" "${VARIATION:=0}" "${IMAGE:=128x128}" "${ACT_K:=10}" "${TARGET_K:=10}"
: "${ENV_STEPS:=2000}" "${CHUNK_EPISODES:=10}" "${EVAL_EVERY:=250}" "${EVAL_EPISODES:=50}" "${EVAL_SEED:=1000000}"
: "${ARCH:=light}" "${BATCH:=32}" "${RATIO:=0.5}" "${PRETRAIN:=200}" "${START_AFTER:=0}"
: "${LEARNER_THREADS:=1}" "${EPSILON:=0.1}" "${ROTATION_NOISE:=1}" "${CHECKPOINT_EVERY:=25}" "${LABEL:=k$ACT_K-$TARGET_K}"
: "${N_STEP:=1}" "${ACTORS:=1}" "${CPU_BUDGET:=0}" "${K_MARGIN:=0.02}" "${K_MAX:=10}" "${ROLE:=all}" "${ACTOR_INDEX:=0}"
mkdir -p "$run/chunks" "$run/eval"
# Adaptive K (ACT_K or TARGET_K 'auto'): each node expands the voxels within K_MARGIN of its
# best Q, at most K_MAX; the options go only to the programs whose K is 'auto'.
branching() {  # K -> the options that go with it
  if [ "$1" = auto ]; then echo "--k-margin $K_MARGIN --k-max $K_MAX"; fi
}
act_branching=$(branching "$ACT_K") target_branching=$(branching "$TARGET_K")
log() { printf '%s %s\n' "$(date +%H:%M:%S)" "$*" >&2; }
# The time a run spends training, up to each evaluation and summed over resumptions
# (evaluations excluded; an interrupted chunk's time is not counted: the chunk is run again):
# train_s, wall-clock seconds, and cpu_s, the processor seconds of the run's own processes
# (the learner, the actors, the demonstrations), which other work on the machine leaves alone.
clock=$(date +%s) ticks=$(getconf CLK_TCK) eval_ticks=0
cpu_base=$(cat "$run/cpu_seconds" 2>/dev/null || echo 0)
stat_ticks() {  # PID FIELD... : the sum of those fields of /proc/PID/stat (0 once it is gone)
  local stat fields n=0 i
  stat=$(cat "/proc/$1/stat" 2>/dev/null) || { echo 0; return; }
  read -ra fields <<< "${stat##*) }"  # from field 3 on: the command name may hold spaces
  shift
  for i in "$@"; do n=$(( n + fields[i - 3] )); done
  echo "$n"
}
# Learner (utime + stime) and finished children of this shell (cutime + cstime).
run_ticks() { echo $(( $(stat_ticks "$learner" 14 15) + $(stat_ticks $$ 16 17) - eval_ticks )); }
cpu_seconds() { echo $(( cpu_base + $(run_ticks) / ticks )); }
count_training_time() {
  local now; now=$(date +%s)
  echo $(( $(cat "$run/train_seconds" 2>/dev/null || echo 0) + now - clock )) > "$run/train_seconds.tmp"
  mv "$run/train_seconds.tmp" "$run/train_seconds"
  cpu_seconds > "$run/cpu_seconds.tmp"
  mv "$run/cpu_seconds.tmp" "$run/cpu_seconds"
  clock=$now
}
# CPU_BUDGET > 0: a budget in processor seconds as well (1200: the paper's "10 minutes",
# on 2 cores): once it is spent no chunk starts, and the final evaluation takes the learner's
# newest checkpoint as it stands (the learner is not waited for: its speed is part of what
# the budget measures).
out_of_budget() { [ "$CPU_BUDGET" -gt 0 ] && [ "$(cpu_seconds)" -ge "$CPU_BUDGET" ]; }

# One chunk of exploring episodes through the closed loop -> chunks/NNNN.rec; its episodes are
# appended to `actor_replay` as they finish.
actor_replay=$run/replay.rec
[ "$ROLE" != actor ] || actor_replay=$run/actors/replay-$ACTOR_INDEX.rec
run_chunk() {  # CHUNK
  local name fifo seed
  name=$run/chunks/$(printf '%04d' "$1") seed=$((SEED * 100000 + $1))
  fifo=$(mktemp -u); mkfifo "$fifo"
  if ! sim-step --task "$task" --variation "$VARIATION" --episodes "$CHUNK_EPISODES" --seed "$seed" \
      --scenes explore --image-size "$IMAGE" --compress < "$fifo" \
    | qte-select --checkpoint "$run/ckpt/latest.rec" --reload --k "$ACT_K" $act_branching --epsilon "$EPSILON" \
        --rotation-noise "$ROTATION_NOISE" --seed "$seed" --threads 1 2>> "$run/actor.log" \
    | plan-path | tee "$fifo" "$name.partial" \
    | keyframe --agent --seed "$SEED" --append --output "$actor_replay" 2>> "$run/actor.log"; then
    rm -f "$fifo"
    return 1
  fi
  rm -f "$fifo"
  mv "$name.partial" "$name.rec"
}
# Environment steps of the finished chunks (each counted once, into chunks/NNNN.steps; written
# under a name of this process's own, since roles on other nodes count too).
finished_steps() {
  local f n=0
  for f in "$run"/chunks/*.rec; do
    [ -f "$f" ] || continue
    if [ ! -f "${f%.rec}.steps" ]; then
      stream-dump --summary "$f" | awk '$1 == "action" { print $2 }' > "${f%.rec}.steps.$$"
      mv "${f%.rec}.steps.$$" "${f%.rec}.steps"
    fi
    n=$(( n + $(cat "${f%.rec}.steps") ))
  done
  echo "$n"
}

# Actor i of a split run: chunks i, i + ACTORS, ... until the run has its environment steps or
# the learner says it is done; each chunk that fails is tried once more.
if [ "$ROLE" = actor ]; then
  mkdir -p "$run/actors"
  until [ -f "$run/ckpt/latest.rec" ]; do sleep 2; done
  chunk=$ACTOR_INDEX tries=0
  while [ ! -f "$run/actor.done" ] && [ "$(finished_steps)" -lt "$ENV_STEPS" ]; do
    if [ -f "$run/chunks/$(printf '%04d' "$chunk").rec" ] || run_chunk "$chunk"; then
      chunk=$((chunk + ACTORS)) tries=0
    else
      tries=$((tries + 1))
      log "$task $LABEL seed $SEED: actor $ACTOR_INDEX: chunk $chunk failed (attempt $tries)"
      [ "$tries" -lt 2 ] || exit 1
    fi
  done
  log "$task $LABEL seed $SEED: actor $ACTOR_INDEX done"
  exit 0
fi

# 1. Demonstrations -> transitions (once; written under a temporary name, then renamed).
if [ ! -f "$run/replay.rec" ]; then
  log "$task: $DEMOS demonstrations"
  demo-record --task "$task" --episodes "$DEMOS" --seed "$SEED" --scenes demo --variation "$VARIATION" --image-size "$IMAGE" \
    --compress --output "$run/demos.rec" 2>> "$run/demos.log"
  keyframe --seed "$SEED" --output "$run/replay.rec.tmp" "$run/demos.rec" 2>> "$run/demos.log"
  mv "$run/replay.rec.tmp" "$run/replay.rec"
fi

# 2. The learner, in the background for the whole run; with ROLE=learner it follows the
# actors' replay files too (made empty here if no actor has started yet).
inputs=("$run/replay.rec")
if [ "$ROLE" = learner ]; then
  mkdir -p "$run/actors"
  for ((i = 0; i < ACTORS; i++)); do touch "$run/actors/replay-$i.rec"; inputs+=("$run/actors/replay-$i.rec"); done
fi
rm -f "$run/actor.done"
qattn-train --follow --resume --stop-file "$run/actor.done" --replay-ratio "$RATIO" --pretrain "$PRETRAIN" \
  --start-after "$START_AFTER" --steps 1000000 --checkpoint-every "$CHECKPOINT_EVERY" --keep 4 \
  --architecture "$ARCH" --batch "$BATCH" --tree-target "$TARGET_K" $target_branching --n-step "$N_STEP" --seed "$SEED" --threads "$LEARNER_THREADS" \
  --checkpoint-dir "$run/ckpt" --metrics "$run/train.csv" "${inputs[@]}" 2>> "$run/train.log" &
learner=$!
trap 'kill $(jobs -p) 2>/dev/null || true' EXIT  # the learner and any actor still running
while [ ! -f "$run/ckpt/latest.rec" ]; do kill -0 $learner || { tail -2 "$run/train.log"; exit 1; }; sleep 0.5; done

# The learner's newest step, from its checkpoint names.
learner_step() { ls "$run/ckpt" | sed -n 's/^step-0*\([0-9][0-9]*\)\.rec$/\1/p' | sort -n | tail -1; }
# Waits until the learner has taken the steps the replay ratio allows for `agent` transitions.
wait_for_learner() {
  local want; want=$(qattn-train --steps-allowed "$1" --pretrain "$PRETRAIN" --replay-ratio "$RATIO")
  want=$(( want / CHECKPOINT_EVERY * CHECKPOINT_EVERY ))
  while [ "$(learner_step)" -lt "$want" ]; do kill -0 $learner || { tail -2 "$run/train.log"; exit 1; }; sleep 1; done
}
# Greedy episodes of one checkpoint on the held-out seeds -> one CSV row.
# eval_point: the budget the evaluation stands for (0, EVAL_EVERY, ..., ENV_STEPS); env_steps
# (what the actor had taken, up to a chunk more) varies between seeds, eval_point does not.
evaluate() {  # CHECKPOINT ENV_STEPS OUT.csv LEARNER_STEP EVAL_POINT
  local fifo; fifo=$(mktemp -u); mkfifo "$fifo"
  sim-step --task "$task" --variation "$VARIATION" --episodes "$EVAL_EPISODES" --seed "$EVAL_SEED" --scenes eval \
    --image-size "$IMAGE" < "$fifo" \
    | qte-select --checkpoint "$1" --k "$ACT_K" $act_branching --threads 1 \
    | plan-path | tee "$fifo" \
    | episode-stats --label "$LABEL" --column seed="$SEED" --column env_steps="$2" --column train_step="$4" \
        --column eval_point="$5" --column train_s="$(cat "$run/train_seconds")" --column cpu_s="$(cat "$run/cpu_seconds")" \
        > "$3.tmp"
  rm -f "$fifo"
  mv "$3.tmp" "$3"
}

declare -A failures=()
while :; do
  env_steps=$(finished_steps)
  finished=0
  if [ "$env_steps" -ge "$ENV_STEPS" ]; then finished=1; elif out_of_budget; then finished=2; fi
  # Every EVAL_EVERY environment steps and at the end: evaluate what the learner has made of
  # the experience so far, once it has taken the steps the replay ratio allows.
  mark=$(( finished ? 999999 : env_steps / EVAL_EVERY ))
  eval_csv=$run/eval/$(printf '%06d' "$mark").csv
  if [ ! -f "$eval_csv" ]; then
    [ "$finished" = 2 ] || wait_for_learner "$env_steps"
    snapshot=$run/eval/checkpoint.rec
    until step=$(learner_step) && cp "$run/ckpt/step-$(printf '%08d' "$step").rec" "$snapshot" 2>/dev/null; do sleep 0.2; done
    count_training_time
    # eval_point: the budget the evaluation stands for; out of budget, the steps it bought.
    point=$(( finished == 2 ? env_steps : finished ? ENV_STEPS : mark * EVAL_EVERY ))
    before=$(stat_ticks $$ 16 17)
    evaluate "$snapshot" "$env_steps" "$eval_csv" "$step" "$point"
    eval_ticks=$(( eval_ticks + $(stat_ticks $$ 16 17) - before ))
    clock=$(date +%s)
    log "$task $LABEL seed $SEED: env steps $env_steps, learner step $step: $(tail -1 "$eval_csv")"
  fi
  [ "$finished" = 0 ] || break
  # A split run's learner: the actors (elsewhere) add chunks; look again in a while.
  if [ "$ROLE" = learner ]; then sleep 5; continue; fi

  # One round: the next ACTORS chunks not yet finished, side by side.
  round=() chunk=0
  while [ "${#round[@]}" -lt "$ACTORS" ]; do
    [ -f "$run/chunks/$(printf '%04d' "$chunk").rec" ] || round+=("$chunk")
    chunk=$((chunk + 1))
  done
  pids=()
  for c in "${round[@]}"; do run_chunk "$c" & pids+=($!); done
  for i in "${!round[@]}"; do
    c=${round[$i]}
    if ! wait "${pids[$i]}"; then
      failures[$c]=$(( ${failures[$c]:-0} + 1 ))
      log "$task $LABEL seed $SEED: the actor of chunk $c failed (attempt ${failures[$c]}); its finished episodes stay in the replay"
      [ "${failures[$c]}" -lt 2 ] || { log "chunk $c failed twice: stopping"; exit 1; }
    fi
  done
done
touch "$run/actor.done"
# Out of budget: the learner would go on to the steps the replay allows, past the budget and
# never evaluated; stop it (its checkpoints are whole files, written under temporary names).
[ "$finished" != 2 ] || kill $learner 2>/dev/null || true
wait $learner || true
trap - EXIT
cat "$run"/eval/*.csv | awk 'NR == 1 || !/^label/' > "$run/eval.csv"
# Where the final networks' agent goes on the evaluation scenes, beside the expert on the same
# scenes (failure_reasons.sh: the last evaluation's episodes again, deterministic).
if [ ! -f "$run/failures.csv" ]; then
  VARIATION=$VARIATION EVAL_SEED=$EVAL_SEED bash "$(dirname "$0")/failure_reasons.sh" "$task" "$run/eval/checkpoint.rec" \
    "$ACT_K" "$IMAGE" "$EVAL_EPISODES" "$LABEL" "$SEED" $act_branching > "$run/failures.csv.tmp" 2>> "$run/actor.log" \
    && mv "$run/failures.csv.tmp" "$run/failures.csv" || log "$task $LABEL seed $SEED: no failure analysis (see actor.log)"
fi
log "$task $LABEL seed $SEED: done; $run/eval.csv"
