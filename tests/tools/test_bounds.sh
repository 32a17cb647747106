#!/usr/bin/env bash
# Numbers from a user are range-checked where they are read, sizes multiply without overflow and
# outputs have a bound: each case below ends at once with one line and its exit status (2 for a
# usage error, 1 for input that cannot be done), leaves no output, and stays within a small
# memory limit (a case that allocated what its numbers claim would be killed by it instead).
source "$(dirname "$0")/common.sh"
src=${QTE_SOURCE:?set QTE_SOURCE to the repository}
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}

# The memory limit; in a build with AddressSanitizer (make sanitize) the programs reserve
# terabytes of address space for its shadow memory at start, so there the bound is left to its
# allocator, which makes a program that asks for a huge allocation end with an error report.
limit=(ulimit -v 4000000)
ldd "$(command -v stream-pack)" 2>/dev/null | grep -q libasan && limit=(true)

# expect STATUS WORDS OUTPUT COMMAND...: exit STATUS, one line holding WORDS, no file OUTPUT.
expect() {
  local status=$1 words=$2 output=$3; shift 3
  local err rc
  err=$("${limit[@]}"; timeout 60 "$@" 2>&1 >/dev/null); rc=$?
  [ "$rc" = "$status" ] || fail "$*: exit $rc, expected $status ($err)"
  [ "$(wc -l <<<"$err")" = 1 ] || fail "$*: more than one line: $err"
  grep -q -- "$words" <<<"$err" || fail "$*: said '$err', expected '$words'"
  [ ! -e "$output" ] || fail "$*: left $output"
}

# stream-pack: shapes whose element count overflows or is negative are refused, not written.
expect 1 "more than 2^40 elements" "$tmp/a.rec" stream-pack obs 'x:f32[4294967296,4294967296]=' --output "$tmp/a.rec"
expect 1 "more than 2^40 elements" "$tmp/a.rec" stream-pack obs 'x:u8[65536,65536,65536,65536]=' --output "$tmp/a.rec"
expect 1 "extent -1 in dimension 0" "$tmp/a.rec" stream-pack obs 'x:u8[-1]=' --output "$tmp/a.rec"
expect 1 "ndim 9" "$tmp/a.rec" stream-pack obs 'x:u8[1,1,1,1,1,1,1,1,1]=1' --output "$tmp/a.rec"

# plot-curves: sizes and counts do not wrap; a picture has a bound; an axis must be drawable.
printf 'step,rate,task\n0,0.1,a\n1,0.5,a\n' > "$tmp/curves.csv"
expect 2 "expected WxH between 200x150 and 10000x10000" "$tmp/p.png" \
  plot-curves --x step --y rate --size 4294967496x300 --output "$tmp/p.png" "$tmp/curves.csv"
expect 2 "panel-columns must be 1..100" "$tmp/p.png" \
  plot-curves --x step --y rate --panel task --panel-columns 4294967297 --output "$tmp/p.png" "$tmp/curves.csv"
expect 2 "y-range: expected LO,HI with LO < HI" "$tmp/p.png" \
  plot-curves --x step --y rate --y-range 1,0 --output "$tmp/p.png" "$tmp/curves.csv"
{ echo step,rate,task; for t in $(seq 1 200); do echo "0,0.1,t$t"; echo "1,0.2,t$t"; done; } > "$tmp/panels.csv"
expect 1 "200 panels of 10000x10000 make a picture of .* megapixels" "$tmp/p.png" \
  plot-curves --x step --y rate --panel task --panel-columns 100 --size 10000x10000 --output "$tmp/p.png" "$tmp/panels.csv"
expect 1 "cannot be drawn" "$tmp/p.png" \
  plot-curves --x step --y rate --y-range 1e17,1.0000000000000002e17 --output "$tmp/p.png" "$tmp/curves.csv"
printf 'step,rate\n0,-1e308\n1,1e308\n' > "$tmp/huge.csv"
expect 1 "cannot be drawn" "$tmp/p.png" plot-curves --x step --y rate --output "$tmp/p.png" "$tmp/huge.csv"
plot-curves --x step --y rate --y-range 0,1 --output "$tmp/p.png" "$tmp/curves.csv" || fail "a good plot"

# qattn-train: every setting within its range before anything is written.
keyframe "$src/tests/data/reach_target_demo.rec" > "$tmp/transitions.rec" 2>/dev/null || fail "keyframe"
for bad in "--alpha -1" "--beta 2" "--gamma 1.5" "--lr 0" "--replay-ratio -1" "--huber-delta 0" "--tau nan"; do
  expect 2 "${bad%% *} must be" "$tmp/ckpt" qattn-train $bad --steps 0 --checkpoint-dir "$tmp/ckpt" "$tmp/transitions.rec"
done
expect 2 "seed must be" "$tmp/ckpt" qattn-train --seed -1 --steps 0 --checkpoint-dir "$tmp/ckpt" "$tmp/transitions.rec"
echo "bounds: ok"
