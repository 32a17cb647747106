# Sourced by the scripts of examples/ (and asked by examples/Makefile for PYTHON and the run
# label): what they share, written once here — the Python interpreter, a run's label, the
# learner's checkpoint names and the agent acting in the simulator through a FIFO.

# Debian's Python, with NumPy and matplotlib (debian-packages.txt); PYTHON=... for another.
: "${PYTHON:=/usr/bin/python3}"

# The K a run of METHOD acts with and expands in its target, "ACT_K TARGET_K": C2F-ARM acts
# greedily with the double-DQN target, adaptive K chooses per node, QTE (qte) expands K in both.
method_k() {  # METHOD K
  case $1 in
    c2farm) echo "1 0" ;;
    adaptive) echo "auto auto" ;;
    *) echo "$2 $2" ;;
  esac
}

# The label of a run of METHOD (qte, c2farm, adaptive) expanding ACT_K when acting and TARGET_K
# in the target, or with adaptive K its K_MARGIN and K_MAX: the run's directory and CSV names
# and eval.csv's label column. qte-k10-t10, c2farm-k1-t0, adaptive-m0.02-max10.
run_label() {  # METHOD ACT_K TARGET_K K_MARGIN K_MAX
  if [ "$1" = adaptive ]; then echo "$1-m$4-max$5"; else echo "$1-k$2-t$3"; fi
}
# The K a run of LABEL acts with, as qte-select's words: "10", or "auto --k-margin M --k-max N".
acting_k_of_label() {  # LABEL
  case $1 in
    adaptive-m*) local margin=${1#adaptive-m}; echo "auto --k-margin ${margin%-max*} --k-max ${1##*-max}" ;;
    *) local k=${1#*-k}; echo "${k%%-t*}" ;;
  esac
}

# What a finished learn.sh run RUN (.../<task>/<label>-seed<N>/ with eval.csv and its final
# eval/checkpoint.rec) was made with, for analyses replayed after it: run_task, run_name,
# run_label, run_seed, run_k (an array: the K it acts with and qte-select's words for it),
# run_image (its demonstrations' camera), run_episodes (its evaluations') and
# run_plan_options (learn.sh's PLAN_OPTIONS). Returns 1 for a run not finished; exits the
# script for a finished run whose settings cannot be read.
# learn.sh writes eval.csv after the final evaluation's snapshot; a run resumed past its end
# snapshots again, leaving a checkpoint newer than its eval.csv: not finished.
finished_run_settings() {  # RUN
  local run=${1%/}
  [ -f "$run/eval.csv" ] && [ -f "$run/eval/checkpoint.rec" ] || return 1
  [ "$run/eval/checkpoint.rec" -nt "$run/eval.csv" ] && return 1
  run_name=$(basename "$run") run_task=$(basename "$(dirname "$run")")
  run_label=${run_name%-seed*} run_seed=${run_name##*-seed}
  read -r -a run_k <<< "$(acting_k_of_label "$run_label")"
  run_image=$(stream-cat --type obs --head 1 "$run/demos.rec" | stream-dump \
    | awk '$1 ~ /\.rgb$/ { gsub(/[\[\],]/, ""); print $3 "x" $4; exit }')
  run_episodes=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) h[i] = $i }
    NR == 2 { for (i = 1; i <= NF; i++) if (h[i] == "episodes") print $i }' "$run/eval.csv")
  run_plan_options=$(cat "$run/plan_options" 2>/dev/null || true)
  if [ -z "$run_image" ] || [ -z "$run_episodes" ]; then  # a finished run lacks neither: stop, do not guess
    echo "$run: no camera size in demos.rec or no episodes column in eval.csv" >&2
    exit 1
  fi
}

# The learner's numbered checkpoints, DIR/step-NNNNNNNN.rec (qattn-train --checkpoint-dir DIR;
# the program names them in CheckpointDirectory::path_for, lib/learner/training_files.cpp;
# supervise.py finds the newest).
# keyframe's option for the CROP_AUGMENTATION setting (VALUE on or off): none, or --no-crop-augmentation.
crop_augmentation_option() {  # VALUE
  [ "$1" = on ] || echo --no-crop-augmentation
}

checkpoint_path() {  # DIR STEP
  printf '%s/step-%08d.rec\n' "$1" "$2"
}

# The agent acting in its world, a pipeline closed by a FIFO:
#   agent_loop [--only-trajectories-back] FIFO STAGE ARG... qte-select ARG... plan-path ARG... ['|' CONSUMER...]
# runs
#   STAGE ARG... < FIFO | qte-select ARG... | plan-path ARG... | tee FIFO [| CONSUMER...]
# STAGE (sim-step, or robot-step for a real robot) writes observations to qte-select (the
# next-best pose) and plan-path (its trajectory); plan-path's stream (observations, actions,
# trajectories) goes back to STAGE through FIFO (made here, an old one removed) and on to
# CONSUMER, or to standard output without one. With --only-trajectories-back only the
# trajectories go back (stream-cat --type trajectory), so a stage waiting at its --gate holds
# nothing in flight. The programs' names separate their arguments. The exit statuses of the
# pipeline's programs, in order, are left in the array agent_loop_status (for a caller without
# set -e).
# write_once OUT COMMAND...: COMMAND's standard output to OUT, whole or not at all, by one pass
# only: when OUT is there, or another pass holds OUT's lock (two runs ending together, each make
# writing one directory's tables), nothing runs and the status is 0; a failed COMMAND leaves no
# OUT and returns its failure.
write_once() {
  local out=$1 status=0
  shift
  exec 9> "$out.lock"
  if flock -n 9 && [ ! -f "$out" ]; then
    if "$@" > "$out.tmp"; then mv "$out.tmp" "$out"; else status=1; rm -f "$out.tmp"; fi
    rm -f "$out.lock"
  fi
  exec 9>&-
  return "$status"
}

agent_loop() {
  local back=(tee) fifo part=stage world=() select=() plan=()
  if [ "$1" = --only-trajectories-back ]; then back=(send_trajectories_back); shift; fi
  fifo=$1
  shift
  while [ $# -gt 0 ] && [ "$1" != '|' ]; do
    case $part:$1 in
      stage:qte-select) part=qte-select ;;
      qte-select:plan-path) part=plan-path ;;
      stage:*) world+=("$1") ;;
      qte-select:*) select+=("$1") ;;
      plan-path:*) plan+=("$1") ;;
    esac
    shift
  done
  [ "${#world[@]}" -gt 0 ] || { echo "agent_loop: expected the stage (sim-step, robot-step) after the FIFO" >&2; return 2; }
  [ "$part" = plan-path ] || { echo "agent_loop: expected qte-select then plan-path among its arguments" >&2; return 2; }
  [ $# -eq 0 ] || shift  # the '|': what follows is the consumer
  rm -f "$fifo"
  mkfifo "$fifo"
  if [ $# -gt 0 ]; then
    "${world[@]}" < "$fifo" | qte-select "${select[@]}" | plan-path "${plan[@]}" | "${back[@]}" "$fifo" | "$@"
  else
    "${world[@]}" < "$fifo" | qte-select "${select[@]}" | plan-path "${plan[@]}" | "${back[@]}" "$fifo"
  fi
  agent_loop_status=("${PIPESTATUS[@]}")
}
send_trajectories_back() {  # FIFO: standard input to standard output, its trajectories also to FIFO
  tee >(stream-cat --type trajectory > "$1")
}
