#!/usr/bin/env bash
# The real-world loop against the simulated one, learning alike: the same 3 recorded
# demonstrations (demo-record's, written out as a camera and joint log record them and packed
# by obs-pack: write_recording.py), then examples/learn.sh twice with the same settings and
# seed: once acting in sim-step, once through robot-step with standin-world behind its spool
# (motions as xArm joint files, frames as PNGs, the outcome from the stand-in's judge.sh), its
# evaluations through robot-step too. Not a test (minutes to an hour): its CSVs are reported
# in docs/real-world.md.
#   compare_loops.sh OUT_DIR   (BUILD=build, SEED=0, ENV_STEPS=600, EVAL_EVERY=300, EVAL_EPISODES=20)
set -euo pipefail
out=$1
src=$(cd "$(dirname "$0")/../.." && pwd)
build=${BUILD:-$src/build}
export PATH=$build/tools:$PATH QTE_TOOLS=$build/tools QTE_SOURCE=$src
: "${SEED:=0}" "${ENV_STEPS:=600}" "${EVAL_EVERY:=300}" "${EVAL_EPISODES:=20}" "${TASK:=reach_prism}"
export SEED ENV_STEPS EVAL_EVERY EVAL_EPISODES DEMOS=3 IMAGE=128x128
mkdir -p "$out"
if [ ! -f "$out/recorded.rec" ]; then
  demo-record --task "$TASK" --episodes 3 --seed "$SEED" --scenes demo --image-size "$IMAGE" --output "$out/demos.rec"
  /usr/bin/python3 "$src/tests/standin/write_recording.py" "$out/demos.rec" "$out/recording" "$out/recorded.rec.tmp"
  mv "$out/recorded.rec.tmp" "$out/recorded.rec"
fi
export DEMOS_FROM=$out/recorded.rec

LABEL=simulated bash "$src/examples/learn.sh" "$TASK" "$out/simulated"

spool=$out/spool
rm -rf "$spool"
mkdir -p "$spool"
"$build/tests/standin/standin-world" --spool "$spool" --image-size "$IMAGE" 2> "$out/standin.log" &
standin=$!
trap 'touch "$spool/stop"; wait $standin' EXIT
# The simulated front camera's calibration at 128x128, as a real camera's would be given.
camera="--intrinsics 154.51,154.51,63.5,63.5 --camera-pose 1.05,0,1.602,-0.63365,-0.63365,0.31383,0.31383"
STAGE="robot-step --spool $spool --judge 'STANDIN_SPOOL=$spool sh $src/tests/standin/judge.sh' $camera" \
  LABEL=robot-step bash "$src/examples/learn.sh" "$TASK" "$out/robot-step"
cat "$out/simulated/eval.csv" <(tail -n +2 "$out/robot-step/eval.csv") > "$out/compare.csv"
echo "compare_loops.sh: $out/compare.csv" >&2
