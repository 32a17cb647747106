#!/usr/bin/env bash
# The online learning loop of C2F-ARM (+QTE), assembled from the toolkit's programs:
#
#   demo-record | keyframe                      demonstrations -> replay.rec (once)
#   qattn-train --follow replay.rec &           the learner: trains as replay.rec grows,
#                                               writes ckpt/step-N.rec and ckpt/latest.rec
#   sim-step --gate < loop | qte-select --reload | plan-path | tee loop | keyframe --agent --append
#                                               the actor: a closed pipeline through a FIFO, up
#                                               for the whole run, running chunks of episodes as
#                                               the loop opens them; every finished episode is
#                                               appended to replay.rec (ACTORS of them at once)
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
# A learner that dies stops the run at once with a line naming it, how it ended and its last
# log line; so does a chunk whose actor fails twice.
#
# ACTORS=N runs N actor pipelines side by side, each on its own chunk of episodes (chunk c
# explores the scenes of seed SEED * 100000 + c, whichever actor runs it), all appending to
# the one replay file the learner follows (whole records under a lock; an episode's frames
# come before its transitions, and episodes are told apart by their keys). A machine with more
# cores collects experience N times as fast. The learner and the actors run side by side, so
# which checkpoint acts in an episode and which transitions a batch draws depend on timing:
# a run's counts of steps follow from its settings and seed, its bytes do not. An actor that
# dies (killed, out of memory) costs only its own chunk: it is started again on that chunk
# (twice failed: the run stops).
#
# ROLE=learner / ROLE=actor (ACTOR_INDEX=i of ACTORS) split one run over processes that meet
# only through RUN_DIR, for a cluster (examples/slurm/): the learner role records the
# demonstrations, trains and evaluates; actor i runs chunks i, i + ACTORS, ... and appends its
# episodes to its own replay file, actors/replay-i.rec, which the learner follows. No FIFO,
# PID or lock crosses roles; each role is resumable on its own. ROLE=all (the default) is the
# whole loop in this one process tree, as above. CPU_BUDGET is for ROLE=all only.
#
# LABEL names the run in its CSVs; by default run_label (common.sh) of METHOD (qte), ACT_K,
# TARGET_K, K_MARGIN and K_MAX, as examples/Makefile labels its runs.
#
# NET_OPTIONS: the coarse-to-fine hierarchy when not the published one, for keyframe and the
# learner alike (e.g. "--depths 3 --offset 0.15,0.05"; qte-select takes it from the checkpoint).
# PRECISION: the networks' arithmetic, qattn-train's and qte-select's --precision (auto, fp32 or
# bf16); the builds file records what the learner ran in.
# PLAN_OPTIONS: plan-path's options for the agent's moves, in training and in every evaluation
# (e.g. "--approach 0.1": grasps end in a straight descent along the tool axis; plan-path(1)).
#
# A real robot (docs/real-world.md): STAGE is the world the agent acts in, a program with its
# options (quoted words stay together): the simulator at IMAGE by default, or robot-step with
# its spool, camera and judge; EVAL_STAGE the world of the evaluations (STAGE by default).
# DEMOS_FROM=FILE takes the demonstrations from recorded ones (obs-pack) instead of the
# simulator's expert; TIME_BUDGET=S stops starting chunks after S seconds of wall-clock
# training (evaluations excluded), paced like CPU_BUDGET: the paper's "10 minutes" on a robot.
set -euo pipefail
task=$1 run=$2
source "$(dirname "$0")/common.sh"
source "$(dirname "$0")/settings.sh"
settings_load learn.sh  # settings.txt: defaults, checks, misspellings refused
# The task, known to the simulator (a real robot's runs name theirs freely).
if [[ $STAGE == sim-step* ]] && ! sim-step --list-tasks | cut -f1 | grep -x -- "$task" > /dev/null; then
  echo "learn.sh: $task is not a task (sim-step --list-tasks: $(sim-step --list-tasks | cut -f1 | xargs | tr ' ' ,))" >&2
  exit 2
fi
export PLAN_OPTIONS  # failure_reasons.sh plans the final agent's moves the same way
eval "stage=($STAGE)"
eval "eval_stage=($EVAL_STAGE)"
mkdir -p "$run/actors" "$run/eval"
# The planner's options are the run's own: kept in it, so that a resumed run and every later
# replay of its agent (failures_of_runs.sh) plan as it did.
if [ -f "$run/plan_options" ]; then
  [ "$(cat "$run/plan_options")" = "$PLAN_OPTIONS" ] || {
    echo "learn.sh: $run was started with PLAN_OPTIONS='$(cat "$run/plan_options")', not '$PLAN_OPTIONS'" >&2; exit 2; }
else
  echo "$PLAN_OPTIONS" > "$run/plan_options"
fi
# The processor the run ran on, a line (started_utc,model,vector_isa,cores) when a start finds
# another than the last line names (a run resumed elsewhere): under CPU_BUDGET a faster
# processor buys more learner steps, so comparisons pair runs made on one kind. Actors of a
# split run (ROLE=actor) leave it to the learner's side.
cpu_field() { sed -n "s/^$1[[:space:]]*: //p" /proc/cpuinfo 2>/dev/null | head -n1; }
vector_isa=$(grep -m1 -ow 'avx512f\|avx2' /proc/cpuinfo 2>/dev/null | sort | tail -n1 || true)
model=$(cpu_field 'model name')
processor="${model:-$(uname -m)} (family $(cpu_field 'cpu family') model $(cpu_field model)),${vector_isa:-other},$(nproc)"
if [ "$ROLE" != actor ] && [ "$(tail -n1 "$run/machine" 2>/dev/null | cut -d, -f2-)" != "$processor" ]; then
  echo "$(date -u +%FT%TZ),$processor" >> "$run/machine"
fi
# The toolkit built (its --version's commit) and the precision its networks run in here, a line
# (started_utc,commit,precision) likewise when a start finds another: a run resumed with another
# build or precision says so.
build=$(qattn-train --version | sed -n 's/.*, commit //p'),$(qattn-train --architecture "$ARCH" $NET_OPTIONS \
  --batch "$BATCH" --precision "$PRECISION" --print-precision | cut -d' ' -f1)
if [ "$ROLE" != actor ] && [ "$(tail -n1 "$run/builds" 2>/dev/null | cut -d, -f2-)" != "$build" ]; then
  echo "$(date -u +%FT%TZ),$build" >> "$run/builds"
fi
# The script's own waiting costs no process (it is counted in the budget, and a method that
# takes longer would pay more for it): a read with a timeout on a FIFO nobody writes.
[ -p "$run/actors/.tick" ] || mkfifo "$run/actors/.tick"
exec {tick}<> "$run/actors/.tick"
nap() { read -r -t "$1" -u "$tick" _ || true; keep_accounts; }
# Adaptive K (ACT_K or TARGET_K 'auto'): each node expands the voxels within K_MARGIN of its
# best Q, at most K_MAX; the options go only to the programs whose K is 'auto'.
branching() {  # K -> the options that go with it
  if [ "$1" = auto ]; then echo "--k-margin $K_MARGIN --k-max $K_MAX"; fi
}
act_branching=$(branching "$ACT_K") target_branching=$(branching "$TARGET_K")
log() { printf '%s %s\n' "$(date +%H:%M:%S)" "$*" >&2; }
# An evaluation's row (episode-stats' CSV, header first) in words.
evaluation_summary() {  # CSV
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) col[$i] = i; next }
           { printf "success %s (%s of %s held-out episodes, 95%% interval %.2f-%.2f), %s s of training", \
                    $col["success_rate"], $col["successes"], $col["episodes"], $col["ci95_low"], $col["ci95_high"], \
                    $col["train_s"] }' "$1"
}
# Processor time of the run, split by role, summed over resumptions (evaluations and the failure
# analysis excluded), in ticks in cpu_ticks ("demos pretrain learner actor other"): demos,
# the demonstrations; pretrain and learner, the learner process before and after step
# PRETRAIN; actor, the actor pipelines; other, this script and the programs it calls.
# train_s: wall-clock seconds up to each evaluation (evaluations excluded). Both are saved
# before each evaluation and every ACCOUNT_EVERY seconds while the run waits, so a run killed
# and resumed loses at most that much of either (and a processor budget stays a budget).
clock=$(date +%s) ticks=$(getconf CLK_TCK) learner= pretraining=0
cpu_base=(0 0 0 0 0)
[ ! -f "$run/cpu_ticks" ] || read -r -a cpu_base < "$run/cpu_ticks"
demos_ticks=0 eval_ticks=0 pretrain_ticks=0 reaped_actor_ticks=0
declare -A actor_pids=() actor_ticks=()
stat_ticks() {  # PID FIELD... : the sum of those fields of /proc/PID/stat (0 once it is gone)
  local stat fields n=0 i
  stat=$(cat "/proc/$1/stat" 2>/dev/null) || { echo 0; return; }
  read -ra fields <<< "${stat##*) }"  # from field 3 on: the command name may hold spaces
  shift
  for i in "$@"; do n=$(( n + fields[i - 3] )); done
  echo "$n"
}
tree_ticks() {  # PID: its processor ticks and those of its live descendants (with what they reaped)
  local n c
  n=$(stat_ticks "$1" 14 15 16 17)
  for c in $(pgrep -P "$1"); do n=$(( n + $(tree_ticks "$c") )); done
  echo "$n"
}
shell_ticks() { stat_ticks $$ 14 15 16 17; }  # this script and every child it has reaped
cpu_roles() {  # -> ticks of "demos pretrain learner actor other", this run so far
  local learner_now pretrain i actors=$reaped_actor_ticks reaped=$reaped_actor_ticks
  learner_now=$(stat_ticks "$learner" 14 15)
  pretrain=$(( pretraining ? learner_now : pretrain_ticks ))  # the learner's ticks up to step PRETRAIN
  for i in "${!actor_pids[@]}"; do  # an actor that has ended is in shell_ticks with its last reading
    if kill -0 "${actor_pids[$i]}" 2>/dev/null; then actor_ticks[$i]=$(tree_ticks "${actor_pids[$i]}")
    else reaped=$(( reaped + ${actor_ticks[$i]:-0} )); fi
    actors=$(( actors + ${actor_ticks[$i]:-0} ))
  done
  echo $(( cpu_base[0] + demos_ticks )) $(( cpu_base[1] + pretrain )) \
    $(( cpu_base[2] + learner_now - pretrain )) $(( cpu_base[3] + actors )) \
    $(( cpu_base[4] + $(shell_ticks) - eval_ticks - demos_ticks - reaped ))
}
cpu_seconds() { cpu_roles | awk -v t="$ticks" '{ print int(($1 + $2 + $3 + $4 + $5) / t) }'; }
# train_s at time $1: what train_seconds holds plus the seconds since it was last counted.
train_seconds_at() { echo $(( $(cat "$run/train_seconds" 2>/dev/null || echo 0) + $1 - clock )); }
count_training_time() {
  local now; now=$(date +%s)
  train_seconds_at "$now" > "$run/train_seconds.tmp"
  mv "$run/train_seconds.tmp" "$run/train_seconds"
  cpu_roles > "$run/cpu_ticks.tmp"
  mv "$run/cpu_ticks.tmp" "$run/cpu_ticks"
  clock=$now
}
# From the waits (nap): the times so far, ACCOUNT_EVERY seconds after they were last counted
# (clock). A split run's actor keeps none (the learner's side keeps the run's).
keep_accounts() {
  [ "$ROLE" != actor ] && [ $(( EPOCHSECONDS - clock )) -ge "$ACCOUNT_EVERY" ] || return 0
  count_training_time
}
# The CSV columns of the processor time: cpu_s, then cpu_<role>_s.
cpu_columns() {
  awk -v t="$ticks" '{ printf "--column cpu_s=%d --column cpu_demos_s=%.1f --column cpu_pretrain_s=%.1f", ($1 + $2 + $3 + $4 + $5) / t, $1 / t, $2 / t
                       printf " --column cpu_learner_s=%.1f --column cpu_actor_s=%.1f --column cpu_other_s=%.1f\n", $3 / t, $4 / t, $5 / t }' "$run/cpu_ticks"
}
# CPU_BUDGET > 0: a budget in processor seconds as well (1200: the paper's "10 minutes",
# on 2 cores). The actor is paced by the learner: before each chunk it waits for the learner
# steps the replay ratio allows, so a run's environment and learner steps follow from its
# settings and seed, not from how the machine shares its cores. Once the budget is spent no
# chunk starts, and the final evaluation takes the learner's newest checkpoint as it stands.
out_of_budget() {
  { [ "$CPU_BUDGET" -gt 0 ] && [ "$(cpu_seconds)" -ge "$CPU_BUDGET" ]; } ||
    { [ "$TIME_BUDGET" -gt 0 ] && [ "$(train_seconds_at "$(date +%s)")" -ge "$TIME_BUDGET" ]; }
}
budgeted() { [ "$CPU_BUDGET" -gt 0 ] || [ "$TIME_BUDGET" -gt 0 ]; }

# A process that ended, in words: "exit status N" or "killed by signal NAME".
describe_status() {
  if [ "$1" -gt 128 ]; then echo "killed by signal $(kill -l $(( $1 - 128 )) 2>/dev/null || echo $(( $1 - 128 )))"
  else echo "exit status $1"; fi
}
# The learner must live as long as the run: once it has died the run stops at once, naming it
# (resumable like any interrupted run: the learner goes on from its newest checkpoint).
check_learner() {
  [ -n "$learner" ] || return 0  # a split run's actor: the learner runs elsewhere
  kill -0 "$learner" 2>/dev/null && return 0
  local status=0
  wait "$learner" 2>/dev/null || status=$?
  log "$task $LABEL seed $SEED: the learner (qattn-train, pid $learner) died, $(describe_status "$status"); last line of $run/train.log: $(tail -1 "$run/train.log")"
  exit 1
}
# A learner alive but making no progress while the run waits for it (stopped, or waiting for
# input that cannot come) stops the run too: STALL_SECONDS without a new checkpoint or a new
# line in train.csv or train.log. watch_learner_from_now starts each wait's clock.
watch_learner_from_now() { stall_mark="" stall_since=$SECONDS; }
check_progress() {
  check_learner
  [ -n "$learner" ] || return 0
  local mark; mark="$(newest_checkpoint_step "$run/ckpt") $({ stat -c %s "$run/train.csv" "$run/train.log" 2>/dev/null || true; } | xargs)"
  if [ "$mark" != "$stall_mark" ]; then stall_mark=$mark stall_since=$SECONDS; return 0; fi
  [ $(( SECONDS - stall_since )) -ge "$STALL_SECONDS" ] || return 0
  log "$task $LABEL seed $SEED: the learner (qattn-train, pid $learner) made no progress in $STALL_SECONDS s (no new checkpoint, no new line in train.csv or train.log; STALL_SECONDS); stopping the run; last line of $run/train.log: $(tail -1 "$run/train.log")"
  kill -CONT "$learner" 2>/dev/null  # a stopped learner must see the kill that ends the run
  exit 1
}
kill_tree() {  # PID...: each process and its descendants, children first
  local p
  for p in "$@"; do kill_tree $(pgrep -P "$p"); kill "$p" 2>/dev/null || true; done
}

# The actor pipelines. Each stays up for the whole run (LibTorch starts once per actor): a
# closed loop through a FIFO that runs chunks of CHUNK_EPISODES exploring episodes, actor i
# the chunks i, i + ACTORS, ... (chunk c explores the scenes of seed SEED * 100000 + c,
# whichever actor runs it). sim-step starts chunk c once actors/gate-i/cccc.go exists and
# writes actors/gate-i/cccc.steps when it has ended; qte-select takes up each new checkpoint at
# the start of an episode; every finished episode is appended to `actor_replay` at once. Only
# trajectories go back to sim-step, so a pipeline waiting at its gate holds nothing in flight.
actor_replay=$run/replay.rec
[ "$ROLE" != actor ] || actor_replay=$run/actors/replay-$ACTOR_INDEX.rec
# A run killed while an episode was being appended leaves a torn last record in the replay; the
# run is the file's only writer, so on resume the torn record is cut off (its chunk runs again)
# and the cut is logged, instead of every later append being refused.
repair_replay() {  # FILE
  local said
  [ -s "$1" ] || return 0
  said=$(stream-cat --append --repair --output "$1" /dev/null 2>&1) || { log "$said"; exit 1; }
  [ -z "$said" ] || log "$task $LABEL seed $SEED: $said"
}
gate_dir() { echo "$run/actors/gate-$1"; }  # ACTOR
chunk_done() { [ -f "$(gate_dir $(( $1 % ACTORS )))/$(printf '%04d' "$1").steps" ]; }  # CHUNK
next_chunk() {  # ACTOR -> its first chunk not finished
  local c=$1
  while chunk_done "$c"; do c=$(( c + ACTORS )); done
  echo "$c"
}
# Environment steps of the finished chunks.
finished_steps() { { cat "$run"/actors/gate-*/[0-9]*.steps 2>/dev/null || true; } | awk '{ n += $1 } END { print n + 0 }'; }
actor_programs=("${stage[0]}" qte-select plan-path tee keyframe)
start_actor() {  # ACTOR: its pipeline, in the background, from its first chunk not finished
  local i=$1 gate
  gate=$(gate_dir "$i")
  mkdir -p "$gate"
  rm -f "$run/actors/status-$i"
  (
    set +e  # the status of every program is what this subshell is for
    agent_loop --only-trajectories-back "$run/actors/loop-$i" \
      "${stage[@]}" --task "$task" --variation "$VARIATION" --episodes 10000000 --seed $(( SEED * 100000 )) --scenes explore \
        --chunk-episodes "$CHUNK_EPISODES" --first-chunk "$(next_chunk "$i")" --chunk-stride "$ACTORS" --gate "$gate" --compress \
      qte-select --checkpoint "$run/ckpt/latest.rec" --reload --k "$ACT_K" $act_branching --epsilon "$EPSILON" \
        --rotation-noise "$ROTATION_NOISE" --seed $(( SEED * 100000 + i )) --threads 1 --precision "$PRECISION" \
      plan-path $PLAN_OPTIONS \
      '|' keyframe --agent --seed "$SEED" $NET_OPTIONS --append --output "$actor_replay"
    echo "${agent_loop_status[*]}" > "$run/actors/status-$i"
  ) 2>> "$run/actor.log" &
  actor_pids[$i]=$!
}
# An actor whose pipeline has ended while its chunk was running: which program failed, how.
actor_failure() {  # ACTOR
  local status=() k
  read -r -a status < "$run/actors/status-$1" 2>/dev/null || { echo "its pipeline was killed"; return; }
  for k in "${!status[@]}"; do
    [ "${status[$k]}" = 0 ] || { echo "${actor_programs[$k]} $(describe_status "${status[$k]}")"; return; }
  done
  echo "its pipeline ended before the chunk did"
}
# Opens the chunks CHUNK... and waits until each has ended, watching the learner and the
# actors: a dead learner stops the run; a dead actor is started again on its chunk (the
# chunk's finished episodes stay in the replay), and a chunk that fails twice stops the run.
declare -A failures=()
run_round() {  # CHUNK...
  local c i pending
  for c in "$@"; do touch "$(gate_dir $(( c % ACTORS )))/$(printf '%04d' "$c").go"; done
  while :; do
    pending=0
    for c in "$@"; do
      chunk_done "$c" && continue
      pending=1
      i=$(( c % ACTORS ))
      kill -0 "${actor_pids[$i]}" 2>/dev/null && continue
      wait "${actor_pids[$i]}" 2>/dev/null || true
      chunk_done "$c" && continue
      failures[$c]=$(( ${failures[$c]:-0} + 1 ))
      reaped_actor_ticks=$(( reaped_actor_ticks + ${actor_ticks[$i]:-0} )); actor_ticks[$i]=0
      log "$task $LABEL seed $SEED: actor $i failed in chunk $c (attempt ${failures[$c]}): $(actor_failure "$i"); last line of $run/actor.log: $(grep -v '^ *[0-9]* Done ' "$run/actor.log" | tail -1)"
      [ "${failures[$c]}" -lt 2 ] || { log "chunk $c failed twice: stopping"; exit 1; }
      start_actor "$i"
    done
    [ "$pending" = 1 ] || return 0
    check_learner
    nap 0.2
  done
}
stop_actors() {  # at a chunk boundary: every actor ends its pipeline
  local i
  for i in "${!actor_pids[@]}"; do touch "$(gate_dir "$i")/stop"; done
  for i in "${!actor_pids[@]}"; do wait "${actor_pids[$i]}" 2>/dev/null || true; done
}

# Actor i of a split run: chunks i, i + ACTORS, ... until the run has its environment steps or
# the learner says it is done.
if [ "$ROLE" = actor ]; then
  mkdir -p "$run/actors"
  until [ -f "$run/ckpt/latest.rec" ]; do nap 2; done
  rm -f "$(gate_dir "$ACTOR_INDEX")"/*.go "$(gate_dir "$ACTOR_INDEX")/stop"
  repair_replay "$actor_replay"
  trap 'kill_tree "${actor_pids[@]}"' EXIT
  start_actor "$ACTOR_INDEX"
  chunk=$(next_chunk "$ACTOR_INDEX")
  while [ ! -f "$run/actor.done" ] && [ "$(finished_steps)" -lt "$ENV_STEPS" ]; do
    run_round "$chunk"
    chunk=$(( chunk + ACTORS ))
  done
  stop_actors
  trap - EXIT
  log "$task $LABEL seed $SEED: actor $ACTOR_INDEX done"
  exit 0
fi

# What this run will do, and how long the committed runs of the same task and label trained
# (examples/results/, the last evaluation's train_s: wall-clock with evaluations excluded).
committed_minutes() {
  local files=("$(dirname "$0")"/results/*/"${task}_${LABEL}"-seed*.csv)
  [ -f "${files[0]}" ] || return 0
  awk -F, 'FNR == 1 { split("", col); for (i = 1; i <= NF; i++) col[$i] = i; next }
           { last[FILENAME] = $col["train_s"] }
           END { for (f in last) if (last[f] > 0) print last[f] / 60 }' "${files[@]}" | sort -n \
    | awk '{ t[NR] = $1 } END { if (NR) printf "%.0f min (median of %d committed runs)", t[int((NR + 1) / 2)], NR }'
}
if [ "$ROLE" != actor ] && [ ! -f "$run/eval.csv" ]; then
  log "$task $LABEL seed $SEED: $DEMOS demonstrations, $ENV_STEPS environment steps in chunks of $CHUNK_EPISODES episodes, $PRETRAIN pretraining steps then $RATIO learner steps per agent transition (batch $BATCH, $N_STEP-step targets, tree target K = $TARGET_K), acting with K = $ACT_K; evaluated every $EVAL_EVERY steps on $EVAL_EPISODES held-out scenes${CPU_BUDGET:+, processor budget $CPU_BUDGET s}; networks in $PRECISION${NET_OPTIONS:+, $NET_OPTIONS}"
  expected=$(committed_minutes)
  [ -z "$expected" ] || log "$task $LABEL: the committed runs trained for $expected on 2 cores, evaluations excluded"
fi

# 1. Demonstrations -> transitions (once; written under a temporary name, then renamed).
if [ ! -f "$run/replay.rec" ]; then
  before=$(shell_ticks)
  if [ -n "$DEMOS_FROM" ]; then
    log "$task: the recorded demonstrations of $DEMOS_FROM"
    stream-cat --output "$run/demos.rec" "$DEMOS_FROM" 2>> "$run/demos.log"
  else
    log "$task: $DEMOS demonstrations"
    demo-record --task "$task" --episodes "$DEMOS" --seed "$SEED" --scenes demo --variation "$VARIATION" --image-size "$IMAGE" \
      --compress --output "$run/demos.rec" 2>> "$run/demos.log"
  fi
  keyframe --seed "$SEED" $NET_OPTIONS --output "$run/replay.rec.tmp" "$run/demos.rec" 2>> "$run/demos.log"
  mv "$run/replay.rec.tmp" "$run/replay.rec"
  demos_ticks=$(( $(shell_ticks) - before ))
fi

# 2. The learner, in the background for the whole run; with ROLE=learner it follows the
# actors' replay files too (made empty here if no actor has started yet).
repair_replay "$run/replay.rec"
inputs=("$run/replay.rec")
if [ "$ROLE" = learner ]; then
  mkdir -p "$run/actors"
  for ((i = 0; i < ACTORS; i++)); do touch "$run/actors/replay-$i.rec"; inputs+=("$run/actors/replay-$i.rec"); done
fi
rm -f "$run/actor.done"
# Pretraining happens in this process tree if the learner starts before step PRETRAIN (it may
# be over before the first checkpoint is seen).
pretraining=$(( $(newest_checkpoint_step "$run/ckpt") < PRETRAIN ))
qattn-train --follow --resume --stop-file "$run/actor.done" --replay-ratio "$RATIO" --pretrain "$PRETRAIN" \
  --start-after "$START_AFTER" --steps 1000000 --checkpoint-every "$CHECKPOINT_EVERY" --keep 4 \
  --architecture "$ARCH" $NET_OPTIONS --batch "$BATCH" --tree-target "$TARGET_K" $target_branching --n-step "$N_STEP" --seed "$SEED" --threads "$LEARNER_THREADS" \
  --precision "$PRECISION" \
  --checkpoint-dir "$run/ckpt" --metrics "$run/train.csv" "${inputs[@]}" 2>> "$run/train.log" &
learner=$!
trap 'kill_tree $(jobs -p)' EXIT  # the learner and the actors, with every program they started
watch_learner_from_now
while [ ! -f "$run/ckpt/latest.rec" ]; do check_progress; nap 0.5; done

# The learner's newest step, from its checkpoint names.
learner_step() { newest_checkpoint_step "$run/ckpt"; }
# Waits until the learner has taken the steps the replay ratio allows for `agent` transitions.
# The gradient steps the replay ratio allows after N agent transitions: what
# `qattn-train --steps-allowed N` prints (a test holds the two equal), without the second it
# takes LibTorch to start, once per chunk.
steps_allowed() { awk -v n="$1" -v p="$PRETRAIN" -v r="$RATIO" 'BEGIN { printf "%d\n", p + int(r * n) }'; }
wait_for_learner() {
  local want; want=$(steps_allowed "$1")
  want=$(( want / CHECKPOINT_EVERY * CHECKPOINT_EVERY ))
  watch_learner_from_now
  while [ "$(learner_step)" -lt "$want" ]; do check_progress; nap 0.5; done
  # Pretraining ends at step PRETRAIN (the first evaluation waits for it when PRETRAIN is a
  # multiple of CHECKPOINT_EVERY; otherwise up to a checkpoint interval of training counts too).
  if [ "$pretraining" = 1 ] && [ "$(learner_step)" -ge "$PRETRAIN" ]; then
    pretrain_ticks=$(stat_ticks "$learner" 14 15) pretraining=0
  fi
}
# Greedy episodes of one checkpoint on the held-out seeds -> one CSV row.
# eval_point: the budget the evaluation stands for (0, EVAL_EVERY, ..., ENV_STEPS); env_steps
# (what the actor had taken, up to a chunk more) varies between seeds, eval_point does not.
evaluate() {  # CHECKPOINT ENV_STEPS OUT.csv LEARNER_STEP EVAL_POINT
  local fifo; fifo=$(mktemp -u)
  agent_loop "$fifo" \
    "${eval_stage[@]}" --task "$task" --variation "$VARIATION" --episodes "$EVAL_EPISODES" --seed "$EVAL_SEED" --scenes eval \
    qte-select --checkpoint "$1" --k "$ACT_K" $act_branching --threads 1 --precision "$PRECISION" \
    plan-path $PLAN_OPTIONS \
    '|' episode-stats --label "$LABEL" --column seed="$SEED" --column env_steps="$2" --column train_step="$4" \
      --column eval_point="$5" --column train_s="$(cat "$run/train_seconds")" $(cpu_columns) \
    > "$3.tmp"
  rm -f "$fifo"
  mv "$3.tmp" "$3"
}

# The actors, waiting at their gates (stale gates of an interrupted run removed).
mkdir -p "$run/actors"
rm -f "$run"/actors/gate-*/*.go "$run"/actors/gate-*/stop
if [ "$ROLE" = all ]; then for ((i = 0; i < ACTORS; i++)); do start_actor "$i"; done; fi
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
    until step=$(learner_step) && cp "$(checkpoint_path "$run/ckpt" "$step")" "$snapshot" 2>/dev/null; do nap 0.2; done
    count_training_time
    # eval_point: the budget the evaluation stands for; out of budget, the steps it bought.
    point=$(( finished == 2 ? env_steps : finished ? ENV_STEPS : mark * EVAL_EVERY ))
    before=$(shell_ticks)
    evaluate "$snapshot" "$env_steps" "$eval_csv" "$step" "$point"
    eval_ticks=$(( eval_ticks + $(shell_ticks) - before ))
    clock=$(date +%s)
    log "$task $LABEL seed $SEED: env steps $env_steps, learner step $step: $(evaluation_summary "$eval_csv")"
  fi
  [ "$finished" = 0 ] || break
  # A split run's learner: the actors (elsewhere) add chunks; look again in a while.
  if [ "$ROLE" = learner ]; then check_learner; nap 5; continue; fi

  # Under a budget, the actor is paced by the learner (see out_of_budget).
  if budgeted; then
    wait_for_learner "$env_steps"
    if out_of_budget; then continue; fi
  fi
  # One round: the chunks of the lowest round not finished, side by side.
  first=0
  while chunk_done "$first"; do first=$(( first + 1 )); done
  round=()
  for ((c = first / ACTORS * ACTORS; c < (first / ACTORS + 1) * ACTORS; c++)); do chunk_done "$c" || round+=("$c"); done
  run_round "${round[@]}"
done
stop_actors
touch "$run/actor.done"
# Out of budget: the learner would go on to the steps the replay allows, past the budget and
# never evaluated; stop it (its checkpoints are whole files, written under temporary names).
[ "$finished" != 2 ] || kill $learner 2>/dev/null || true
wait $learner || true
trap - EXIT
cat "$run"/eval/*.csv | awk 'NR == 1 || !/^label/' > "$run/eval.csv"
# Where the final networks' agent goes on the evaluation scenes, beside the expert on the same
# scenes (failure_reasons.sh: the last evaluation's episodes again, deterministic).
# The simulator's analysis: not for a real robot's runs.
if [ "${stage[0]}" = sim-step ] && [ ! -f "$run/failures.csv" ]; then
  VARIATION=$VARIATION EVAL_SEED=$EVAL_SEED bash "$(dirname "$0")/failure_reasons.sh" "$task" "$run/eval/checkpoint.rec" \
    "$ACT_K" "$IMAGE" "$EVAL_EPISODES" "$LABEL" "$SEED" $act_branching > "$run/failures.csv.tmp" 2>> "$run/actor.log" \
    && mv "$run/failures.csv.tmp" "$run/failures.csv" || log "$task $LABEL seed $SEED: no failure analysis (see actor.log)"
fi
# ALSO_ACT_K=K[,K...]: the final networks acting with other K as well (trained with one method,
# acting with another), each into failures-act-kK.csv.
for k in ${ALSO_ACT_K//,/ }; do
  [ "${stage[0]}" = sim-step ] && [ "$k" != "$ACT_K" ] && [ ! -f "$run/failures-act-k$k.csv" ] || continue
  VARIATION=$VARIATION EVAL_SEED=$EVAL_SEED bash "$(dirname "$0")/failure_reasons.sh" "$task" "$run/eval/checkpoint.rec" \
    "$k" "$IMAGE" "$EVAL_EPISODES" "$LABEL" "$SEED" > "$run/failures-act-k$k.csv.tmp" 2>> "$run/actor.log" \
    && mv "$run/failures-act-k$k.csv.tmp" "$run/failures-act-k$k.csv" || log "$task $LABEL seed $SEED: no analysis acting with K = $k"
done
log "$task $LABEL seed $SEED: done; $run/eval.csv"
