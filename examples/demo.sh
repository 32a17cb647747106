#!/usr/bin/env bash
# `make demo`: runs the toolkit's main job with the programs that exist so far, on real data,
# and says what it did. (The full loop sim-step -> voxelize -> qte-select -> plan-path lands
# with the simulator, planner and learner; this script grows with them.)
set -euo pipefail
out=${QTE_DEMO_DIR:-out/demo}
mkdir -p "$out"
say() { printf '\n== %s\n' "$*" >&2; }

say "1. write a reset record and an observation-like record (stream-pack)"
stream-pack reset task=reach_target variation:i32=0 seed:i64=7 > "$out/episode.rec"
# A synthetic 128x128 camera frame as NumPy arrays (Debian's python3 has NumPy).
/usr/bin/python3 - "$out" <<'PY'
import sys, numpy as np
out = sys.argv[1]
y, x = np.mgrid[0:128, 0:128]
np.save(f"{out}/front_rgb.npy", np.stack([x * 2, y * 2, np.full_like(x, 128)], -1).astype(np.uint8))
np.save(f"{out}/front_depth.npy", (1.0 + 0.002 * x).astype(np.float32))
PY
stream-pack obs front.rgb=@"$out/front_rgb.npy" front.depth=@"$out/front_depth.npy" \
  step:i32=0 reward:f32=0 terminal:u8=0 --compress --output "$out/obs.rec"

say "2. join them into one stream through a pipe, checking every record (stream-cat)"
stream-cat "$out/episode.rec" "$out/obs.rec" | stream-cat --output "$out/all.rec"

say "3. inspect it (stream-dump), export the arrays for NumPy (--npy)"
stream-dump "$out/all.rec"
stream-dump --summary "$out/all.rec"
stream-dump --npy "$out/npy" --json "$out/all.rec" > "$out/all.jsonl"
ls "$out/npy" >&2

say "done: streams, JSON Lines and .npy files are in $out/"
echo "The simulator, planner and learner stages (sim-step, plan-path, voxelize, keyframe," >&2
echo "qattn-train, qte-select) are not built yet; this demo ran every stage that exists." >&2
