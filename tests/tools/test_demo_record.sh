#!/usr/bin/env bash
# demo-record: full demonstrations, marked episodes, determinism.
source "$(dirname "$0")/common.sh"

demo-record --task pick_and_lift --episodes 2 --seed 5 --image-size 64x64 --output "$tmp/a.rec" 2> "$tmp/log" || fail "exit $?"
grep -q "expert success 2/2" "$tmp/log" || fail "expert did not succeed: $(cat "$tmp/log")"
demo-record --task pick_and_lift --episodes 2 --seed 5 --image-size 64x64 --output "$tmp/b.rec" 2>/dev/null
cmp -s "$tmp/a.rec" "$tmp/b.rec" || fail "same seed, different bytes"
[ "$(stream-dump --summary --type episode "$tmp/a.rec" | cut -f2)" = "2 records" ] || fail "episode records"
frames=$(stream-dump --summary --type obs "$tmp/a.rec" | cut -f2 | cut -d' ' -f1)
[ "$frames" -gt 40 ] || fail "only $frames observations: not every control step was recorded"
stream-dump --json --type episode "$tmp/a.rec" | grep -c '"name":"success","dtype":"uint8","shape":\[\],"values":\[1\]' | grep -qx 2 \
  || fail "episodes not marked successful"

demo-record --task reach_target --episodes 1 --no-points --output "$tmp/c.rec" 2>/dev/null || fail "--no-points"
stream-dump --json --type obs "$tmp/c.rec" | grep -q '"front.points"' && fail "--no-points left point clouds in"
err=$(demo-record --task open_drawer 2>&1 >/dev/null) && fail "unknown task accepted"
grep -q "known tasks" <<<"$err" || fail "$err"
echo "demo-record ok"
