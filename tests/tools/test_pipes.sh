#!/usr/bin/env bash
# Streams through pipes: records pass unchanged, a reader that quits early stops the writer
# quietly (no error message, no hang), binary output to a terminal is refused.
source "$(dirname "$0")/common.sh"

for i in $(seq 1 50); do stream-pack obs "step:i32=$i" "x:f32[1000]=$(seq -s, 1 1000)"; done > "$tmp/many.rec"
cmp "$tmp/many.rec" <(stream-cat < "$tmp/many.rec") || fail "stream-cat changed the bytes"
[ "$(stream-dump --type obs --summary "$tmp/many.rec" | cut -f2)" = "50 records" ] || fail "summary"

# Downstream exits after one line: upstream must end quietly and promptly.
timeout 10 stream-cat "$tmp/many.rec" "$tmp/many.rec" "$tmp/many.rec" 2>"$tmp/err" | head -c 100 >/dev/null
rc=${PIPESTATUS[0]}
[ "$rc" = 141 ] || fail "stream-cat into a closed pipe: exit $rc, expected 141"
[ ! -s "$tmp/err" ] || fail "stream-cat complained about a closed pipe: $(cat "$tmp/err")"
err=$(timeout 10 stream-dump "$tmp/many.rec" 2>"$tmp/err" | head -n 1 >/dev/null; cat "$tmp/err")
[ -z "$err" ] || fail "stream-dump complained about a closed pipe: $err"

# A write error that is not a closed pipe (a full disk) is one line and exit 1, never a quiet 141.
for tool in "stream-dump $tmp/many.rec" "stream-dump --json $tmp/many.rec" "stream-dump --summary $tmp/many.rec"; do
  err=$($tool 2>&1 >/dev/full); rc=$?
  [ "$rc" = 1 ] && grep -q "cannot write standard output" <<<"$err" || fail "$tool > /dev/full: exit $rc: $err"
done

# Appending from several writers keeps every record whole.
for w in 1 2 3 4; do stream-cat "$tmp/many.rec" --append --output "$tmp/replay.rec" & done; wait
[ "$(stream-dump --summary "$tmp/replay.rec" | cut -f2)" = "200 records" ] || fail "concurrent append"

# A terminal is refused (script gives us one when available).
if command -v script >/dev/null; then
  out=$(script -qec "$tools/stream-pack reset a=1" /dev/null)
  grep -q "refusing to write a binary stream to a terminal" <<<"$out" \
    || fail "binary output to a terminal was not refused: $out"
fi
echo "pipes ok"
