#!/usr/bin/env bash
# Appends never corrupt the file appended to (stream-cat, stream-pack, keyframe --append share
# the writer): onto a file that is not a stream, a torn last record or one of its own inputs
# they refuse with one line naming the file, record and byte offset; --repair cuts a torn tail
# back to the last whole record; a file-size limit (SIGXFSZ / EFBIG) leaves no torn record.
source "$(dirname "$0")/common.sh"

for i in 1 2 3; do stream-pack obs "step:i32=$i" "x:f32[1000]=$(seq -s, 1 1000)"; done > "$tmp/three.rec"
stream-pack obs step:i32=9 > "$tmp/one.rec"
size() { stat -c %s "$1"; }
records() { stream-dump --summary "$1" | cut -f2; }

# expect_refusal FILE WORDS COMMAND...: exit 1, one line naming FILE and WORDS, FILE unchanged.
expect_refusal() {
  local file=$1 words=$2; shift 2
  local before; before=$(cat "$file" | md5sum)
  local err rc; err=$("$@" 2>&1 >/dev/null); rc=$?
  [ "$rc" = 1 ] || fail "$*: exit $rc, expected 1 ($err)"
  [ "$(wc -l <<<"$err")" = 1 ] || fail "$*: more than one line: $err"
  grep -q "$file" <<<"$err" && grep -q "$words" <<<"$err" || fail "$*: said '$err', expected '$file' and '$words'"
  [ "$(cat "$file" | md5sum)" = "$before" ] || fail "$*: changed $file"
}

# A file that is not a record stream.
printf 'hello, this is text and not a record stream at all, long enough for a header: 0123456789\n' > "$tmp/text.rec"
expect_refusal "$tmp/text.rec" "record 0 at byte 0: cannot append: bad magic" stream-cat "$tmp/one.rec" --append --output "$tmp/text.rec"
expect_refusal "$tmp/text.rec" "record 0 at byte 0" stream-pack obs a:i32=1 --append --output "$tmp/text.rec"
expect_refusal "$tmp/text.rec" "record 0 at byte 0" stream-cat "$tmp/one.rec" --append --repair --output "$tmp/text.rec"
printf 'short' > "$tmp/short.rec"
expect_refusal "$tmp/short.rec" "not a record stream" stream-cat "$tmp/one.rec" --append --output "$tmp/short.rec"

# A torn last record: refused, then cut off with --repair; the append lands behind record 1.
whole=$(( $(size "$tmp/three.rec") / 3 ))
head -c $(( whole * 2 + 1000 )) "$tmp/three.rec" > "$tmp/torn.rec"
expect_refusal "$tmp/torn.rec" "record 2 at byte $(( whole * 2 )): cannot append: .*torn record.*--repair" \
  stream-cat "$tmp/one.rec" --append --output "$tmp/torn.rec"
expect_refusal "$tmp/torn.rec" "record 2 at byte $(( whole * 2 ))" keyframe --append --output "$tmp/torn.rec" /dev/null
err=$(stream-cat "$tmp/one.rec" --append --repair --output "$tmp/torn.rec" 2>&1) || fail "--repair failed: $err"
grep -q "repaired $tmp/torn.rec: record 2 at byte $(( whole * 2 )): cut off 1000 bytes" <<<"$err" || fail "--repair said '$err'"
[ "$(records "$tmp/torn.rec")" = "3 records" ] || fail "after --repair: $(records "$tmp/torn.rec")"
# A torn header (fewer than 64 bytes, starting like one) is a torn record too.
{ cat "$tmp/one.rec"; head -c 20 "$tmp/one.rec"; } > "$tmp/torn_header.rec"
expect_refusal "$tmp/torn_header.rec" "record 1 at byte $(size "$tmp/one.rec")" stream-pack obs a:i32=1 --append --output "$tmp/torn_header.rec"
stream-pack obs a:i32=1 --append --repair --output "$tmp/torn_header.rec" 2>/dev/null || fail "--repair of a torn header"
[ "$(records "$tmp/torn_header.rec")" = "2 records" ] || fail "after --repair of a torn header"
# A damaged last payload is cut off with --repair as well; damage before the last record is not.
cp "$tmp/three.rec" "$tmp/bad_last.rec"
printf '\x55' | dd of="$tmp/bad_last.rec" bs=1 seek=$(( whole * 2 + 200 )) conv=notrunc status=none
expect_refusal "$tmp/bad_last.rec" "record 2 at byte $(( whole * 2 )): cannot append: payload checksum" \
  stream-cat "$tmp/one.rec" --append --output "$tmp/bad_last.rec"
cp "$tmp/three.rec" "$tmp/bad_middle.rec"
printf '\x55' | dd of="$tmp/bad_middle.rec" bs=1 seek=$(( whole + 3 )) conv=notrunc status=none
expect_refusal "$tmp/bad_middle.rec" "record 1 at byte $whole: cannot append: bad magic" \
  stream-cat "$tmp/one.rec" --append --repair --output "$tmp/bad_middle.rec"

# Appending a file onto itself (by name or through standard input) would grow it forever.
cp "$tmp/three.rec" "$tmp/self.rec"
expect_refusal "$tmp/self.rec" "it is also an input" timeout 20 stream-cat "$tmp/self.rec" --append --output "$tmp/self.rec"
expect_refusal "$tmp/self.rec" "it is also an input" sh -c "timeout 20 stream-cat --append --output '$tmp/self.rec' < '$tmp/self.rec'"
ln -s "$tmp/self.rec" "$tmp/link.rec"
expect_refusal "$tmp/self.rec" "it is also an input" timeout 20 stream-cat "$tmp/link.rec" --append --output "$tmp/self.rec"

# The file-size limit stops an append half-way through a record: the record is cut back, the
# file ends in a whole record, the next append works.
cp "$tmp/three.rec" "$tmp/limited.rec"
before=$(size "$tmp/limited.rec")
err=$(ulimit -f $(( (before + whole + whole / 2) / 1024 )); stream-cat "$tmp/three.rec" --append --output "$tmp/limited.rec" 2>&1); rc=$?
[ "$rc" = 1 ] && grep -q "File too large" <<<"$err" || fail "append past the file-size limit: exit $rc, $err"
[ "$(size "$tmp/limited.rec")" = $(( before + whole )) ] || fail "a torn record was left behind the size limit: $(size "$tmp/limited.rec") bytes"
stream-cat "$tmp/one.rec" --append --output "$tmp/limited.rec" || fail "append after the size limit"
[ "$(records "$tmp/limited.rec")" = "5 records" ] || fail "after the size limit: $(records "$tmp/limited.rec")"

# All or nothing: an input damaged at its third record appends none of the records before it,
# with or without --repair.
cp "$tmp/three.rec" "$tmp/damaged.rec"
third=$(( $(size "$tmp/three.rec") / 3 * 2 + 70 ))  # inside the third record's payload
printf 'XXXX' | dd of="$tmp/damaged.rec" bs=1 seek="$third" conv=notrunc 2> /dev/null
for repair in "" --repair; do
  cp "$tmp/one.rec" "$tmp/target.rec"
  err=$(stream-cat "$tmp/one.rec" "$tmp/damaged.rec" --append $repair --output "$tmp/target.rec" 2>&1); rc=$?
  [ "$rc" = 1 ] && grep -q "$tmp/damaged.rec: record 2 at byte" <<<"$err" || fail "damaged input ($repair): exit $rc, $err"
  cmp -s "$tmp/target.rec" "$tmp/one.rec" || fail "a damaged input ($repair) appended part of itself: $(records "$tmp/target.rec")"
done

# A new file and an empty file are streams to append to.
stream-cat "$tmp/one.rec" --append --output "$tmp/new.rec" && : > "$tmp/empty.rec" \
  && stream-cat "$tmp/one.rec" --append --output "$tmp/empty.rec" || fail "append to a new or empty file"
cmp "$tmp/new.rec" "$tmp/one.rec" && cmp "$tmp/empty.rec" "$tmp/one.rec" || fail "append to a new or empty file: bytes"
echo "append ok"
