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
# This script holds the pipelines; supervise.py runs them (as `learn.sh TASK RUN --part
# learner | actor I FIRST | evaluate ...`) and does the bookkeeping: pacing, the chunks' gates,
# when to evaluate, the processor and wall-clock accounts, the stops.
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
# settings.txt: defaults, checks, misspellings refused (a part has them from its run's learn.sh)
[ "${3:-}" = --part ] || settings_load learn.sh
eval "stage=($STAGE)"
eval "eval_stage=($EVAL_STAGE)"
# Adaptive K (ACT_K or TARGET_K 'auto'): each node expands the voxels within K_MARGIN of its
# best Q, at most K_MAX; the options go only to the programs whose K is 'auto'.
branching() {  # K -> the options that go with it
  if [ "$1" = auto ]; then echo "--k-margin $K_MARGIN --k-max $K_MAX"; fi
}
# The replay file an actor appends its episodes to: the run's, or in a split run its own.
actor_replay=$run/replay.rec
[ "$ROLE" != actor ] || actor_replay=$run/actors/replay-$ACTOR_INDEX.rec

# The parts supervise.py runs, `learn.sh TASK RUN --part NAME ARG...` (the settings come from
# the run's own learn.sh, in the environment):
if [ "${3:-}" = --part ]; then
  part=$4
  shift 4
  case $part in
    # The learner, for the whole run: trains as the replay grows (with ROLE=learner it follows
    # the actors' replay files too), writing ckpt/step-N.rec and ckpt/latest.rec.
    learner)
      inputs=("$run/replay.rec")
      if [ "$ROLE" = learner ]; then
        for ((i = 0; i < ACTORS; i++)); do inputs+=("$run/actors/replay-$i.rec"); done
      fi
      exec qattn-train --follow --resume --stop-file "$run/actor.done" --replay-ratio "$RATIO" --pretrain "$PRETRAIN" \
        --start-after "$START_AFTER" --steps 1000000 --checkpoint-every "$CHECKPOINT_EVERY" --keep 4 \
        --architecture "$ARCH" $NET_OPTIONS --batch "$BATCH" --tree-target "$TARGET_K" $(branching "$TARGET_K") \
        --n-step "$N_STEP" --demo-margin "$DEMO_MARGIN" --demo-cross-entropy "$DEMO_CROSS_ENTROPY" --demo-share "$DEMO_SHARE" --head-input "$HEAD_INPUT" --seed "$SEED" --threads "$LEARNER_THREADS" \
        --precision "$PRECISION" --checkpoint-dir "$run/ckpt" --metrics "$run/train.csv" "${inputs[@]}" 2>> "$run/train.log" ;;
    # Actor I from chunk FIRST: a closed loop through a FIFO, up until its gate says stop,
    # running chunks FIRST, FIRST + ACTORS, ... of CHUNK_EPISODES exploring episodes as
    # supervise.py opens them (chunk c explores the scenes of seed SEED * 100000 + c, whichever
    # actor runs it); qte-select takes up each new checkpoint at the start of an episode; every
    # finished episode is appended to the replay at once. Only trajectories go back to the
    # stage, so a pipeline waiting at its gate holds nothing in flight. The exit statuses of its
    # programs are left in actors/status-I.
    actor)  # I FIRST
      exec 2>> "$run/actor.log"
      set +e  # the status of every program is what this part is for
      agent_loop --only-trajectories-back "$run/actors/loop-$1" \
        "${stage[@]}" --task "$task" --variation "$VARIATION" --episodes 10000000 --seed $(( SEED * 100000 )) --scenes explore \
          --chunk-episodes "$CHUNK_EPISODES" --first-chunk "$2" --chunk-stride "$ACTORS" --gate "$run/actors/gate-$1" --compress \
        qte-select --checkpoint "$run/ckpt/latest.rec" --reload --k "$ACT_K" $(branching "$ACT_K") --epsilon "$EPSILON" \
          --rotation-noise "$ROTATION_NOISE" --seed $(( SEED * 100000 + $1 )) --threads 1 --precision "$PRECISION" \
        plan-path $PLAN_OPTIONS \
        '|' keyframe --agent --seed "$SEED" $NET_OPTIONS --append --output "$actor_replay"
      echo "${agent_loop_status[*]}" > "$run/actors/status-$1"
      exit 0 ;;
    # Greedy episodes of a checkpoint on the held-out scenes -> one CSV row on standard output.
    # eval_point: the budget the evaluation stands for (0, EVAL_EVERY, ..., ENV_STEPS); env_steps
    # (what the actors had taken, up to a chunk more) varies between seeds, eval_point does not.
    evaluate)  # CHECKPOINT ENV_STEPS LEARNER_STEP EVAL_POINT TRAIN_S [--column NAME=VALUE]...
      checkpoint=$1 env_steps=$2 step=$3 point=$4 train_s=$5
      shift 5
      fifo=$(mktemp -u)
      agent_loop "$fifo" \
        "${eval_stage[@]}" --task "$task" --variation "$VARIATION" --episodes "$EVAL_EPISODES" --seed "$EVAL_SEED" --scenes eval \
        qte-select --checkpoint "$checkpoint" --k "$ACT_K" $(branching "$ACT_K") --threads 1 --precision "$PRECISION" \
        plan-path $PLAN_OPTIONS \
        '|' episode-stats --label "$LABEL" --column seed="$SEED" --column env_steps="$env_steps" --column train_step="$step" \
          --column eval_point="$point" --column train_s="$train_s" "$@"
      rm -f "$fifo"
      exit 0 ;;
    *) echo "learn.sh: no part $part (learner, actor, evaluate)" >&2; exit 2 ;;
  esac
fi
# The task, known to the simulator (a real robot's runs name theirs freely).
if [[ $STAGE == sim-step* ]] && ! sim-step --list-tasks | cut -f1 | grep -x -- "$task" > /dev/null; then
  echo "learn.sh: $task is not a task (sim-step --list-tasks: $(sim-step --list-tasks | cut -f1 | xargs | tr ' ' ,))" >&2
  exit 2
fi
export PLAN_OPTIONS  # failure_reasons.sh plans the final agent's moves the same way
mkdir -p "$run/actors" "$run/eval"
# The planner's options are the run's own: kept in it, so that a resumed run and every later
# replay of its agent (failures_of_runs.sh) plan as it did.
if [ -f "$run/plan_options" ]; then
  [ "$(cat "$run/plan_options")" = "$PLAN_OPTIONS" ] || {
    echo "learn.sh: $run was started with PLAN_OPTIONS='$(cat "$run/plan_options")', not '$PLAN_OPTIONS'" >&2; exit 2; }
else
  echo "$PLAN_OPTIONS" > "$run/plan_options"
fi
# The settings its replay's demonstrations were made with likewise: replay.rec is made once, so
# a run resumed with others (CHAIN_STEPS=episode into a reset run's directory, which has the same
# label) would train on data it does not name.
crop_option=$(crop_augmentation_option "$CROP_AUGMENTATION")
demo_settings="DEMOS=$DEMOS IMAGE=$IMAGE VARIATION=$VARIATION CHAIN_STEPS=$CHAIN_STEPS DEMOS_FROM=$DEMOS_FROM NET_OPTIONS=$NET_OPTIONS"
demo_settings+=${crop_option:+ CROP_AUGMENTATION=off}  # named only when off: earlier runs' files stay valid
if [ -f "$run/demo_settings" ]; then
  [ "$(cat "$run/demo_settings")" = "$demo_settings" ] || {
    echo "learn.sh: $run was started with $(cat "$run/demo_settings"), not $demo_settings" >&2; exit 2; }
elif [ ! -f "$run/replay.rec" ]; then  # a run started before the file was kept: its settings are unknown
  echo "$demo_settings" > "$run/demo_settings"
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
log() { printf '%s %s\n' "$(date +%H:%M:%S)" "$*" >&2; }
# Processor ticks of this script and every child it has reaped (the demonstrations' share and
# the start's own are handed to supervise.py, which keeps the run's accounts).
shell_ticks() {
  local stat fields
  read -r stat < "/proc/$$/stat"
  read -ra fields <<< "${stat##*) }"  # from field 3 on: the command name may hold spaces
  echo $(( fields[11] + fields[12] + fields[13] + fields[14] ))
}
# A run killed while an episode was being appended leaves a torn last record in the replay; the
# run is the file's only writer, so on resume the torn record is cut off (its chunk runs again)
# and the cut is logged, instead of every later append being refused.
repair_replay() {  # FILE
  local said
  [ -s "$1" ] || return 0
  said=$(stream-cat --append --repair --output "$1" /dev/null 2>&1) || { log "$said"; exit 1; }
  [ -z "$said" ] || log "$task $LABEL seed $SEED: $said"
}

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
  log "$task $LABEL seed $SEED: $DEMOS demonstrations, $ENV_STEPS environment steps in chunks of $CHUNK_EPISODES episodes, $PRETRAIN pretraining steps then $RATIO learner steps per agent transition (batch $BATCH, $N_STEP-step targets, tree target K = $TARGET_K), acting with K = $ACT_K; evaluated every $EVAL_EVERY steps on $EVAL_EPISODES held-out scenes$([ "$CPU_BUDGET" = 0 ] || echo ", processor budget $CPU_BUDGET s")$([ "$TIME_BUDGET" = 0 ] || echo ", wall-clock budget $TIME_BUDGET s"); networks in $PRECISION${NET_OPTIONS:+, $NET_OPTIONS}"
  expected=$(committed_minutes)
  [ -z "$expected" ] || log "$task $LABEL: the committed runs trained for $expected on 2 cores, evaluations excluded"
fi

# The supervision of the run (supervise.py): it starts the learner and the actors (the parts
# above), paces the actors by the learner, opens the chunks' gates, evaluates, keeps the
# accounts and stops the run when its learner dies or stalls. In the background so that a
# signal to this script reaches it at once; it ends the run's programs when it ends.
supervise() {  # ARG...
  local status=0
  "$PYTHON" "$(dirname "$0")/supervise.py" --learn-sh "$0" --task "$task" --run "$run" --label "$LABEL" --seed "$SEED" \
    --role "$ROLE" --actors "$ACTORS" --actor-index "$ACTOR_INDEX" --stage-program "$(basename "${stage[0]}")" \
    --env-steps "$ENV_STEPS" --eval-every "$EVAL_EVERY" --pretrain "$PRETRAIN" --ratio "$RATIO" \
    --checkpoint-every "$CHECKPOINT_EVERY" --cpu-budget "$CPU_BUDGET" --time-budget "$TIME_BUDGET" \
    --account-every "$ACCOUNT_EVERY" --stall-seconds "$STALL_SECONDS" "$@" &
  supervisor=$!
  trap 'kill $supervisor 2>/dev/null; wait $supervisor' EXIT
  wait $supervisor || status=$?
  trap - EXIT
  return $status
}

# Actor i of a split run: chunks i, i + ACTORS, ... until the run has its environment steps or
# the learner says it is done.
if [ "$ROLE" = actor ]; then
  mkdir -p "$run/actors"
  repair_replay "$actor_replay"
  supervise || exit $?
  exit 0
fi

# 1. Demonstrations -> transitions (once; written under a temporary name, then renamed).
demos_ticks=0
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
  keyframe --seed "$SEED" --chain-steps "$CHAIN_STEPS" $crop_option $NET_OPTIONS --output "$run/replay.rec.tmp" "$run/demos.rec" 2>> "$run/demos.log" \
    || { status=$?; echo "learn.sh: $(tail -1 "$run/demos.log")" >&2; exit "$status"; }  # its reason, not only in demos.log
  mv "$run/replay.rec.tmp" "$run/replay.rec"
  demos_ticks=$(( $(shell_ticks) - before ))
fi

# 2. The learner and the actors, supervised, to the run's end; with ROLE=learner the learner
# follows the actors' replay files too (made empty here if no actor has started yet).
repair_replay "$run/replay.rec"
if [ "$ROLE" = learner ]; then
  for ((i = 0; i < ACTORS; i++)); do touch "$run/actors/replay-$i.rec"; done
fi
rm -f "$run/actor.done"
supervise --demos-ticks "$demos_ticks" --startup-ticks $(( $(shell_ticks) - demos_ticks )) || exit $?

cat "$run"/eval/*.csv | awk 'NR == 1 || !/^label/' > "$run/eval.csv"
# Where the final networks' agent goes on the evaluation scenes, beside the expert on the same
# scenes (failure_reasons.sh: the last evaluation's episodes again, deterministic).
# The simulator's analysis: not for a real robot's runs.
if [ "${stage[0]}" = sim-step ] && [ ! -f "$run/failures.csv" ]; then
  VARIATION=$VARIATION EVAL_SEED=$EVAL_SEED bash "$(dirname "$0")/failure_reasons.sh" "$task" "$run/eval/checkpoint.rec" \
    "$ACT_K" "$IMAGE" "$EVAL_EPISODES" "$LABEL" "$SEED" $(branching "$ACT_K") > "$run/failures.csv.tmp" 2>> "$run/actor.log" \
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
