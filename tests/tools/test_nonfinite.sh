#!/usr/bin/env bash
# Nothing non-finite reaches the replay: keyframe (--agent or from demonstrations) refuses a
# NaN or infinite target pose, bounds, reward or camera matrix with one line naming the record
# and the field, exit 1, and writes no output file.
source "$(dirname "$0")/common.sh"

# obs STEP TERMINAL REWARD [EXTRA FIELD...]: an observation of the learning loop.
obs() {
  stream-pack obs frame:i32=$1 step:i32=$1 terminal:u8=$2 reward:f32=$3 success:u8=0 \
    "gripper_pose:f64=0.2,0,0.9,0,0,0,1" "joint_positions:f64=0,0,0,0,0,0,0" gripper_open:u8=1 \
    "front.intrinsics:f64[3,3]=100,0,32,0,100,32,0,0,1" \
    "front.extrinsics:f64[4,4]=1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1" "${@:4}"
}
# action POSE BOUNDS0
action() {
  stream-pack action "depth0.index:i32=1,2,3" "depth0.bounds:f64=$2" "depth1.index:i32=4,5,6" \
    "depth1.bounds:f64=0,0,0.8,0.3" "rotation_bins:i32=0,0,0" gripper_open:u8=1 "pose:f64=$1"
}
good_pose=0.2,0,0.9,0,0,0,1 good_bounds=-0.3,-0.5,0.6,1.0
episode() {  # POSE BOUNDS REWARD
  { obs 0 0 0; action "$1" "$2"; obs 1 1 "$3"; }
}
episode "$good_pose" "$good_bounds" 100 > "$tmp/good.rec"
keyframe --agent --output "$tmp/good_out.rec" "$tmp/good.rec" 2>/dev/null || fail "a good agent episode was refused"

# expect WHAT RECORD FIELD INPUT: exit 1, one line naming the record and field, no output file.
expect() {
  local err rc
  err=$(keyframe --agent --output "$tmp/out.rec" "$4" 2>&1); rc=$?
  [ "$rc" = 1 ] || fail "$1: exit $rc, expected 1 ($err)"
  [ "$(wc -l <<<"$err")" = 1 ] || fail "$1: more than one line: $err"
  grep -q "$2.*'$3': expected finite values" <<<"$err" || fail "$1: said '$err', expected record '$2' and field '$3'"
  [ ! -e "$tmp/out.rec" ] || fail "$1: left an output file"
}
episode 0.2,nan,0.9,0,0,0,1 "$good_bounds" 100 > "$tmp/in.rec"
expect "NaN target pose" "record 1 at byte [0-9]*: 'action' record, field" pose "$tmp/in.rec"
episode 0.2,inf,0.9,0,0,0,1 "$good_bounds" 100 > "$tmp/in.rec"
expect "infinite target pose" "record 1 at byte" pose "$tmp/in.rec"
episode "$good_pose" -0.3,nan,0.6,1.0 100 > "$tmp/in.rec"
expect "NaN bounds" "record 1 at byte" depth0.bounds "$tmp/in.rec"
episode "$good_pose" "$good_bounds" nan > "$tmp/in.rec"
expect "NaN reward" "record 2 at byte" reward "$tmp/in.rec"
episode "$good_pose" "$good_bounds" -inf > "$tmp/in.rec"
expect "infinite reward" "record 2 at byte" reward "$tmp/in.rec"
{ obs 0 0 0; action "$good_pose" "$good_bounds"; obs 1 1 0 "joint_positions:f64=0,0,nan,0,0,0,0"; } > "$tmp/in.rec"
expect "NaN joint positions of a frame" "record 2 at byte" joint_positions "$tmp/in.rec"
echo "non-finite ok"
