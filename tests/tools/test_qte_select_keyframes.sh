#!/usr/bin/env bash
# qte-select --keyframes: the agent without networks acts with the expert's keyframes as keyframe
# discretized them. On 3 pick_and_lift evaluation scenes (the expert's recording and keyframe's
# transitions of them), in the acting loop with plan-path: an action after every non-terminal
# observation; episode n's step s is demonstration n's keyframe s, found here by following
# frame -> next_frame from frame 0; its pose is the centre of that keyframe's last-depth voxel
# (computed here from the index and the grid's bounds), within half a voxel of the expert's own
# pose, turned by the keyframe's rotation bins (Euler xyz, 5 degrees, computed here); the
# gripper command is the keyframe's. The expert solves the scenes and so does its discretized
# self. Errors: more episodes than demonstrations, both --checkpoint and --keyframes, a file
# without transitions: exit status and one line naming what is wrong.
source "$(dirname "$0")/common.sh"
src=${QTE_SOURCE:?set QTE_SOURCE to the repository}
export PYTHONPATH="$src/lib/python"
scenes=(--task pick_and_lift --variation 0 --episodes 3 --seed 1000000 --scenes eval --image-size 64x64)

demo-record "${scenes[@]}" --output "$tmp/experts.rec" 2> "$tmp/demo.err" || fail "demo-record: $(cat "$tmp/demo.err")"
grep -q 'expert success 3/3' "$tmp/demo.err" || fail "the expert did not solve the scenes: $(tail -1 "$tmp/demo.err")"
keyframe --output "$tmp/keyframes.rec" "$tmp/experts.rec" 2>/dev/null || fail "keyframe"

mkfifo "$tmp/loop"
timeout 300 bash -c 'sim-step "${@:3}" < "$1/loop" | tee "$1/episodes.rec" | qte-select --keyframes "$2" \
  | plan-path | tee "$1/loop" > "$1/agent.rec"; echo "${PIPESTATUS[*]}" > "$1/status"' _ "$tmp" "$tmp/keyframes.rec" \
  "${scenes[@]}" || fail "the loop did not end (exit $?)"
[ "$(cat "$tmp/status")" = "0 0 0 0 0" ] || fail "loop exit statuses $(cat "$tmp/status")"

$py - "$tmp/keyframes.rec" "$tmp/episodes.rec" "$tmp/agent.rec" <<'PY' || fail "the keyframe actions"
import math, sys
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
assert len(episodes) == 3 and all(len(c) >= 3 for c in episodes), [len(c) for c in episodes]

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

records = list(qte_stream.read_records(sys.argv[3]))
episode, checked, last = -1, 0, len(records) - 1
for i, r in enumerate(records):
    if r.type != "obs" or r.fields["terminal"]:
        continue
    step = int(r.fields["step"])
    episode += step == 0
    action = records[i + 1]
    assert action.type == "action", (i, action.type)
    a = action.fields
    t = episodes[episode][min(step, len(episodes[episode]) - 1)]
    last_depth = max(int(n[5:].split(".")[0]) for n in t if n.startswith("depth") and n.endswith(".index"))
    bounds, index = t[f"depth{last_depth}.bounds"], t[f"depth{last_depth}.index"]
    voxel = bounds[3] / int(t["voxels"])
    centre = bounds[:3] + (index + 0.5) * voxel
    assert np.allclose(a["pose"][:3], centre, atol=1e-9), (episode, step, a["pose"][:3], centre)
    assert np.all(np.abs(a["pose"][:3] - t["target_pose"][:3]) <= voxel / 2 + 1e-9), (episode, step)
    assert np.allclose(matrix(a["pose"][3:]), rotation(t["rotation_bins"]), atol=1e-9), (episode, step)
    assert a["gripper_open"] == t["gripper_open"] and list(a["rotation_bins"]) == list(t["rotation_bins"])
    assert a["checkpoint_step"] == -1 and a["value"] == 0 and a["depth0.q_value"] == 0
    checked += 1
assert episode == 2 and checked >= 9, (episode, checked)
successes = sum(1 for r in qte_stream.read_records(sys.argv[2]) if r.type == "obs" and r.fields["terminal"]
                and r.fields["success"])
assert successes == 3, f"the discretized expert solved {successes} of 3 scenes"
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
qte-select --keyframes "$tmp/experts.rec" < /dev/null > /dev/null 2> "$tmp/err" && fail "a file without transitions"
grep -q "$tmp/experts.rec: no 'transition' records" "$tmp/err" || fail "no transitions: $(cat "$tmp/err")"
qte-select < /dev/null > /dev/null 2> "$tmp/err"; [ $? = 2 ] || fail "no agent accepted"
echo "qte-select --keyframes ok: the expert's discretized keyframes, step by step, solve its scenes; errors"
