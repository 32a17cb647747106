#!/usr/bin/env bash
# qte-select --keyframes: the agent without networks acts with the expert's keyframes as keyframe
# discretized them. On 3 pick_and_lift evaluation scenes (the expert's recording and keyframe's
# transitions of them), in the acting loop with plan-path: an action after every non-terminal
# observation; episode n's step s is demonstration n's keyframe s, found here by following
# frame -> next_frame from frame 0; its pose is the centre of that keyframe's last-depth voxel
# (computed here from the index and the grid's bounds), within half a voxel of the expert's own
# pose, turned by the keyframe's rotation bins (Euler xyz, 5 degrees, computed here); the
# gripper command is the keyframe's; ignore_collisions is the agent's (--ignore-collisions),
# never the expert's. The expert solves the scenes and so does its discretized self. On other
# scenes, where the episodes outlast the keyframes, the last keyframe again. With
# --rotation-offset, every action's bins are the keyframe's plus the offset, wrapped around, and
# its pose turned by them. Errors: more
# episodes than demonstrations, both --checkpoint and --keyframes, a network option, a file
# without transitions, --rotation-offset with networks or out of range: exit status and one line
# naming what is wrong.
source "$(dirname "$0")/common.sh"
src=${QTE_SOURCE:?set QTE_SOURCE to the repository}
export PYTHONPATH="$src/lib/python"
demo-record --task pick_and_lift --variation 0 --episodes 3 --seed 1000000 --scenes eval --image-size 64x64 --output "$tmp/experts.rec" 2> "$tmp/demo.err" || fail "demo-record: $(cat "$tmp/demo.err")"
grep -q 'expert success 3/3' "$tmp/demo.err" || fail "the expert did not solve the scenes: $(tail -1 "$tmp/demo.err")"
keyframe --keep-failed --no-crop-augmentation --output "$tmp/keyframes.rec" "$tmp/experts.rec" 2>/dev/null || fail "keyframe"

loop() {  # SEED OUT [QTE-SELECT OPTIONS...]: 3 pick_and_lift scenes of seed SEED acted with the keyframes
  rm -f "$tmp/loop" && mkfifo "$tmp/loop"
  timeout 300 bash -c 'sim-step --task pick_and_lift --variation 0 --episodes 3 --seed "$3" --scenes eval --image-size 64x64 \
    < "$1/loop" | tee "$1/$4.episodes.rec" | qte-select --keyframes "$2" "${@:5}" | plan-path | tee "$1/loop" > "$1/$4"
    echo "${PIPESTATUS[*]}" > "$1/status"' _ "$tmp" "$tmp/keyframes.rec" "$@" || fail "the loop did not end (exit $?)"
  [ "$(cat "$tmp/status")" = "0 0 0 0 0" ] || fail "loop exit statuses $(cat "$tmp/status")"
}
loop 1000000 agent.rec
loop 2000000 elsewhere.rec --ignore-collisions  # other scenes: the episodes outlast the keyframes
loop 1000000 offset.rec --rotation-offset 0,-1,71  # 71 wraps a bin 0 keyframe's yaw round to 71

$py - "$tmp/keyframes.rec" "$tmp" <<'PY' || fail "the keyframe actions"
import math, os, sys
import numpy as np
import qte_stream

transitions = [r.fields for r in qte_stream.read_records(sys.argv[1]) if r.type == "transition"]
episodes = []  # per demonstration, its keyframe transitions in order
for key in dict.fromkeys(int(t["episode_key"]) for t in transitions):
    by_frame = {int(t["frame"]): t for t in transitions if int(t["episode_key"]) == key}
    chain, frame = [], 0
    while frame in by_frame:
        chain.append(by_frame[frame])
        if by_frame[frame]["terminal"]:
            break
        frame = int(by_frame[frame]["next_frame"])
    episodes.append(chain)
assert len(episodes) == 3 and all(len(c) >= 3 and c[-1]["terminal"] for c in episodes), [len(c) for c in episodes]

def rotation(bins):  # Euler xyz from 5-degree bins, R = Rz Ry Rx
    x, y, z = (np.asarray(bins, float) * 5 - 180) * math.pi / 180
    rx = np.array([[1, 0, 0], [0, math.cos(x), -math.sin(x)], [0, math.sin(x), math.cos(x)]])
    ry = np.array([[math.cos(y), 0, math.sin(y)], [0, 1, 0], [-math.sin(y), 0, math.cos(y)]])
    rz = np.array([[math.cos(z), -math.sin(z), 0], [math.sin(z), math.cos(z), 0], [0, 0, 1]])
    return rz @ ry @ rx

def matrix(q):  # x, y, z, w
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])

def check(name, ignore_collisions, offset=(0, 0, 0)):
    """Every action against its keyframe, turned by `offset` bins; (episodes, actions checked,
    actions past the last keyframe)."""
    records = list(qte_stream.read_records(os.path.join(sys.argv[2], name)))
    episode, checked, past = -1, 0, 0
    for i, r in enumerate(records):
        if r.type != "obs" or r.fields["terminal"]:
            continue
        step = int(r.fields["step"])
        episode += step == 0
        action = records[i + 1]
        assert action.type == "action", (i, action.type)
        a = action.fields
        t = episodes[episode][min(step, len(episodes[episode]) - 1)]
        past += step >= len(episodes[episode])
        last_depth = max(int(n[5:].split(".")[0]) for n in t if n.startswith("depth") and n.endswith(".index"))
        bounds, index = t[f"depth{last_depth}.bounds"], t[f"depth{last_depth}.index"]
        voxel = bounds[3] / int(t["voxels"])
        centre = bounds[:3] + (index + 0.5) * voxel
        assert np.allclose(a["pose"][:3], centre, atol=1e-9), (name, episode, step, a["pose"][:3], centre)
        bins = [(int(b) + o) % 72 for b, o in zip(t["rotation_bins"], offset)]
        assert np.allclose(matrix(a["pose"][3:]), rotation(bins), atol=1e-9), (name, episode, step)
        assert a["gripper_open"] == t["gripper_open"] and list(a["rotation_bins"]) == bins, (name, episode, step)
        # the agent's flag, never the expert's (whose grasps are straight-line moves)
        assert a["ignore_collisions"] == ignore_collisions, (name, episode, step)
        assert a["checkpoint_step"] == -1 and a["value"] == 0 and a["depth0.q_value"] == 0
        checked += 1
    return episode + 1, checked, past

# On the demonstrations' own scenes: the crop-free keyframe grids are centred on depth 0's voxel
# as an acting network's are, so the pose is within half a voxel of the expert's own.
assert any(t["ignore_collisions"] for c in episodes for t in c), "the expert's grasps no straight-line moves"
episodes_run, checked, _ = check("agent.rec", 0)
assert episodes_run == 3 and checked >= 9, (episodes_run, checked)
for c in episodes:
    for t in c:
        last_depth = max(int(n[5:].split(".")[0]) for n in t if n.startswith("depth") and n.endswith(".index"))
        bounds, index = t[f"depth{last_depth}.bounds"], t[f"depth{last_depth}.index"]
        voxel = bounds[3] / int(t["voxels"])
        assert np.all(np.abs(bounds[:3] + (index + 0.5) * voxel - t["target_pose"][:3]) <= voxel / 2 + 1e-9)
successes = sum(1 for r in qte_stream.read_records(os.path.join(sys.argv[2], "agent.rec.episodes.rec"))
                if r.type == "obs" and r.fields["terminal"] and r.fields["success"])
assert successes == 3, f"the discretized expert solved {successes} of 3 scenes"
episodes_run, checked, past = check("elsewhere.rec", 1)
assert episodes_run == 3 and past > 0, (episodes_run, checked, past)
episodes_run, checked, _ = check("offset.rec", 0, (0, -1, 71))
assert episodes_run == 3 and checked >= 9, (episodes_run, checked)
PY

# Errors: one line naming the file or option, exit status 1 (input) or 2 (usage).
rm -f "$tmp/loop" && mkfifo "$tmp/loop"
timeout 300 bash -c 'sim-step --task pick_and_lift --episodes 4 --seed 1000000 --scenes eval --image-size 64x64 \
  < "$1/loop" 2>/dev/null | qte-select --keyframes "$1/keyframes.rec" 2> "$1/err" | plan-path 2>/dev/null > "$1/loop"
  echo "${PIPESTATUS[1]}" > "$1/status"' _ "$tmp" || fail "the loop of 4 episodes did not end (exit $?)"
[ "$(cat "$tmp/status")" = 1 ] || fail "a fourth episode was accepted (qte-select exit $(cat "$tmp/status"))"
grep -q "at most 3 episodes: $tmp/keyframes.rec holds 3 demonstrations" "$tmp/err" || fail "episodes error: $(cat "$tmp/err")"
qte-select --keyframes "$tmp/keyframes.rec" --checkpoint x.rec < /dev/null > /dev/null 2> "$tmp/err"
[ $? = 2 ] && grep -q 'leave out --checkpoint' "$tmp/err" || fail "both agents: $(cat "$tmp/err")"
qte-select --keyframes "$tmp/keyframes.rec" --epsilon 0.1 < /dev/null > /dev/null 2> "$tmp/err"
[ $? = 2 ] && grep -q 'leave out --epsilon' "$tmp/err" || fail "exploration without networks: $(cat "$tmp/err")"
qte-select --checkpoint x.rec --rotation-offset 0,0,1 < /dev/null > /dev/null 2> "$tmp/err"
[ $? = 2 ] && grep -q 'rotation-offset is for --keyframes' "$tmp/err" || fail "an offset for networks: $(cat "$tmp/err")"
qte-select --keyframes "$tmp/keyframes.rec" --rotation-offset 0,0,72 < /dev/null > /dev/null 2> "$tmp/err"
[ $? = 2 ] && grep -q 'between -71 and 71 (got 0,0,72)' "$tmp/err" || fail "an offset of a full turn: $(cat "$tmp/err")"
qte-select --keyframes "$tmp/experts.rec" < /dev/null > /dev/null 2> "$tmp/err" && fail "a file without transitions"
grep -q "$tmp/experts.rec: no 'transition' records" "$tmp/err" || fail "no transitions: $(cat "$tmp/err")"
qte-select < /dev/null > /dev/null 2> "$tmp/err"; [ $? = 2 ] || fail "no agent accepted"
echo "qte-select --keyframes ok: the expert's discretized keyframes, step by step, solve its scenes; past its keyframes; a rotation offset; errors"
