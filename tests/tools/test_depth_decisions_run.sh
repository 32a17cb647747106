#!/usr/bin/env bash
# examples/depth_decisions.sh and .py on the simulator's own objects: a real scene
# (sim-step --objects) with actions placed on the target, on a lookalike and away from both
# gives the known table; the acting loop on two reach_prism scenes gives a table whose rows
# add up to the actions qte-select took, whose overruled row counts the actions whose depth-0
# voxel is not depth 0's argmax, and with K = 1 overrules nothing; with PICTURES every action
# has its row, its depths' pictures and the view it was chosen on; a stream without objects is
# refused, naming the option.
source "$(dirname "$0")/common.sh"
src=${QTE_SOURCE:?set QTE_SOURCE to the repository}
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}
export PYTHONPATH="$src/lib/python"

# --- a known answer: lift_numbered_block variation 1, block 2 the target -----------------------
stream-pack reset task=lift_numbered_block variation:i32=1 seed:i64=3 \
  | sim-step --image-size 32x32 --objects > "$tmp/obs.rec" || fail "sim-step --objects"
# An action whose voxels (depth 0 over the 1 m scene, depth 1 the 30 cm around it, 16 per side)
# hold the point WHERE (target, lookalike or away), depth 0's argmax holding ARGMAX's point.
action() {
  $py - "$tmp/obs.rec" "$1" "$2" <<'EOF'
import sys
import numpy as np
import qte_stream
obs = next(r for r in qte_stream.read_records(sys.argv[1]) if r.type == "obs")
objects = {o.name: o for o in qte_stream.scene_objects(obs)}
assert [objects[n].role for n in ("block1", "block2", "block3")] == ["distractor", "target", "distractor"], objects
points = {"target": objects["block2"].pose[:3], "lookalike": objects["block1"].pose[:3],
          "away": (objects["block1"].pose[:3] + objects["block3"].pose[:3]) / 2 + [0, 0, 0.3]}
fields, bounds = [], np.array([-0.3, -0.5, 0.6, 1.0])
for d in range(2):
    edge = bounds[3] / 16
    index = np.floor((points[sys.argv[2]] - bounds[:3]) / edge).astype(int)
    centre = bounds[:3] + (index + 0.5) * edge
    text = lambda v: ",".join(repr(float(x)) for x in v)
    fields += [f"depth{d}.index:i32=" + ",".join(map(str, index)), f"depth{d}.bounds:f64={text(bounds)}",
               f"depth{d}.centre:f64={text(centre)}"]
    if d == 0:
        argmax = np.floor((points[sys.argv[3]] - bounds[:3]) / edge).astype(int)
        fields.append("depth0.argmax_index:i32=" + ",".join(map(str, argmax)))
    bounds = np.concatenate([centre - 0.15, [0.3]])
print(" ".join(fields + ["k:i32=10", "explored:u8=0"]))
EOF
}
{
  cat "$tmp/obs.rec"; stream-pack action $(action target target) || exit 1
  cat "$tmp/obs.rec"; stream-pack action $(action lookalike lookalike) || exit 1
  cat "$tmp/obs.rec"; stream-pack action $(action away target) || exit 1  # overruled, to nowhere
} > "$tmp/known.rec" || fail "building the known actions"
$py "$src/examples/analysis/depth_decisions.py" --label known "$tmp/known.rec" > "$tmp/known.csv" || fail "depth_decisions.py exit $?"
expected='label,k,row,actions,target,lookalike,elsewhere,target_share,lookalike_share,elsewhere_share
known,10,depth0,3,1,1,1,0.333,0.333,0.333
known,10,depth1,3,1,1,1,0.333,0.333,0.333
known,10,depth0_argmax,3,2,1,0,0.667,0.333,0.000
known,10,overruled,1,0,0,1,0.000,0.000,1.000
known,10,overruled_argmax,1,1,0,0,1.000,0.000,0.000'
[ "$(cat "$tmp/known.csv")" = "$expected" ] || fail "the known table: $(cat "$tmp/known.csv")"

# --- the acting loop: fresh networks on two reach_prism scenes ---------------------------------
keyframe "$src/tests/data/reach_target_demo.rec" > "$tmp/transitions.rec" 2>/dev/null || fail "keyframe"
qattn-train --steps 0 --seed 1 --checkpoint-dir "$tmp/ckpt" "$tmp/transitions.rec" 2>/dev/null || fail "qattn-train"
for k in 3 1; do
  PICTURES=$([ $k = 3 ] && echo "$tmp/pictures") AGENT="$tmp/agent$k.rec" timeout 300 bash "$src/examples/depth_decisions.sh" reach_prism "$tmp/ckpt/latest.rec" $k 32x32 2 \
    > "$tmp/k$k.csv" 2> "$tmp/k$k.err" || fail "depth_decisions.sh with K = $k: exit $?: $(cat "$tmp/k$k.err")"
  $py - "$tmp/agent$k.rec" "$tmp/k$k.csv" $k <<'EOF' || fail "the table with K = $k does not add up"
import csv, sys
import numpy as np
import qte_stream
actions = [r for r in qte_stream.read_records(sys.argv[1]) if r.type == "action"]
overruled = sum(not np.array_equal(a.fields["depth0.index"], a.fields["depth0.argmax_index"]) for a in actions)
rows = {r["row"]: r for r in csv.DictReader(open(sys.argv[2]))}
problems = []
if list(rows) != ["depth0", "depth1", "depth0_argmax", "overruled", "overruled_argmax"]:
    problems.append(f"rows {list(rows)}")
for name, r in rows.items():
    n = int(r["actions"])
    want = overruled if name.startswith("overruled") else len(actions)
    if n != want:
        problems.append(f"{name}: {n} actions, the stream has {want}")
    if int(r["target"]) + int(r["lookalike"]) + int(r["elsewhere"]) != n:
        problems.append(f"{name}: the places do not add up to {n}")
    if n and abs(sum(float(r[p + "_share"]) for p in ("target", "lookalike", "elsewhere")) - 1) > 0.002:
        problems.append(f"{name}: the shares do not add up to 1")
    if r["k"] != sys.argv[3]:
        problems.append(f"{name}: k {r['k']}")
if not actions:
    problems.append("no actions")
if sys.argv[3] == "1" and (overruled or [rows["depth0"][p] for p in ("target", "lookalike", "elsewhere")]
                           != [rows["depth0_argmax"][p] for p in ("target", "lookalike", "elsewhere")]):
    problems.append("K = 1 overruled depth 0")
if problems:
    sys.exit("; ".join(problems))
EOF
done
# PICTURES: a row per action, and for each its depths' pictures and the view it was chosen on.
$py - "$tmp/agent3.rec" "$tmp/pictures" <<'EOF' || fail "the pictures of the decisions"
import csv, os, sys
import qte_stream
records = list(qte_stream.read_records(sys.argv[1]))
actions = [r for r in records if r.type == "action"]
rows = list(csv.DictReader(open(os.path.join(sys.argv[2], "actions.csv"))))
problems = [] if len(rows) == len(actions) else [f"{len(rows)} rows for {len(actions)} actions"]
for r in rows:
    obs = records[int(r["obs_record"])]
    if obs.type != "obs" or str(obs.fields["step"]) != r["step"] or str(obs.fields["episode_seed"]) != r["episode_seed"]:
        problems.append(f"action {r['action']}: record {r['obs_record']} is not its observation")
    for name in [f"attention/{int(r['action']):06d}.depth0.png", f"attention/{int(r['action']):06d}.depth1.png",
                 f"frames/{int(r['obs_record']):06d}.front.rgb.png"]:
        if not os.path.isfile(os.path.join(sys.argv[2], name)):
            problems.append(f"no {name}")
if problems:
    sys.exit("; ".join(problems[:5]))
EOF

# --- depths_of_runs.sh: a finished run's settings decide the replay ----------------------------
# A run of label qte-k3-t3 whose demonstrations had a 32x32 camera and whose evaluations had 2
# episodes: its table is depth_decisions.sh's with K = 3, 32x32 and 2 episodes; a run not
# finished (no final checkpoint, or one newer than its eval.csv) gets none, and a table already
# there is kept.
run=$tmp/runs/reach_prism/qte-k3-t3-seed4
mkdir -p "$run/eval" "$tmp/runs/reach_prism/qte-k3-t3-seed5"
cp "$src/tests/data/reach_target_demo.rec" "$run/demos.rec"
cp "$tmp/ckpt/latest.rec" "$run/eval/checkpoint.rec"
printf 'label,seed,env_steps,episodes,successes\nqte-k3-t3,4,0,2,0\n' > "$run/eval.csv"
echo "--approach 0.1" > "$run/plan_options"  # learn.sh's PLAN_OPTIONS, replayed as the run planned
PLAN_OPTIONS="--approach 0.1" AGENT="$tmp/direct.rec" timeout 300 bash "$src/examples/depth_decisions.sh" reach_prism \
  "$tmp/ckpt/latest.rec" 3 32x32 2 qte-k3-t3 > "$tmp/direct.csv" 2>/dev/null || fail "depth_decisions.sh for the run's settings"
[ "$(stream-cat --type trajectory "$tmp/direct.rec" | wc -c)" -gt 0 ] || fail "the direct replay planned nothing"
timeout 300 bash "$src/examples/depths_of_runs.sh" "$tmp/runs" "$tmp/depths" 2> "$tmp/runs.err" \
  || fail "depths_of_runs.sh exit $?: $(cat "$tmp/runs.err")"
[ "$(ls "$tmp/depths")" = reach_prism_qte-k3-t3-seed4.csv ] || fail "depths_of_runs.sh wrote $(ls "$tmp/depths")"
cmp -s "$tmp/direct.csv" "$tmp/depths/reach_prism_qte-k3-t3-seed4.csv" \
  || fail "depths_of_runs.sh's table is not the run's: $(cat "$tmp/depths/reach_prism_qte-k3-t3-seed4.csv")"
# A run resumed past its end (learn.sh with a larger budget) snapshots a newer checkpoint than
# its eval.csv: not finished until it writes eval.csv again, so no table.
cp -rp "$run" "$tmp/runs/reach_prism/qte-k3-t3-seed7"
touch -d '+1 second' "$tmp/runs/reach_prism/qte-k3-t3-seed7/eval/checkpoint.rec"
bash "$src/examples/depths_of_runs.sh" "$tmp/runs" "$tmp/depths" 2>/dev/null || fail "depths_of_runs.sh with a resumed run"
[ "$(ls "$tmp/depths")" = reach_prism_qte-k3-t3-seed4.csv ] || fail "a resumed run got a table: $(ls "$tmp/depths")"
rm -r "$tmp/runs/reach_prism/qte-k3-t3-seed7"
echo kept > "$tmp/depths/reach_prism_qte-k3-t3-seed4.csv"
bash "$src/examples/depths_of_runs.sh" "$tmp/runs" "$tmp/depths" 2>/dev/null \
  && [ "$(cat "$tmp/depths/reach_prism_qte-k3-t3-seed4.csv")" = kept ] || fail "a table already there was not kept"
# The run's planner options reach plan-path: one it refuses stops the script, naming the run,
# and leaves no table, whole or half-written.
# -p: a copy keeps the run finished (its checkpoint not newer than its eval.csv, whatever order cp
# writes them in)
cp -rp "$run" "$tmp/runs/reach_prism/qte-k3-t3-seed6"
echo "--no-such-option" > "$tmp/runs/reach_prism/qte-k3-t3-seed6/plan_options"
err=$(timeout 300 bash "$src/examples/depths_of_runs.sh" "$tmp/runs" "$tmp/depths" 2>&1) && fail "a refused planner option passed"
grep -q "failed for .*qte-k3-t3-seed6" <<<"$err" || fail "the failed run is not named: $err"
[ "$(ls "$tmp/depths")" = reach_prism_qte-k3-t3-seed4.csv ] || fail "a failed run left $(ls "$tmp/depths")"
# A table another pass is writing (two runs ending together, each make running this script over
# one directory) is left to that pass: while its lock is held, this pass neither writes it nor
# replays the run (whose refused option would stop it), and goes on.
exec 8> "$tmp/depths/reach_prism_qte-k3-t3-seed6.csv.lock"
flock 8
timeout 60 bash "$src/examples/depths_of_runs.sh" "$tmp/runs" "$tmp/depths" 2>/dev/null 8>&- \
  || fail "a pass beside another's lock did not go on"
[ ! -f "$tmp/depths/reach_prism_qte-k3-t3-seed6.csv" ] || fail "a table under another pass's lock was written"
exec 8>&-
rm "$tmp/depths/reach_prism_qte-k3-t3-seed6.csv.lock"

# --- a stream without objects is refused, naming the option -----------------------------------
err=$($py "$src/examples/analysis/depth_decisions.py" "$src/tests/data/pick_and_lift_obs.rec" 2>&1); rc=$?
[ $rc != 0 ] && grep -q "sim-step --objects" <<<"$err" || fail "a stream without objects: exit $rc: $err"
echo "depth decisions ok"
