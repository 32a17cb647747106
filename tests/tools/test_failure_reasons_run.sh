#!/usr/bin/env bash
# examples/analysis/failure_reasons.py's reasons on a real scene whose answers are known: the first
# pick_up_cup evaluation scene (sim-step --objects), played by hand-written actions planned by
# plan-path, or by hand-written trajectories: the cup lifted (success), the gripper closed on
# empty space (grasp_missed), the cup let go of (dropped), the other cup grasped
# (wrong_object), a goal in the table (goal_in_collision), a trajectory that does not start
# where the arm is (trajectory_refused), a move into the table (collision), and standing still
# for the episode's 10 steps (out_of_steps); the expert's own episode of the scene sorted alone
# is a success. Then examples/failure_reasons.sh records the expert's episodes once per key in
# EXPERT_CACHE: a second analysis takes them from there and prints the same bytes, a
# different image size records again, and EXPERT_CACHE= keeps nothing. The ceiling
# (ceiling.sh: the expert's discretized keyframes) solves two reach_target scenes.
source "$(dirname "$0")/common.sh"
py=/usr/bin/python3
src=${QTE_SOURCE:?set QTE_SOURCE to the repository}
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}
export PYTHONPATH="$src/lib/python"
scene=(--task pick_up_cup --variation 0 --episodes 1 --seed 1000000 --scenes eval --image-size 64x64)

sim-step "${scene[@]}" --objects < /dev/null > "$tmp/reset.rec" || fail "sim-step --objects"
# Points to go to: the cup's grasp point (its centre, halfway up), the other cup's, empty table
# 12 cm from the cup away from the other one, and the same 3 cm under the table top; then the
# arm's joints at the reset.
eval "$($py - "$tmp/reset.rec" <<'EOF'
import sys
import numpy as np
import qte_stream
obs = next(r for r in qte_stream.read_records(sys.argv[1]) if r.type == "obs")
cups = {o.name: o for o in qte_stream.scene_objects(obs)}
assert (cups["cup"].role, cups["other_cup"].role) == ("target", "distractor"), cups
assert list(cups["cup"].box_max[:2]) == [0.035, 0.035] and cups["cup"].held is False, cups["cup"]
cup, other = (cups[n].pose[:3] + [0, 0, 0.045] for n in ("cup", "other_cup"))
away = (cup - other)[:2] / np.linalg.norm((cup - other)[:2])
empty = cup + [0.12 * away[0], 0.12 * away[1], 0]
text = lambda v: ",".join(repr(float(x)) for x in v)
print(f"cup={text(cup)} other={text(other)} empty={text(empty)} under={text(empty - [0, 0, 0.045 + 0.03])}")
print(f"joints={text(obs.fields['joint_positions'])}")
EOF
)" || fail "the scene's points"

# play NAME MOVE...: an episode of the scene, one MOVE per step: "POINT DZ OPEN IGNORE" (an
# action at POINT + DZ m, top-down, planned by plan-path) or "trajectory FIELDS" (an action
# over the cup and, instead of the plan, the trajectory stream-pack makes of FIELDS). Writes
# the agent's stream NAME.rec: each observation, then the action taken after it.
play() {
  local name=$1 step=0 move
  shift
  : > "$tmp/$name.traj"; : > "$tmp/$name.rec"
  for move in "$@"; do
    sim-step "${scene[@]}" --objects < "$tmp/$name.traj" > "$tmp/obs.rec" || fail "$name: sim-step"
    stream-cat --type obs --where step=$step "$tmp/obs.rec" > "$tmp/last.rec" || fail "$name: no step $step"
    [ "$(stream-cat --where terminal=1 "$tmp/last.rec" | wc -c)" = 0 ] || fail "$name: the episode ended at step $step"
    read -r point dz open ignore <<< "$move"
    if [ "$point" = trajectory ]; then
      stream-pack action pose:f64=${cup%%,*},0,1.1,1,0,0,0 > "$tmp/action.rec"
      stream-pack trajectory ${move#trajectory } >> "$tmp/$name.traj" || fail "$name: stream-pack trajectory"
    else
      IFS=, read -r x y z <<< "${!point}"
      stream-pack action pose:f64=$x,$y,$($py -c "print($z + $dz)"),1,0,0,0 gripper_open:u8=$open \
        ignore_collisions:u8=$ignore > "$tmp/action.rec"
      cat "$tmp/last.rec" "$tmp/action.rec" | plan-path | stream-cat --type trajectory >> "$tmp/$name.traj" \
        || fail "$name: plan-path"
    fi
    cat "$tmp/last.rec" "$tmp/action.rec" >> "$tmp/$name.rec"
    step=$((step + 1))
  done
  sim-step "${scene[@]}" --objects < "$tmp/$name.traj" | stream-cat --type obs --where step=$step >> "$tmp/$name.rec" \
    || fail "$name: the last observation"
}
stay="trajectory time_s:f64=0,0.1 joint_positions:f64[2,7]=$joints,$joints gripper_open:u8=1"
into_table=$($py -c "
q = [float(v) for v in '$joints'.split(',')]
to = list(q); to[1], to[3] = 1.6, 0.2  # shoulder forward and down: the arm sweeps into the table
print(','.join(map(repr, q + to)))")
play success "cup 0.1 1 0" "cup 0 0 1" "cup 0.15 0 1"
play grasp_missed "empty 0.1 1 0" "empty 0 0 1" "empty 0.15 0 1"
play dropped "cup 0.1 1 0" "cup 0 0 1" "cup 0 1 1"
play wrong_object "other 0.1 1 0" "other 0 0 1"
play goal_in_collision "under 0 1 0"
play trajectory_refused "cup 0.1 1 0" "trajectory time_s:f64=0,1 joint_positions:f64[2,7]=$(printf '0,%.0s' {1..13})0 gripper_open:u8=1"
play collision "trajectory time_s:f64=0,3 joint_positions:f64[2,7]=$into_table gripper_open:u8=1"
play out_of_steps "$stay" "$stay" "$stay" "$stay" "$stay" "$stay" "$stay" "$stay" "$stay" "$stay"

reasons=(success grasp_missed dropped wrong_object goal_in_collision trajectory_refused collision out_of_steps)
demo-record "${scene[@]}" --objects --no-points --output "$tmp/expert.rec" 2>/dev/null || fail "demo-record"
for name in "${reasons[@]}"; do cat "$tmp/$name.rec"; done > "$tmp/agent.rec"
for name in "${reasons[@]}"; do cat "$tmp/expert.rec"; done > "$tmp/experts.rec"
$py "$src/examples/analysis/failure_reasons.py" --episodes --label known "$tmp/experts.rec" "$tmp/agent.rec" \
  > "$tmp/known.csv" 2> "$tmp/known.err" || fail "failure_reasons.py exit $?: $(cat "$tmp/known.err")"
got=$(sed 's/^episode [0-9]*: \([a-z_]*\) .*/\1/' "$tmp/known.err" | tr '\n' ' ')
[ "$got" = "${reasons[*]} " ] || fail "reasons: expected ${reasons[*]}, got $got ($(cat "$tmp/known.err"))"
grep -q "^episode 6: collision .*collision:.*-table" "$tmp/known.err" || fail "the move into the table: $(cat "$tmp/known.err")"
grep -c "the expert: success$" "$tmp/known.err" | grep -qx 8 || fail "the expert's reason per scene: $(cat "$tmp/known.err")"
expected='label,seed,episodes,success,distractor,target,elsewhere,failed_actions,wrong_object,pushed,grasp_missed,dropped,goal_in_collision,ik_failed,no_path,start_in_collision,outside_workspace,invalid_pose,approach_blocked,trajectory_refused,collision,other_failure,out_of_steps
known,,8,1,1,1,5,3,1,0,1,1,1,0,0,0,0,0,0,1,1,0,1'
[ "$(cat "$tmp/known.csv")" = "$expected" ] || fail "the counts: $(cat "$tmp/known.csv")"
# The expert's stream alone: its own episode, sorted by its objects.
$py "$src/examples/analysis/failure_reasons.py" --label expert "$tmp/expert.rec" | tail -1 | grep -q "^expert,,1,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0$" \
  || fail "the expert alone: $($py "$src/examples/analysis/failure_reasons.py" "$tmp/expert.rec" 2>&1)"

# --- the expert's episodes recorded once per key --------------------------------------------
keyframe "$src/tests/data/reach_target_demo.rec" > "$tmp/transitions.rec" 2>/dev/null || fail "keyframe"
qattn-train --steps 0 --seed 1 --checkpoint-dir "$tmp/run/ckpt" "$tmp/transitions.rec" 2>/dev/null || fail "qattn-train"
# demo-record as a program that counts its calls (the cache key's checksum is this file's).
mkdir -p "$tmp/bin"
printf '#!/bin/sh\necho "$*" >> %s\nexec %s "$@"\n' "$tmp/demo-record.calls" "$(command -v demo-record)" > "$tmp/bin/demo-record"
chmod +x "$tmp/bin/demo-record"
analyse() {  # IMAGE OUT [EXPERT_CACHE]: failure_reasons.sh on two reach_target scenes
  if [ $# -gt 2 ]; then
    PATH="$tmp/bin:$PATH" EXPERT_CACHE=$3 timeout 300 bash "$src/examples/failure_reasons.sh" reach_target "$tmp/run/ckpt/latest.rec" 1 "$1" 2
  else
    PATH="$tmp/bin:$PATH" timeout 300 bash "$src/examples/failure_reasons.sh" reach_target "$tmp/run/ckpt/latest.rec" 1 "$1" 2
  fi > "$tmp/$2" 2> "$tmp/$2.err" || fail "failure_reasons.sh $*: exit $?: $(cat "$tmp/$2.err")"
}
calls() { [ -f "$tmp/demo-record.calls" ] && wc -l < "$tmp/demo-record.calls" || echo 0; }
analyse 32x32 first.csv
[ "$(calls)" = 1 ] || fail "the first analysis ran demo-record $(calls) times"
cached=$(ls "$tmp/expert-cache"/reach_target_variation0_seed1000000_episodes2_32x32_demo-record-*.rec 2>/dev/null)
[ -n "$cached" ] || fail "no expert episodes in the default cache, beside the run: $(ls -R "$tmp")"
analyse 32x32 second.csv
[ "$(calls)" = 1 ] || fail "the second analysis recorded the expert again"
cmp -s "$tmp/first.csv" "$tmp/second.csv" || fail "the second analysis differs: $(cat "$tmp/first.csv" "$tmp/second.csv")"
analyse 40x32 other.csv
[ "$(calls)" = 2 ] || fail "another image size took the cached expert"
[ "$(ls "$tmp/expert-cache" | wc -l)" = 2 ] || fail "the cache: $(ls "$tmp/expert-cache")"
analyse 32x32 uncached.csv ""
[ "$(calls)" = 3 ] || fail "EXPERT_CACHE= used the cache"
cmp -s "$tmp/first.csv" "$tmp/uncached.csv" || fail "the analysis without the cache differs"
analyse 32x32 elsewhere.csv "$tmp/elsewhere"
# AGENT_STREAM keeps the agent's episodes: both scenes, to their terminal observations.
AGENT_STREAM=$tmp/agent.rec analyse 32x32 kept.csv
$py - "$tmp/agent.rec" <<'PY2' || fail "AGENT_STREAM: the agent's episodes"
import sys
import qte_stream
records = list(qte_stream.read_records(sys.argv[1]))
terminal = [r for r in records if r.type == "obs" and int(r.fields["terminal"])]
assert len(terminal) == 2 and any(r.type == "action" for r in records), len(terminal)
PY2
[ "$(calls)" = 4 ] && [ -n "$(ls "$tmp/elsewhere")" ] || fail "EXPERT_CACHE=DIR was not recorded into"
# reach_target needs no grasp (its expert holds nothing): closing the gripper there is no grasp_missed.
$py -c "import csv, sys; row = list(csv.DictReader(open(sys.argv[1])))[0]; sys.exit(row['grasp_missed'] != '0')" \
  "$tmp/first.csv" || fail "the analysis's columns, or a grasp missed on reach_target: $(cat "$tmp/first.csv")"
# The ceiling (examples/ceiling.sh: CHECKPOINT `keyframes`): the expert's discretized keyframes
# solve both scenes, with no checkpoint anywhere; it keeps nothing unless EXPERT_CACHE is set,
# and an existing CSV is kept.
mkdir -p "$tmp/cwd/sub"
(cd "$tmp/cwd/sub" && PATH="$tmp/bin:$PATH" IMAGE=32x32 EVAL_EPISODES=2 timeout 300 bash "$src/examples/ceiling.sh" reach_target \
  "$tmp/ceiling/reach_target_keyframes.csv" 2> "$tmp/ceiling.err") || fail "ceiling.sh: $(cat "$tmp/ceiling.err")"
tail -1 "$tmp/ceiling/reach_target_keyframes.csv" | grep -q "^keyframes,,2,2," \
  || fail "the ceiling on reach_target: $(cat "$tmp/ceiling/reach_target_keyframes.csv")"
[ "$(calls)" = 5 ] && [ -z "$(ls -A "$tmp/cwd/sub")" ] && [ ! -e "$tmp/cwd/expert-cache" ] \
  && [ "$(ls "$tmp/ceiling")" = reach_target_keyframes.csv ] || fail "the ceiling's expert: $(calls) calls; $(ls -R "$tmp/cwd" "$tmp/ceiling")"
# CEILING_OPTIONS reach the keyframes agent: an offset of a whole turn is refused, and no CSV.
PATH="$tmp/bin:$PATH" IMAGE=32x32 EVAL_EPISODES=2 CEILING_OPTIONS="--rotation-offset 0,0,72" timeout 300 \
  bash "$src/examples/ceiling.sh" reach_target "$tmp/ceiling/offset.csv" 2> "$tmp/offset.err" \
  && fail "ceiling.sh with a refused CEILING_OPTIONS succeeded"
grep -q 'between -71 and 71' "$tmp/offset.err" && [ -z "$(ls "$tmp/ceiling" | grep offset)" ] \
  || fail "CEILING_OPTIONS did not reach qte-select: $(cat "$tmp/offset.err")"
touch -d 2000-01-01 "$tmp/ceiling/reach_target_keyframes.csv"
PATH="$tmp/bin:$PATH" bash "$src/examples/ceiling.sh" reach_target "$tmp/ceiling/reach_target_keyframes.csv" \
  && [ "$(calls)" = 6 ] && [ "$(date -r "$tmp/ceiling/reach_target_keyframes.csv" +%Y)" = 2000 ] || fail "ceiling.sh redid an existing CSV"
echo "failure reasons ok: ${#reasons[@]} known episodes, the expert once per key, the ceiling"
