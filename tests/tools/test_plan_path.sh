#!/usr/bin/env bash
# plan-path between the simulator's observations and its trajectories.
source "$(dirname "$0")/common.sh"

src=${QTE_SOURCE:?set QTE_SOURCE to the repository}
# A pick_and_lift scene's first observation at 64x64, and its reset (tests/data/make_data.sh).
cp "$src/tests/data/pick_and_lift_reset.rec" "$tmp/reset.rec"
cp "$src/tests/data/pick_and_lift_obs.rec" "$tmp/obs.rec"
# 40 cm above the table, gripper pointing down (180 deg about x: qx = 1).
stream-pack action pose:f64=0.1,0.0,1.15,1,0,0,0 gripper_open:u8=1 > "$tmp/action.rec"
cat "$tmp/obs.rec" "$tmp/action.rec" | plan-path --seed 3 --octomap "$tmp/scene.bt" > "$tmp/planned.rec" 2> "$tmp/err" \
  || fail "plan-path exit"
[ ! -s "$tmp/err" ] || fail "plan-path --octomap printed on standard error: $(cat "$tmp/err")"  # OctoMap's " done."
[ "$(stream-dump --summary "$tmp/planned.rec" | cut -f1,2 | tr '\n' ' ')" = "$(printf 'action\t1 records obs\t1 records trajectory\t1 records ')" ] \
  || fail "expected obs, action and trajectory to come out: $(stream-dump --summary "$tmp/planned.rec")"
stream-dump --json --type trajectory "$tmp/planned.rec" | grep -q '"name":"joint_positions","dtype":"float64","shape":\[[0-9]*,7\]' \
  || fail "no joint waypoints"
head -c 40 "$tmp/scene.bt" | grep -q "Octomap OcTree binary file" || fail "--octomap did not write an OctoMap .bt"
cat "$tmp/obs.rec" "$tmp/action.rec" | plan-path --seed 3 | cmp -s - "$tmp/planned.rec" || fail "same input and seed, different bytes"

# The trajectory executes in the simulator: it starts where the arm is, stays within limits.
{ cat "$tmp/reset.rec"; stream-cat --type trajectory "$tmp/planned.rec"; } | sim-step --image-size 64x64 > "$tmp/after.rec" \
  || fail "sim-step on the plan"
stream-dump --json --type obs "$tmp/after.rec" | tail -n 1 > "$tmp/last.json"
grep -q '"name":"failure"' "$tmp/last.json" && fail "the planned trajectory failed in the simulator: $(grep -o '"name":"failure"[^}]*' "$tmp/last.json")"
grep -q '"name":"step","dtype":"int32","shape":\[\],"values":\[1\]' "$tmp/last.json" || fail "no observation after the move"

# Invalid poses come back as failures, not crashes.
stream-pack action pose:f64=0.1,nan,1,1,0,0,0 > "$tmp/nan.rec"
stream-pack action pose:f64=0.1,0,1,0.5,0,0,0 > "$tmp/nonunit.rec"
stream-pack action pose:f64=3,0,1,1,0,0,0 > "$tmp/far.rec"
for case in nan:invalid_pose nonunit:invalid_pose far:outside_workspace; do
  name=${case%%:*} reason=${case##*:}
  cat "$tmp/obs.rec" "$tmp/$name.rec" | plan-path | stream-dump --json --type trajectory > "$tmp/$name.json" || fail "$name: exit $?"
  grep -q "\"value\":\"$reason\"" "$tmp/$name.json" || fail "$name: expected failure $reason: $(cat "$tmp/$name.json")"
done

# An action with no observation before it is a stream error naming the record.
# Settings outside what a plan can use are usage errors, not minutes of planning or a silent
# negative clearance.
for bad in "--time-budget inf" "--velocity-scale 1e-300" "--clearance -1" "--acceleration 1e-12" "--time-budget nan"; do
  err=$(plan-path $bad < "$tmp/action.rec" 2>&1 >/dev/null); rc=$?
  [ $rc = 2 ] && grep -q -- "${bad%% *} must be" <<<"$err" || fail "plan-path $bad: exit $rc: $err"
done
err=$(voxelize --offset -1 < "$tmp/action.rec" 2>&1 >/dev/null); rc=$?
[ $rc = 2 ] && grep -q -- "--offset must be" <<<"$err" || fail "voxelize --offset -1: exit $rc: $err"
err=$(voxelize --centre 0.1,nan,0.9 < "$tmp/action.rec" 2>&1 >/dev/null); rc=$?
[ $rc = 2 ] && grep -q -- "'nan' is not a finite number" <<<"$err" || fail "voxelize --centre nan: exit $rc: $err"
err=$(plan-path < "$tmp/action.rec" 2>&1 >/dev/null); rc=$?
[ $rc = 1 ] || fail "action before obs: exit $rc"
grep -q "<stdin>: record 0 at byte 0: action before any observation" <<<"$err" || fail "$err"
echo "plan-path ok"
