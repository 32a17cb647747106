#!/usr/bin/env bash
# Nothing seen, nothing done: voxelize, qte-select and qattn-train refuse an observation with no point
# inside the scene bounds (here a camera facing away, placed far off), naming the record and
# saying what to check; bad camera matrices are refused where they are read.
source "$(dirname "$0")/common.sh"
src=${QTE_SOURCE:?set QTE_SOURCE to the repository}
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}

# obs STEP TERMINAL EXTRINSICS [INTRINSICS]: a 4x4 camera seeing everything 1 m along its z axis.
obs() {
  stream-pack obs frame:i32=$1 step:i32=$1 terminal:u8=$2 reward:f32=0 success:u8=0 \
    "gripper_pose:f64=0.2,0,0.9,0,0,0,1" "joint_positions:f64=0,0,0,0,0,0,0" gripper_open:u8=1 \
    gripper_opening_m:f64=0.08 "front.rgb:u8[4,4,3]=$(seq -s, 1 48)" "front.depth:f32[4,4]=$(printf '1,%.0s' $(seq 15))1" \
    "front.intrinsics:f64[3,3]=${4:-2,0,2,0,2,2,0,0,1}" "front.extrinsics:f64[4,4]=$3"
}
seen=1,0,0,0.2,0,1,0,0,0,0,1,0.1,0,0,0,1
away=1,0,0,0.2,0,-1,0,0,0,0,-1,0.1,0,0,0,1  # the same camera turned round: it looks down, away from the table
mirror=-1,0,0,0.2,0,1,0,0,0,0,1,0.1,0,0,0,1

cp "$src/tests/data/reach_target_demo.rec" "$tmp/demos.rec"
keyframe "$tmp/demos.rec" > "$tmp/transitions.rec" 2>/dev/null || fail "keyframe"
qattn-train --steps 0 --seed 1 --checkpoint-dir "$tmp/ckpt" "$tmp/transitions.rec" 2>/dev/null || fail "qattn-train --steps 0"
ckpt=$tmp/ckpt/latest.rec

obs 0 0 "$seen" > "$tmp/seen.rec"
qte-select --checkpoint "$ckpt" "$tmp/seen.rec" > "$tmp/seen_out.rec" 2>"$tmp/err" || fail "a seen scene was refused: $(cat "$tmp/err")"
# expect WORDS COMMAND...: exit 1, one line with WORDS, nothing on standard output.
expect() {
  local words=$1; shift
  local err rc; err=$("$@" 2>&1 > "$tmp/out"); rc=$?
  [ "$rc" = 1 ] || fail "$*: exit $rc, expected 1 ($err)"
  [ "$(wc -l <<<"$err")" = 1 ] || fail "$*: more than one line: $err"
  grep -q "$words" <<<"$err" || fail "$*: said '$err', expected '$words'"
}
obs 0 0 "$away" > "$tmp/away.rec"
expect "away.rec: record 0 at byte 0: 'obs' record: none of its 16 points lies inside the scene bounds.*check the cameras' extrinsics" \
  qte-select --checkpoint "$ckpt" "$tmp/away.rec"
[ "$(stream-dump --type action --summary "$tmp/out" | cut -f2)" != "1 records" ] || fail "qte-select chose an action on an empty scene"
# voxelize refuses it too, rather than write an empty grid the networks would then refuse.
expect "away.rec: record 0 at byte 0: 'obs' record: none of its 16 points lies inside the scene bounds" \
  voxelize --output "$tmp/away_voxels.rec" "$tmp/away.rec"
[ ! -e "$tmp/away_voxels.rec" ] || fail "voxelize left its output for an empty scene"
obs 0 0 "$mirror" > "$tmp/mirror.rec"
expect "'front.extrinsics': expected a camera-to-world pose: a proper rotation" qte-select --checkpoint "$ckpt" "$tmp/mirror.rec"
obs 0 0 "$seen" 0,0,2,0,0,2,0,0,1 > "$tmp/zero_focal.rec"
expect "'front.intrinsics': expected positive focal lengths" qte-select --checkpoint "$ckpt" "$tmp/zero_focal.rec"

# qattn-train on the agent's transitions of a blind episode.
{ obs 0 0 "$away"; stream-pack action "depth0.index:i32=1,2,3" "depth0.bounds:f64=-0.3,-0.5,0.6,1.0" \
    "depth1.index:i32=4,5,6" "depth1.bounds:f64=0,0,0.8,0.3" "rotation_bins:i32=0,0,0" gripper_open:u8=1 \
    "pose:f64=0.2,0,0.9,0,0,0,1"; obs 1 1 "$away"; } | keyframe --agent > "$tmp/blind.rec" 2>/dev/null || fail "keyframe --agent"
expect "blind.rec: record [0-9]* at byte [0-9]*: 'frame' record: none of its 16 points lies inside the scene bounds" \
  qattn-train --steps 1 --batch 1 --start-after 1 --seed 1 --checkpoint-dir "$tmp/blind_ckpt" "$tmp/blind.rec"
echo "empty scene ok"
