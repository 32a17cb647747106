#!/usr/bin/env bash
# voxelize and keyframe as programs: demos -> transitions, observations -> grids, bad input.
source "$(dirname "$0")/common.sh"

src=${QTE_SOURCE:?set QTE_SOURCE to the repository}
demos=$src/tests/data/lift_numbered_block_demo.rec  # one demonstration (tests/data/make_data.sh)
cp "$demos" "$tmp/demos.rec"
keyframe --seed 1 "$tmp/demos.rec" --output "$tmp/t1.rec" 2> "$tmp/log" || fail "keyframe exit $?"
grep -q "1/1 episodes converted" "$tmp/log" || fail "$(cat "$tmp/log")"
keyframe --seed 1 < "$tmp/demos.rec" > "$tmp/t2.rec" 2>/dev/null
cmp -s "$tmp/t1.rec" "$tmp/t2.rec" || fail "same seed, different transitions"
keyframe --seed 2 "$tmp/demos.rec" 2>/dev/null | cmp -s - "$tmp/t1.rec" && fail "crop augmentation ignores the seed"
# lift_numbered_block: 3 keyframes per demo; the chain from frame 0 has 3 transitions.
n=$(stream-dump --json --type transition "$tmp/t1.rec" | grep -c '"name":"frame","dtype":"int32","shape":\[\],"values":\[0\]')
[ "$n" = 1 ] || fail "expected one transition from frame 0 per demo, got $n"
stream-dump --json --type transition "$tmp/t1.rec" > "$tmp/t1.json"
grep -q '"name":"depth1.index","dtype":"int32","shape":\[3\]' "$tmp/t1.json" || fail "no depth-1 index"

# Unsuccessful episodes are skipped and counted; --keep-failed keeps them.
stream-cat --type obs "$tmp/demos.rec" | stream-cat --head 30 > "$tmp/partial.rec"
keyframe "$tmp/partial.rec" > /dev/null 2> "$tmp/log2"
grep -q "0/1 episodes converted.*skipped 1 unsuccessful" "$tmp/log2" || fail "$(cat "$tmp/log2")"

# voxelize: one voxels record after each obs, pictures, and a clear error without images.
stream-cat --type obs --head 2 "$tmp/demos.rec" | voxelize --png "$tmp/png" --centre 0.1,0,0.8 > "$tmp/v.rec" || fail "voxelize"
[ "$(stream-dump --summary "$tmp/v.rec" | cut -f1,2 | tr '\n' ' ')" = "$(printf 'obs\t2 records voxels\t2 records ')" ] || fail "records"
[ -s "$tmp/png/000000.depth0.png" ] && [ -s "$tmp/png/000000.depth1.0.png" ] || fail "no pictures"
err=$(stream-pack obs step:i32=0 | voxelize 2>&1 >/dev/null) && fail "obs without images accepted"
grep -q "<stdin>: record 0 at byte 0: 'obs' record has no camera image" <<<"$err" || fail "$err"
echo "voxelize and keyframe ok"
