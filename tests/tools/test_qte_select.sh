#!/usr/bin/env bash
# qte-select: the acting loop closed by a FIFO; an action after every non-terminal observation,
# everything else passed through; actions consistent with the coarse-to-fine geometry;
# determinism, exploration, K, --reload, --png, and errors.
source "$(dirname "$0")/common.sh"
src=${QTE_SOURCE:?set QTE_SOURCE to the repository}
# LibTorch's OpenMP threads spin while they wait for each other: with another busy process on a
# 2-core machine (tests run in parallel) a forward then takes about a second instead of 20 ms.
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}

# Fresh networks for the transitions of one demonstration.
cp "$src/tests/data/reach_target_demo.rec" "$tmp/demos.rec"  # one demonstration (tests/data/make_data.sh)
keyframe "$tmp/demos.rec" > "$tmp/transitions.rec" 2>/dev/null || fail "keyframe"
qattn-train --steps 0 --seed 1 --checkpoint-dir "$tmp/ckpt" "$tmp/transitions.rec" 2>/dev/null \
  || fail "qattn-train --steps 0: exit $?"
ckpt=$tmp/ckpt/latest.rec
[ -s "$ckpt" ] || fail "qattn-train wrote no $ckpt"

# The acting loop: sim-step -> qte-select -> plan-path -> back into sim-step through a FIFO,
# sim-step's observations kept by tee. It ends when sim-step has run its episodes: sim-step
# closes its output, the others see the end of the stream and finish, and nobody meets a
# closed pipe. (The deadline is around a shell: `timeout` wrapped around sim-step alone would
# hold sim-step's output open and keep the loop from ending.)
mkfifo "$tmp/loop"
timeout 120 bash -c 'sim-step --task reach_target --episodes 2 --seed 3 --image-size 64x64 < "$1/loop" \
  | tee "$1/episodes.rec" | qte-select --checkpoint "$2" | plan-path --time-budget 0.3 > "$1/loop"
  echo "${PIPESTATUS[*]}" > "$1/loop_status"' _ "$tmp" "$ckpt" || fail "the loop did not end (exit $?)"
[ "$(cat "$tmp/loop_status")" = "0 0 0 0" ] || fail "loop exit statuses $(cat "$tmp/loop_status")"
terminals=$(stream-dump --json --type obs "$tmp/episodes.rec" | grep -c '"name":"terminal","dtype":"uint8","shape":\[\],"values":\[1\]')
[ "$terminals" = 2 ] || fail "the loop gave $terminals terminal observations, expected 2"

# Every record passes through unchanged and in order; other record types included.
{ stream-pack reset task=reach_target seed:i64=3; cat "$tmp/episodes.rec"; stream-pack metrics step:i64=7; } > "$tmp/in.rec"
qte-select --checkpoint "$ckpt" --seed 5 "$tmp/in.rec" > "$tmp/greedy.rec" 2> "$tmp/err" || fail "qte-select exit $?"
[ ! -s "$tmp/err" ] || fail "unexpected stderr: $(cat "$tmp/err")"
stream-cat --exclude action "$tmp/greedy.rec" | cmp -s - "$tmp/in.rec" || fail "records not passed through unchanged"

# The actions, checked with the NumPy reader: CHECK FILE K EXPLORED(0, 1 or any)
check() {
  $py - "$src/lib/python" "$@" <<'EOF' || fail "action check of $1 (k $2, explored $3)"
import sys
import numpy as np
sys.path.insert(0, sys.argv[1])
from qte_stream import read_records
path, k, explored = sys.argv[2], int(sys.argv[3]), sys.argv[4]
records = list(read_records(path))
fields = ["pose", "gripper_open", "ignore_collisions"]
for d in range(2):
    fields += [f"depth{d}.index", f"depth{d}.bounds", f"depth{d}.centre", f"depth{d}.q_value"]
    fields += ["depth0.argmax_index"] if d == 0 else []  # non-leaf depths: the grid's own best voxel
fields += ["rotation_bins", "value", "k", "branches", "explored", "checkpoint_step", "step"]
def bad(i, what):
    sys.exit(f"{path}: record {i}: {what}")
def rotation(bins):  # Euler 'xyz': R = Rz(c) Ry(b) Rx(a), angle = bin * 5 - 180 degrees
    a, b, c = np.radians(np.asarray(bins) * 5.0 - 180.0)
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rz = np.array([[np.cos(c), -np.sin(c), 0], [np.sin(c), np.cos(c), 0], [0, 0, 1]])
    return rz @ ry @ rx
def quaternion_matrix(x, y, z, w):
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
actions = 0
for i, r in enumerate(records):
    wants_action = r.type == "obs" and int(r.fields["terminal"]) == 0
    following = records[i + 1] if i + 1 < len(records) else None
    if wants_action != (following is not None and following.type == "action"):
        bad(i, f"'{r.type}' followed by '{following.type if following else 'the end'}'")
    if r.type != "action":
        continue
    actions += 1
    a, f = r.fields, records[i - 1].fields
    if list(a) != fields:
        bad(i, f"fields {list(a)}")
    pose = a["pose"]
    if pose.dtype != np.float64 or pose.shape != (7,) or abs(np.linalg.norm(pose[3:]) - 1) > 1e-9:
        bad(i, f"pose {pose}")
    bins = a["rotation_bins"]
    if not ((bins >= 0) & (bins < 72)).all():
        bad(i, f"rotation bins {bins}")
    if not np.allclose(quaternion_matrix(*pose[3:]), rotation(bins), atol=1e-9):
        bad(i, f"quaternion {pose[3:]} is not the rotation of bins {bins}")
    if int(a["step"]) != int(f["step"]) or int(a["k"]) != k or int(a["checkpoint_step"]) != 0:
        bad(i, "step, k or checkpoint_step")
    if list(a["branches"]) != [k]:  # a fixed K expands K grids at depth 1, explored or not
        bad(i, f"branches {list(a['branches'])}")
    if int(a["gripper_open"]) not in (0, 1) or int(a["ignore_collisions"]) != 0:
        bad(i, "gripper_open or ignore_collisions")
    if explored != "any" and int(a["explored"]) != int(explored):
        bad(i, f"explored {int(a['explored'])}")
    if not np.array_equal(a["depth0.bounds"], [-0.3, -0.5, 0.6, 1.0]):
        bad(i, f"depth 0 bounds {a['depth0.bounds']}")
    q = []
    for d in range(2):
        index, bounds, centre = a[f"depth{d}.index"], a[f"depth{d}.bounds"], a[f"depth{d}.centre"]
        if index.dtype != np.int32 or not ((index >= 0) & (index < 16)).all():
            bad(i, f"depth {d} index {index}")
        if not np.allclose(centre, bounds[:3] + (index + 0.5) * bounds[3] / 16, atol=1e-12):
            bad(i, f"depth {d} centre {centre} is not voxel {index}'s of {bounds}")
        q.append(float(a[f"depth{d}.q_value"]))
    # Depth 0's argmax: a voxel of its grid; the one taken when nothing can overrule it.
    argmax = a["depth0.argmax_index"]
    if argmax.dtype != np.int32 or not ((argmax >= 0) & (argmax < 16)).all():
        bad(i, f"depth 0 argmax {argmax}")
    if k == 1 and int(a["explored"]) == 0 and not np.array_equal(argmax, a["depth0.index"]):
        bad(i, f"K = 1 took {a['depth0.index']}, not depth 0's argmax {argmax}")
    # Depth 1 is centre +- 0.15 around depth 0's chosen voxel; the pose is depth 1's voxel.
    if not np.allclose(a["depth1.bounds"], list(a["depth0.centre"] - 0.15) + [0.3], atol=1e-12):
        bad(i, f"depth 1 bounds {a['depth1.bounds']} not around depth 0's voxel {a['depth0.centre']}")
    if not np.array_equal(pose[:3], a["depth1.centre"]):
        bad(i, "the pose is not the last depth's voxel centre")
    value = np.float32((np.float32(q[0]) + np.float32(q[1])) / np.float32(2))
    if abs(float(a["value"]) - float(value)) > 1e-6:
        bad(i, f"value {float(a['value'])}, the Q-values {q} give {value}")
if actions == 0:
    sys.exit(f"{path}: no actions")
EOF
}
check "$tmp/greedy.rec" 10 0

# Same inputs and seed, same bytes; with exploration too, which depends on the seed.
qte-select --checkpoint "$ckpt" --seed 5 < "$tmp/in.rec" | cmp -s - "$tmp/greedy.rec" || fail "same seed, different bytes"
explore=(--k 3 --epsilon 0.5 --index-noise 1 --rotation-noise 2 --gripper-flip 0.3)
qte-select --checkpoint "$ckpt" "${explore[@]}" --seed 9 "$tmp/in.rec" > "$tmp/noisy.rec" || fail "exploration exit $?"
check "$tmp/noisy.rec" 3 any
qte-select --checkpoint "$ckpt" "${explore[@]}" --seed 9 "$tmp/in.rec" | cmp -s - "$tmp/noisy.rec" \
  || fail "exploration with the same seed, different bytes"
qte-select --checkpoint "$ckpt" "${explore[@]}" --seed 10 "$tmp/in.rec" | cmp -s - "$tmp/noisy.rec" \
  && fail "exploration ignores the seed"
# --epsilon 1: a random voxel at every depth, so every action differs from the greedy one.
qte-select --checkpoint "$ckpt" --k 3 --epsilon 1 "$tmp/in.rec" > "$tmp/random.rec" || fail "--epsilon 1 exit $?"
check "$tmp/random.rec" 3 1

# K = 1 is C2F-ARM's greedy choice: valid actions, and the K = 10 tree is worth at least as much.
qte-select --checkpoint "$ckpt" --k 1 "$tmp/in.rec" > "$tmp/k1.rec" || fail "--k 1 exit $?"
check "$tmp/k1.rec" 1 0
value() { stream-dump --json --type action "$1" | grep -o '"name":"value","dtype":"float32","shape":\[\],"values":\[[^]]*' | grep -o '[^[]*$'; }
paste -d' ' <(value "$tmp/k1.rec") <(value "$tmp/greedy.rec") | awk '$2 < $1 - 1e-5 { bad = 1 } END { exit bad }' \
  || fail "a K = 10 value below the greedy one: $(paste -d' ' <(value "$tmp/k1.rec") <(value "$tmp/greedy.rec") | tr '\n' ';')"

# --k auto: a margin wider than any Q range is K = --k-max (the same bytes as --k 10); margin 0
# is the greedy choice (the poses of --k 1, one branch); in between, 1 to K_max per action.
qte-select --checkpoint "$ckpt" --k auto --k-margin 1e9 --k-max 10 --seed 5 "$tmp/in.rec" | cmp -s - "$tmp/greedy.rec" \
  || fail "--k auto with an unbounded margin differs from --k 10"
qte-select --checkpoint "$ckpt" --k auto --k-margin 0 "$tmp/in.rec" > "$tmp/auto0.rec" || fail "--k auto exit $?"
qte-select --checkpoint "$ckpt" --k auto --k-mass 0.5 --k-max 4 "$tmp/in.rec" > "$tmp/mass.rec" || fail "--k-mass exit $?"
$py - "$src/lib/python" "$tmp/greedy.rec" "$tmp/k1.rec" "$tmp/auto0.rec" "$tmp/mass.rec" <<'EOF2' || fail "--k auto's branches"
import sys
import numpy as np
sys.path.insert(0, sys.argv[1])
from qte_stream import read_records
actions = [[r for r in read_records(path) if r.type == "action"] for path in sys.argv[2:]]
greedy, k1, auto0, mass = actions
assert all(list(a.fields["branches"]) == [10] for a in greedy), "--k 10 expands 10 at depth 1"
for a, b in zip(k1, auto0):
    assert list(b.fields["branches"]) == [1], "margin 0: one branch"
    assert np.array_equal(a.fields["pose"], b.fields["pose"]), "margin 0: the greedy pose"
assert all(1 <= int(a.fields["branches"][0]) <= 4 for a in mass), "--k-max 4 bounds the branches"
EOF2
# Without auto, the rule's options are refused; auto needs a rule.
qte-select --checkpoint "$ckpt" --k 3 --k-margin 1 "$tmp/in.rec" > /dev/null 2>&1 && fail "--k-margin without auto accepted"
qte-select --checkpoint "$ckpt" --k auto "$tmp/in.rec" > /dev/null 2>&1 && fail "--k auto without a rule accepted"

# --ignore-collisions and --png.
first_obs() { stream-cat --type obs --head 1 "$tmp/episodes.rec"; }
first_obs | qte-select --checkpoint "$ckpt" --ignore-collisions --png "$tmp/png" \
  | stream-dump --json --type action | grep -q '"name":"ignore_collisions","dtype":"uint8","shape":\[\],"values":\[1\]' \
  || fail "--ignore-collisions"
[ -s "$tmp/png/000000.depth0.png" ] && [ -s "$tmp/png/000000.depth1.png" ] || fail "--png wrote no pictures"

# An episode video with the attention pictures of each action beside the camera (stream-png
# --video): one frame per observation, the camera and two 256-pixel panels wide. MP4's sample
# table and sample entry read here; the decoders' read-back is in tests/unit/video.
qte-select --checkpoint "$ckpt" --png "$tmp/attention" "$tmp/episodes.rec" > /dev/null || fail "qte-select --png on episodes"
stream-png --video "$tmp/episodes.mp4" --fps 4 --attention "$tmp/attention" "$tmp/episodes.rec" || fail "stream-png --video"
# A directory of pictures that is not there is an error, not a video without them.
err=$(stream-png --video "$tmp/none.mp4" --fps 4 --attention "$tmp/no-such-dir" "$tmp/episodes.rec" 2>&1); rc=$?
[ $rc = 2 ] && grep -q "no-such-dir: no such directory" <<<"$err" && [ ! -e "$tmp/none.mp4" ] \
  || fail "--attention with a missing directory: exit $rc, '$err'"
stream-png --video "$tmp/episodes.gif" --height 64 "$tmp/episodes.rec" || fail "stream-png --video .gif"
observations=$(stream-dump --summary --type obs "$tmp/episodes.rec" | cut -f2 | cut -d' ' -f1)
$py - "$tmp/episodes.mp4" "$tmp/episodes.gif" "$observations" <<'EOF2' || fail "episode video"
import struct, sys
mp4 = open(sys.argv[1], "rb").read()
frames = struct.unpack(">I", mp4[mp4.index(b"stsz") + 12:][:4])[0]
entry = mp4.index(b"mp4v")
width, height = struct.unpack(">HH", mp4[entry + 28:entry + 32])
assert frames == int(sys.argv[3]), f"{frames} frames for {sys.argv[3]} observations"
assert (width, height) == (3 * 256, 256), f"frame {width}x{height}"  # 64x64 camera + two pictures
gif = open(sys.argv[2], "rb").read()
assert gif[:6] == b"GIF89a" and struct.unpack("<HH", gif[6:10]) == (64, 64), "GIF header"
EOF2

# --reload: the checkpoint replaced between two episodes is loaded at the second one's start.
qattn-train --steps 0 --seed 2 --checkpoint-dir "$tmp/ckpt2" "$tmp/transitions.rec" 2>/dev/null || fail "qattn-train --seed 2"
cp "$ckpt" "$tmp/live.rec"
mkfifo "$tmp/actor_in"
qte-select --checkpoint "$tmp/live.rec" --reload < "$tmp/actor_in" > "$tmp/reloaded.rec" 2> "$tmp/reload.err" &
actor=$!
exec 3> "$tmp/actor_in"
first_obs >&3
for _ in $(seq 100); do
  stream-dump --summary "$tmp/reloaded.rec" 2>/dev/null | grep -q '^action' && break
  sleep 0.1
done
cp "$tmp/ckpt2/latest.rec" "$tmp/live.tmp" && mv "$tmp/live.tmp" "$tmp/live.rec"
first_obs >&3
exec 3>&-
wait $actor || fail "qte-select --reload exit $?"
[ "$(cat "$tmp/reload.err")" = "qte-select: loaded checkpoint $tmp/live.rec at training step 0" ] \
  || fail "--reload said: $(cat "$tmp/reload.err")"
stream-dump --json --type action "$tmp/reloaded.rec" | grep -o '"fields":.*' > "$tmp/two.json"
[ "$(wc -l < "$tmp/two.json")" = 2 ] || fail "--reload: expected two actions"
[ "$(sed -n 1p "$tmp/two.json")" != "$(sed -n 2p "$tmp/two.json")" ] || fail "--reload: the new networks chose the same"

# A minimal observation: two points, one of them NaN (a pixel without a return: no point).
stream-pack obs "front.rgb:u8[1,2,3]=200,10,10,10,200,10" "front.points:f32[1,2,3]=0.1,0,0.8,nan,nan,nan" \
  gripper_open:u8=1 gripper_opening_m:f64=0.085 step:i32=3 terminal:u8=0 > "$tmp/packed.rec"
qte-select --checkpoint "$ckpt" --k 2 "$tmp/packed.rec" > "$tmp/packed_action.rec" || fail "packed obs: exit $?"
check "$tmp/packed_action.rec" 2 0

# Errors: a missing checkpoint names it; options that disagree with it are usage errors;
# an observation without cameras is a stream error naming the record.
err=$(qte-select --checkpoint "$tmp/none.rec" < "$tmp/in.rec" 2>&1 >/dev/null); rc=$?
[ $rc = 1 ] && grep -q "cannot open $tmp/none.rec" <<<"$err" || fail "missing checkpoint: exit $rc: $err"
err=$(qte-select --checkpoint "$ckpt" --voxels 32 < "$tmp/in.rec" 2>&1 >/dev/null); rc=$?
[ $rc = 2 ] && grep -q -- "--voxels 32 differs from the checkpoint's 16" <<<"$err" || fail "--voxels 32: exit $rc: $err"
err=$(qte-select --checkpoint "$ckpt" --depths 3 < "$tmp/in.rec" 2>&1 >/dev/null); rc=$?
[ $rc = 2 ] && grep -q -- "--depths 3 differs from the checkpoint's 2" <<<"$err" || fail "--depths 3: exit $rc: $err"
err=$(qte-select --checkpoint "$ckpt" --bounds=-0.3,-0.5,0.7,1.0 < "$tmp/in.rec" 2>&1 >/dev/null); rc=$?
[ $rc = 2 ] && grep -q -- "--bounds -0.3,-0.5,0.7,1.0 differs from the bounds the checkpoint was trained on" <<<"$err" \
  || fail "other --bounds: exit $rc: $err"
err=$(qte-select --checkpoint "$ckpt" --offset 0.1 < "$tmp/in.rec" 2>&1 >/dev/null); rc=$?
[ $rc = 2 ] && grep -q -- "--offset 0.1 differs from the offsets the checkpoint was trained on" <<<"$err" \
  || fail "other --offset: exit $rc: $err"
qte-select --checkpoint "$ckpt" --bounds=-0.3,-0.5,0.6,1.0 --offset 0.15 --seed 5 "$tmp/in.rec" | cmp -s - "$tmp/greedy.rec" \
  || fail "the checkpoint's own --bounds and --offset changed the actions"
# Integers that would wrap when narrowed are refused (4294967297 used to run as k = 1).
err=$(qte-select --checkpoint "$ckpt" --k 4294967297 < "$tmp/in.rec" 2>&1 >/dev/null); rc=$?
[ $rc = 2 ] && grep -q -- "--k must be 1..4096, got 4294967297" <<<"$err" || fail "--k 2^32 + 1: exit $rc: $err"
err=$(demo-record --task reach_target --episodes 4294967297 --output "$tmp/x.rec" 2>&1); rc=$?
[ $rc = 2 ] && grep -q -- "--episodes must be 1..1000000" <<<"$err" || fail "--episodes 2^32 + 1: exit $rc: $err"
err=$(voxelize --voxels 4294967312 < "$tmp/in.rec" 2>&1 >/dev/null); rc=$?
[ $rc = 2 ] && grep -q -- "--voxels must be 2..256" <<<"$err" || fail "--voxels 2^32 + 16: exit $rc: $err"
err=$(qte-select < "$tmp/in.rec" 2>&1 >/dev/null); rc=$?
[ $rc = 2 ] && grep -q -- "--checkpoint FILE is required" <<<"$err" || fail "no --checkpoint: exit $rc: $err"
err=$(stream-pack obs step:i32=0 terminal:u8=0 | qte-select --checkpoint "$ckpt" 2>&1 >/dev/null); rc=$?
[ $rc = 1 ] && grep -q "<stdin>: record 0 at byte 0: 'obs' record has no camera image" <<<"$err" \
  || fail "obs without cameras: exit $rc: $err"
echo "qte-select ok"
