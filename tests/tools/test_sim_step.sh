#!/usr/bin/env bash
# sim-step as a program: observations on reset, same seed -> same bytes, clear errors.
source "$(dirname "$0")/common.sh"

sim-step --task pick_and_lift --seed 4 --image-size 64x64 < /dev/null > "$tmp/a.rec" || fail "sim-step exit $?"
sim-step --task pick_and_lift --seed 4 --image-size 64x64 < /dev/null > "$tmp/b.rec"
sim-step --task pick_and_lift --seed 5 --image-size 64x64 < /dev/null > "$tmp/c.rec"
cmp -s "$tmp/a.rec" "$tmp/b.rec" || fail "same seed gave different bytes"
cmp -s "$tmp/a.rec" "$tmp/c.rec" && fail "different seeds gave the same bytes"
[ "$(stream-dump --summary "$tmp/a.rec" | cut -f1,2)" = "$(printf 'obs\t1 records')" ] || fail "expected one obs"
stream-dump --json "$tmp/a.rec" | grep -q '"name":"front.rgb","dtype":"uint8","shape":\[64,64,3\]' || fail "front.rgb"

# An explicit reset record drives it too, and the PNG helper writes a real image.
stream-pack reset task=lift_numbered_block variation:i32=2 seed:i64=1 | sim-step --image-size 96x96 \
  | stream-png --depth --dir "$tmp/png" || fail "reset pipeline"
file "$tmp/png/000000.front.rgb.png" 2>/dev/null | grep -q "96 x 96" || [ -s "$tmp/png/000000.front.rgb.png" ] \
  || fail "no PNG written"
[ -s "$tmp/png/000000.front.depth.png" ] || fail "no depth PNG"
# stream-png: an image field that is empty or not an image names the record and field, exit 1.
for bad in "front.rgb:u8[0,4,3]=" "front.rgb:u8[2,2]=1,2,3,4" "front.depth:f32[0,3]="; do
  err=$(stream-pack obs "$bad" | stream-png --depth --dir "$tmp/badpng" 2>&1); rc=$?
  [ $rc = 1 ] && grep -q "<stdin>: record 0 at byte 0: 'obs' record, field 'front\.\(rgb\|depth\)': expected" <<<"$err" \
    || fail "stream-png on $bad: exit $rc: $err"
done
[ -z "$(ls "$tmp/badpng" 2>/dev/null)" ] || fail "stream-png wrote a PNG of a bad image"

# Unknown task: one line listing the tasks, exit 1, nothing written.
err=$(sim-step --task open_drawer --output "$tmp/x.rec" < /dev/null 2>&1 >/dev/null); rc=$?
[ $rc = 1 ] || fail "unknown task exit $rc"
[ "$(printf '%s\n' "$err" | wc -l)" = 1 ] || fail "not one line: $err"
grep -q "known tasks: reach_target, pick_and_lift, lift_numbered_block" <<<"$err" || fail "$err"
[ ! -e "$tmp/x.rec" ] || fail "output file left behind"

# A trajectory before any reset names the record.
err=$(stream-pack trajectory time_s:f64=0 "joint_positions:f64[1,7]=0,0,0,0,0,0,0" | sim-step 2>&1 >/dev/null)
grep -q "<stdin>: record 0 at byte 0: trajectory before any reset" <<<"$err" || fail "$err"
echo "sim-step ok"
