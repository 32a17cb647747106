#!/usr/bin/env bash
# episode-stats: episodes of real sim-step runs and of packed observations, the Wilson interval
# against an independent computation, extra columns, unfinished episodes, damaged input.
source "$(dirname "$0")/common.sh"

# Real episodes: three actions whose trajectories do not start at the arm's joints, so each
# episode ends after one step with a failure (reward 0), and sim-step starts the next.
bad_trajectory() { stream-pack trajectory time_s:f64=0 "joint_positions:f64[1,7]=3,3,3,3,3,3,3"; }
{ bad_trajectory; bad_trajectory; bad_trajectory; } > "$tmp/actions.rec"
sim-step --task reach_target --episodes 3 --seed 1 --image-size 32x32 --no-points \
  < "$tmp/actions.rec" > "$tmp/run.rec" || fail "sim-step exit $?"
out=$(episode-stats "$tmp/run.rec" 2>"$tmp/err") || fail "episode-stats exit $?"
[ ! -s "$tmp/err" ] || fail "unexpected stderr: $(cat "$tmp/err")"
[ "$(sed -n 1p <<<"$out")" = "episodes,successes,success_rate,ci95_low,ci95_high,mean_steps,mean_return" ] \
  || fail "header: $out"
# 0 of 3: the Wilson upper end is z^2/n / (1 + z^2/n).
high=$($py -c 'z=1.959963984540054; n=3; print("%.6g" % ((z*z/n) / (1 + z*z/n)))')
[ "$(sed -n 2p <<<"$out")" = "3,0,0,0,$high,1,0" ] || fail "summary of 3 failed episodes: $out"
per=$(episode-stats --per-episode "$tmp/run.rec")
[ "$(wc -l <<<"$per")" = 4 ] || fail "per-episode rows: $per"
[ "$(sed -n 1p <<<"$per")" = "episode,episode_seed,task,success,steps,return,failure" ] || fail "per-episode header"
[ "$(cut -d, -f1,3-6 <<<"$per" | sed 1d | sort -u)" = "$(printf '0,reach_target,0,1,0\n1,reach_target,0,1,0\n2,reach_target,0,1,0')" ] \
  || fail "per-episode rows: $per"
[ "$(cut -d, -f7 <<<"$per" | grep -c '^invalid_trajectory:')" = 3 ] || fail "failure reasons: $per"
[ "$(cut -d, -f2 <<<"$per" | sed 1d | sort -u | wc -l)" = 3 ] || fail "episode seeds not distinct: $per"

# Packed observations: 7 episodes, 5 solved, of 2 or 3 steps, with actions and trajectories
# between them (ignored). obs FRAME STEP TERMINAL SUCCESS REWARD SEED
obs() {
  stream-pack obs frame:i32=$1 step:i32=$2 terminal:u8=$3 success:u8=$4 reward:f32=$5 \
    episode_seed:i64=$6 task=pick_and_lift
}
action() { stream-pack action "pose:f64=0.3,0,0.9,0,0,0,1"; }
episode() {  # SEED STEPS SUCCESS
  obs 0 0 0 0 0 "$1"; action; bad_trajectory
  [ "$2" = 3 ] && { obs 1 2 0 0 0 "$1"; action; }
  obs 2 "$2" 1 "$3" $(( $3 * 100 )) "$1"
}
{ for s in 11 12 13 14 15; do episode $s 2 1; done; episode 16 3 0; episode 17 3 0; } > "$tmp/packed.rec"
out=$(episode-stats --no-header < "$tmp/packed.rec") || fail "packed exit $?"
IFS=, read -r n k rate low high steps ret <<<"$out"
[ "$n,$k,$steps" = "7,5,2.28571" ] || fail "counts: $out"
[ "$ret" = "71.4286" ] || fail "mean return: $out"
# The Wilson score interval computed here independently, compared to 5 significant digits.
$py - "$rate" "$low" "$high" <<'EOF' || fail "Wilson interval: $out"
import math, sys
n, k, z = 7, 5, 1.959963984540054
p = k / n
centre = (p + z * z / (2 * n)) / (1 + z * z / n)
half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
got = [float(v) for v in sys.argv[1:]]
want = [p, centre - half, centre + half]   # 0.714286, 0.358934, 0.917781
sys.exit(0 if all(abs(g - w) <= 1e-5 * w for g, w in zip(got, want)) else 1)
EOF

# --label and --column add leading columns; --no-header appends; cells with commas are quoted.
out=$(episode-stats --label qte --column seed=2 --column step=5000 "$tmp/packed.rec")
[ "$(sed -n 1p <<<"$out")" = "label,seed,step,episodes,successes,success_rate,ci95_low,ci95_high,mean_steps,mean_return" ] \
  || fail "label header: $out"
[[ "$(sed -n 2p <<<"$out")" == qte,2,5000,7,5,0.714286,* ]] || fail "label row: $out"
[[ "$(episode-stats --no-header --label 'a,"b"' "$tmp/packed.rec")" == '"a,""b""",7,'* ]] || fail "quoted label"
{ episode-stats --label one "$tmp/run.rec"; episode-stats --label two --no-header "$tmp/packed.rec"; } > "$tmp/both.csv"
[ "$(cut -d, -f1,2 "$tmp/both.csv" | tr '\n' ' ')" = "label,episodes one,3 two,7 " ] || fail "appended rows"
episode-stats --column novalue "$tmp/run.rec" >/dev/null 2>&1; [ $? = 2 ] || fail "--column without = accepted"
# ... and said at once, not after the input has ended (here: a pipe open for 20 s).
start=$(date +%s)
episode-stats --column novalue < <(sleep 20) >/dev/null 2>&1; rc=$?
[ $rc = 2 ] && [ $(( $(date +%s) - start )) -lt 10 ] || fail "--column usage error after the input: exit $rc, $(( $(date +%s) - start )) s"

# An unfinished last episode (a reset's observation, no terminal one) is left out and reported;
# so is one cut short by a new reset.
sim-step --task reach_target --seed 2 --image-size 32x32 --no-points < /dev/null > "$tmp/partial.rec"
out=$(cat "$tmp/run.rec" "$tmp/partial.rec" | episode-stats --no-header 2>"$tmp/err") || fail "unfinished: exit $?"
[[ "$out" == 3,0,* ]] || fail "unfinished episode counted: $out"
[ "$(wc -l < "$tmp/err")" = 1 ] && grep -q "unfinished episode at the end (1 observation" "$tmp/err" \
  || fail "unfinished episode not reported: $(cat "$tmp/err")"
out=$(cat "$tmp/partial.rec" "$tmp/run.rec" | episode-stats --no-header 2>"$tmp/err") || fail "reset: exit $?"
[[ "$out" == 3,0,* ]] || fail "episode cut by a reset counted: $out"
grep -q "^episode-stats: <stdin>: unfinished episode before record 1 " "$tmp/err" || fail "cut episode not reported: $(cat "$tmp/err")"
# An episode does not span files.
out=$(episode-stats --no-header "$tmp/partial.rec" "$tmp/partial.rec" 2>"$tmp/err")
[[ "$out" == 0,* ]] && [ "$(wc -l < "$tmp/err")" = 2 ] || fail "episodes across files: $out $(cat "$tmp/err")"

# No input: no episodes, and no NaN.
[ "$(episode-stats --no-header < /dev/null)" = "0,0,0,0,1,0,0" ] || fail "empty input"

# Damage: one line naming file, record and offset; exit 1; no CSV.
size=$(stat -c %s "$tmp/run.rec")
head -c $((size - 10)) "$tmp/run.rec" > "$tmp/truncated.rec"
episode-stats "$tmp/truncated.rec" > "$tmp/out" 2>"$tmp/err"; rc=$?
[ $rc = 1 ] || fail "truncated stream: exit $rc"
[ "$(wc -l < "$tmp/err")" = 1 ] || fail "not one line: $(cat "$tmp/err")"
grep -q "^episode-stats: $tmp/truncated.rec: record 5 at byte [0-9]*: truncated stream" "$tmp/err" \
  || fail "truncation message: $(cat "$tmp/err")"
[ ! -s "$tmp/out" ] || fail "CSV written for a damaged stream"
cp "$tmp/run.rec" "$tmp/flipped.rec"
printf 'X' | dd of="$tmp/flipped.rec" bs=1 seek=200 conv=notrunc 2>/dev/null
err=$(episode-stats "$tmp/flipped.rec" 2>&1 >/dev/null); rc=$?
[ $rc = 1 ] && grep -q "record 0 at byte 0: payload checksum mismatch" <<<"$err" || fail "flipped byte: $rc $err"
# An observation without a reward names the record.
err=$(stream-pack obs terminal:u8=1 success:u8=0 step:i32=0 | episode-stats 2>&1 >/dev/null); rc=$?
[ $rc = 1 ] && grep -q "<stdin>: record 0 at byte 0: 'obs' record has no field 'reward'" <<<"$err" \
  || fail "missing field: $rc $err"
# A NaN reward is an error naming the record, not a 'nan' return in the table.
err=$(obs 0 0 1 0 nan 4 | episode-stats 2>&1 >/dev/null); rc=$?
[ $rc = 1 ] && grep -q "<stdin>: record 0 at byte 0: 'obs' record, field 'reward': expected a finite reward" <<<"$err" \
  || fail "NaN reward: $rc $err"
# No file named '' is attempted.
err=$(obs 0 0 1 0 0 4 | stream-cat --output "" 2>&1); rc=$?
[ $rc = 2 ] && grep -q "an empty output path" <<<"$err" || fail "--output '': $rc $err"
echo "episode-stats ok"
