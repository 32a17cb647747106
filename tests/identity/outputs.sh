#!/usr/bin/env bash
# What the programs write, as one SHA-256 a command: run it with two builds (before and after a
# change that should not change what a user sees) and diff the two listings. Every line that
# differs is a change to name in the commit, or a mistake.
#
#   tests/identity/outputs.sh TOOLS_DIR > after.txt
#   git stash; make build; tests/identity/outputs.sh build/tools > before.txt; git stash pop
#   diff before.txt after.txt
#
# Each command runs with fixed seeds on small inputs made by the programs themselves (the
# demonstrations first), so its bytes follow from the build alone. A command that fails is
# listed as "exit N" with its first line of error, so a failure is a difference too. About two
# minutes of one core.
set -uo pipefail
tools=${1:?usage: outputs.sh TOOLS_DIR}
tools=$(cd "$tools" && pwd)
# The networks' layers pinned (their default follows the processor): the same bytes on any machine.
export PATH="$tools:$PATH" QTE_NETWORK_LAYERS=${QTE_NETWORK_LAYERS:-libtorch}
examples=$(cd "$(dirname "$0")/../../examples" && pwd)
source "$examples/common.sh"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"

# NAME COMMAND...: the command's standard output, then every file it wrote into out/ (sorted),
# hashed as one. Standard error is not compared (it holds timings).
listed() {
  local name=$1 status hash
  shift
  rm -rf out && mkdir out
  "$@" > out/.stdout 2> err
  status=$?
  if [ "$status" -ne 0 ]; then
    echo "$name exit $status: $(head -c 200 err | head -1)"
    return
  fi
  hash=$(cd out && find . -type f | LC_ALL=C sort | xargs -d '\n' cat | sha256sum | cut -c1-16)
  echo "$name $hash"
}

# The demonstrations and their transitions (inputs of what follows).
demo-record --task reach_target --episodes 2 --seed 0 --scenes demo --image-size 48x48 --output demos.rec 2>/dev/null
demo-record --task lift_numbered_block --episodes 1 --seed 3 --scenes demo --image-size 48x48 --compress --output lift.rec 2>/dev/null
keyframe --seed 0 --output replay.rec demos.rec 2>/dev/null
stream-cat --type obs --head 1 demos.rec > obs.rec
stream-cat --type obs --head 1 lift.rec > lift_obs.rec
qattn-train --batch 4 --start-after 0 --seed 0 --steps 3 --checkpoint-every 3 --checkpoint-dir ckpt replay.rec 2>/dev/null

listed demo-record demo-record --task reach_target --episodes 2 --seed 0 --scenes demo --image-size 48x48
listed demo-record-compressed demo-record --task lift_numbered_block --episodes 1 --seed 3 --scenes demo --image-size 48x48 --compress
listed demo-record-objects demo-record --task stack_blocks --episodes 1 --seed 1 --image-size 32x32 --objects
listed keyframe keyframe --seed 0 demos.rec
listed keyframe-depths3 keyframe --seed 0 --depths 3 --offset 0.15,0.05 lift.rec
listed stream-dump stream-dump demos.rec
listed stream-dump-summary stream-dump --summary replay.rec
listed stream-dump-schema stream-dump --schema
listed stream-cat-where stream-cat --type transition --where demo=1 replay.rec
listed stream-pack stream-pack obs step:i32=3 "x:f32[4]=1,2,3,4" task=reach_target
listed voxelize voxelize obs.rec
listed voxelize-crop voxelize --centre 0.2,0.0,0.9 --offset 0.15 lift_obs.rec
listed qattn-train qattn-train --batch 4 --start-after 0 --seed 0 --steps 3 --checkpoint-every 3 --checkpoint-dir out/ckpt replay.rec
listed qattn-train-tree qattn-train --batch 4 --start-after 0 --seed 1 --steps 2 --tree-target 3 --checkpoint-every 2 --checkpoint-dir out/ckpt replay.rec
train_with_metrics() {  # the metrics without their timing columns (steps_per_s, elapsed_s)
  qattn-train --batch 4 --start-after 0 --seed 2 --steps 2 --checkpoint-every 2 --checkpoint-dir out/ckpt --metrics metrics.csv replay.rec \
    && awk -F, -v OFS=, 'NR == 1 { for (i = 1; i <= NF; i++) keep[i] = $i !~ /^(steps_per_s|elapsed_s)$/ }
      { line = ""; for (i = 1; i <= NF; i++) if (keep[i]) line = line (line == "" ? "" : OFS) $i; print line }' metrics.csv > out/metrics.csv
}
listed qattn-train-metrics train_with_metrics
listed qte-select-k1 qte-select --checkpoint ckpt/latest.rec --k 1 --seed 0 obs.rec
listed qte-select-k3 qte-select --checkpoint ckpt/latest.rec --k 3 --seed 0 obs.rec
listed qte-select-explore qte-select --checkpoint ckpt/latest.rec --k 1 --epsilon 0.5 --rotation-noise 1 --seed 4 obs.rec
qte-select --checkpoint ckpt/latest.rec --k 1 --seed 0 obs.rec > chosen.rec 2>/dev/null
listed plan-path plan-path --seed 0 chosen.rec
listed plan-path-approach plan-path --seed 0 --approach 0.1 chosen.rec
plan-path --seed 0 chosen.rec > planned.rec 2>/dev/null
listed xarm-export xarm-export --dir out/arm planned.rec
listed stream-png stream-png --dir out/png obs.rec
listed sim-step-tasks sim-step --list-tasks
stream-pack reset task=pick_and_lift seed:i64=2 > reset.rec
listed sim-step sim-step --image-size 32x32 reset.rec
# An episode of the agent in the simulator, closed through a FIFO, summed up by episode-stats.
agent_episodes() {  # agent_loop's arguments: its status, the first program's that failed
  local status
  agent_loop "$@"
  for status in "${agent_loop_status[@]}"; do [ "$status" = 0 ] || return "$status"; done
}
listed agent-episodes agent_episodes fifo sim-step --task reach_target --episodes 2 --seed 7 --scenes eval --image-size 32x32 \
  qte-select --checkpoint ckpt/latest.rec --k 1 --seed 0 plan-path '|' episode-stats --label identity
listed failure-reasons env EVAL_SEED=7 VARIATION=0 bash "$examples/failure_reasons.sh" \
  reach_target ckpt/latest.rec 1 32x32 2 identity 0
printf 'step,rate,task\n0,0.1,a\n10,0.5,a\n0,0.2,b\n10,0.3,b\n' > curves.csv
listed plot-curves plot-curves --x step --y rate --panel task --output out/curves.png curves.csv
for tool in "$tools"/*; do
  [ -x "$tool" ] && [ -f "$tool" ] || continue
  listed "man-$(basename "$tool")" "$tool" --help-man
done
