#!/usr/bin/env bash
# A program that fails leaves no partial output: the several files of stream-png, xarm-export,
# stream-dump --npy/--pcd, voxelize --png and qte-select --png appear all or none (a directory
# that was there keeps what it had; one the run created goes again); plan-path writes no
# --output when its --octomap cannot be written; qattn-train leaves no initial checkpoint when
# its --metrics cannot be written. An output path that is a symbolic link is followed.
source "$(dirname "$0")/common.sh"
src=${QTE_SOURCE:?set QTE_SOURCE to the repository}
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}

# expect_failure WORDS COMMAND...: exit 1 with one line holding WORDS.
expect_failure() {
  local words=$1; shift
  local err rc; err=$("$@" 2>&1 >/dev/null); rc=$?
  [ "$rc" = 1 ] || fail "$*: exit $rc, expected 1 ($err)"
  [ "$(wc -l <<<"$err")" = 1 ] || fail "$*: more than one line: $err"
  grep -q -- "$words" <<<"$err" || fail "$*: said '$err', expected '$words'"
}
# unchanged DIR LISTING: DIR holds exactly the files of LISTING (no staging directory either).
listing() { (cd "$1" && ls -A | tr '\n' ' '); }

# Two observations, then damage: the third record's payload is corrupted.
obs=$src/tests/data/pick_and_lift_obs.rec
cat "$obs" "$obs" "$obs" > "$tmp/three.rec"
size=$(stat -c %s "$obs")
printf 'XXXX' | dd of="$tmp/three.rec" bs=1 seek=$(( 2 * size + size / 2 )) conv=notrunc status=none

# stream-png: into a new directory (removed again) and into one holding a file (kept as it was).
expect_failure "three.rec: record 2" stream-png --depth --dir "$tmp/new" "$tmp/three.rec"
[ ! -e "$tmp/new" ] || fail "stream-png left $tmp/new: $(listing "$tmp/new")"
mkdir "$tmp/old" && echo before > "$tmp/old/000000.front.rgb.png"
expect_failure "three.rec: record 2" stream-png --dir "$tmp/old" "$tmp/three.rec"
[ "$(listing "$tmp/old")" = "000000.front.rgb.png " ] || fail "stream-png left in old/: $(listing "$tmp/old")"
[ "$(cat "$tmp/old/000000.front.rgb.png")" = before ] || fail "stream-png replaced a file of a run that failed"
stream-png --dir "$tmp/old" "$obs" || fail "stream-png on whole input"
file "$tmp/old/000000.front.rgb.png" | grep -q PNG || fail "a successful run did not replace the old file"

# stream-dump --npy and --pcd (one directory for both) on the same damage.
expect_failure "three.rec: record 2" stream-dump --summary --npy "$tmp/arrays" --pcd "$tmp/arrays" "$tmp/three.rec"
[ ! -e "$tmp/arrays" ] || fail "stream-dump left $tmp/arrays: $(listing "$tmp/arrays")"
stream-dump --summary --npy "$tmp/arrays" --pcd "$tmp/arrays" "$obs" > /dev/null || fail "stream-dump --npy --pcd"
ls "$tmp/arrays" | grep -q '^000000\..*\.pcd$' && ls "$tmp/arrays" | grep -q '^obs\..*\.npy$' || fail "stream-dump wrote $(listing "$tmp/arrays")"

# voxelize --png.
expect_failure "three.rec: record 2" voxelize --png "$tmp/grids" --output "$tmp/voxels.rec" "$tmp/three.rec"
[ ! -e "$tmp/grids" ] && [ ! -e "$tmp/voxels.rec" ] || fail "voxelize left its outputs"

# xarm-export: the first motion is fine, the second leaves the joint limits.
joints="0,0,0,0,0,0,0,0.1,0,0,0,0,0,0"
stream-pack trajectory time_s:f64[2]=0,1 "joint_positions:f64[2,7]=$joints" gripper_open:u8=1 > "$tmp/moves.rec"
stream-pack trajectory time_s:f64[2]=0,1 "joint_positions:f64[2,7]=0,0,0,0,0,0,0,9,0,0,0,0,0,0" gripper_open:u8=1 >> "$tmp/moves.rec"
expect_failure "moves.rec: record 1" xarm-export --dir "$tmp/arm" "$tmp/moves.rec"
[ ! -e "$tmp/arm" ] || fail "xarm-export left $(listing "$tmp/arm")"
stream-cat --head 1 "$tmp/moves.rec" | xarm-export --dir "$tmp/arm" || fail "xarm-export of one good move"
[ "$(listing "$tmp/arm")" = "000000.xarm.csv " ] || fail "xarm-export wrote $(listing "$tmp/arm")"

# A signal while the files are staged: none appear, the directory created goes again.
big=$tmp/many.rec
for i in $(seq 1 40); do cat "$obs"; done > "$big"
mkfifo "$tmp/slow"
( cat "$big"; sleep 30 ) > "$tmp/slow" &
feeder=$!
stream-png --dir "$tmp/signalled" "$tmp/slow" &
pid=$!
for _ in $(seq 100); do [ -d "$tmp/signalled" ] && [ -n "$(ls -A "$tmp/signalled"/.qte-staging.tmp.*/ 2>/dev/null)" ] && break; sleep 0.1; done
kill -TERM "$pid"; wait "$pid" 2>/dev/null
kill "$feeder" 2>/dev/null; wait "$feeder" 2>/dev/null
[ ! -e "$tmp/signalled" ] || fail "SIGTERM left $tmp/signalled: $(ls -AR "$tmp/signalled" | head -5)"

# plan-path: an --octomap that cannot be written leaves no --output.
stream-pack action pose:f64=0.1,0.0,1.15,1,0,0,0 gripper_open:u8=1 > "$tmp/action.rec"
cat "$obs" "$tmp/action.rec" > "$tmp/to_plan.rec"
expect_failure "$tmp/no/such/dir/scene.bt" plan-path --octomap "$tmp/no/such/dir/scene.bt" --output "$tmp/planned.rec" "$tmp/to_plan.rec"
[ ! -e "$tmp/planned.rec" ] || fail "plan-path left --output behind a failed --octomap"

# qattn-train: a --metrics that cannot be written leaves no checkpoint.
keyframe "$src/tests/data/reach_target_demo.rec" > "$tmp/transitions.rec" 2>/dev/null || fail "keyframe"
expect_failure "$tmp/no/such/dir/train.csv" qattn-train --steps 0 --checkpoint-dir "$tmp/ckpt" --metrics "$tmp/no/such/dir/train.csv" "$tmp/transitions.rec"
[ -z "$(ls -A "$tmp/ckpt" 2>/dev/null)" ] || fail "qattn-train left $(listing "$tmp/ckpt") behind a failed --metrics"
# A metrics file that is not one is named with its line when a run resumes; a fresh run replaces it.
qattn-train --steps 0 --checkpoint-dir "$tmp/ckpt" "$tmp/transitions.rec" 2>/dev/null || fail "qattn-train --steps 0"
printf 'step,loss\n0,1\nnot a number,2\n' > "$tmp/foreign.csv"
qattn-train --resume --steps 0 --checkpoint-dir "$tmp/ckpt" --metrics "$tmp/foreign.csv" "$tmp/transitions.rec" 2> "$tmp/err" \
  && fail "a foreign metrics file was taken up"
tail -1 "$tmp/err" | grep -q "foreign.csv: line 3: expected a step number" || fail "said $(cat "$tmp/err")"

# Symbolic links are followed: the file they name gets the bytes, the link stays.
mkdir "$tmp/disk" && ln -s disk/actual.rec "$tmp/link.rec"
stream-cat --output "$tmp/link.rec" "$obs" || fail "stream-cat onto a dangling link"
[ -L "$tmp/link.rec" ] || fail "the link was replaced by a file"
cmp -s "$tmp/disk/actual.rec" "$obs" || fail "the link's target did not get the bytes"
stream-cat --output "$tmp/link.rec" "$tmp/action.rec" && cmp -s "$tmp/disk/actual.rec" "$tmp/action.rec" \
  || fail "writing again through the link"
echo "partial outputs: ok"
