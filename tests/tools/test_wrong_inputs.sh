#!/usr/bin/env bash
# Inputs of the wrong kind are named, never passed over in silence: each program given records
# it does not read (a replay where observations belong, demonstrations where actions belong)
# exits non-zero with one line saying what it expected, what it got and which program makes the
# right records, and writes no output; so do a terminal as standard input, a short text file, an
# unknown --type, observations given to the learner and a checkpoint directory that holds a run.
source "$(dirname "$0")/common.sh"
src=${QTE_SOURCE:?set QTE_SOURCE to the repository}
demos=$src/tests/data/lift_numbered_block_demo.rec  # one demonstration (tests/data/make_data.sh)
keyframe --seed 1 --output "$tmp/replay.rec" "$demos" 2> /dev/null || fail "keyframe of the demonstration"
qattn-train --steps 0 --checkpoint-dir "$tmp/ckpt0" --start-after 0 "$tmp/replay.rec" 2> /dev/null \
  || fail "networks for qte-select"

# PROGRAM ARGS... : must fail with one line holding every later word of EXPECT (a | list).
refused() {  # WHAT EXPECT OUTPUT -- COMMAND...
  local what=$1 expect=$2 output=$3
  shift 4
  "$@" > "$tmp/out" 2> "$tmp/err" && fail "$what: accepted"
  [ "$(wc -l < "$tmp/err")" = 1 ] || fail "$what: not one line: $(cat "$tmp/err")"
  local word
  IFS='|' read -ra words <<< "$expect"
  for word in "${words[@]}"; do grep -qF -- "$word" "$tmp/err" || fail "$what: no '$word' in: $(cat "$tmp/err")"; done
  [ -z "$output" ] || [ ! -e "$output" ] || fail "$what: left $output"
}

refused "keyframe given transitions" "expected 'obs' records|'transition'|keyframe|sim-step" "$tmp/k.rec" -- \
  keyframe --output "$tmp/k.rec" "$tmp/replay.rec"
refused "qte-select given a replay" "expected 'obs' records|'frame'" "$tmp/a.rec" -- \
  qte-select --checkpoint "$tmp/ckpt0/latest.rec" --output "$tmp/a.rec" "$tmp/replay.rec"
refused "plan-path given demonstrations" "expected 'action' records|qte-select|'obs'" "$tmp/p.rec" -- \
  plan-path --output "$tmp/p.rec" "$demos"
refused "voxelize given a replay" "expected 'obs' records" "" -- voxelize "$tmp/replay.rec"
refused "episode-stats given a replay" "expected 'obs' records|'transition'" "" -- episode-stats "$tmp/replay.rec"
refused "stream-dump --type obz" "--type obz|no such record type|obs, voxels" "" -- stream-dump --type obz "$demos"
[ "$(stream-dump --type obz "$demos" > /dev/null 2>&1; echo $?)" = 2 ] || fail "--type obz: not a usage error (exit 2)"
# The types the programs know are the format's registry (formats/record-stream.md, section 12).
doc_types=$(sed -n '/^## 12\./,/^## 13\./p' "$src/formats/record-stream.md" | sed -n 's/^### `\([a-z_]*\)`.*/\1/p' | xargs)
code_types=$(stream-dump --type obz "$demos" 2>&1 | sed -n 's/.*(the types: \([^)]*\)).*/\1/p' | tr -d ',')
[ -n "$doc_types" ] && [ "$doc_types" = "$code_types" ] || fail "record types: format '$doc_types', programs '$code_types'"

# The learner given observations: run keyframe first, not --start-after.
refused "qattn-train given observations" "no transitions|'obs'|keyframe" "$tmp/ckpt1" -- \
  qattn-train --steps 1 --checkpoint-dir "$tmp/ckpt1" "$demos"
# A checkpoint directory that holds a run: --resume or --overwrite, nothing replaced.
cp "$tmp/ckpt0/latest.rec" "$tmp/kept.rec"
refused "qattn-train into a run's directory" "holds a run|--resume|--overwrite" "" -- \
  qattn-train --steps 1 --start-after 0 --checkpoint-dir "$tmp/ckpt0" "$tmp/replay.rec"
cmp -s "$tmp/ckpt0/latest.rec" "$tmp/kept.rec" || fail "the refused run replaced latest.rec"
qattn-train --steps 1 --start-after 0 --overwrite --checkpoint-dir "$tmp/ckpt0" "$tmp/replay.rec" 2> /dev/null \
  || fail "--overwrite did not start over"

# A follower resumed on a replay that has lost records its checkpoint had read (a file system
# that dropped recent appends) stops at once with one line, instead of waiting for them.
qattn-train --steps 2 --start-after 0 --checkpoint-dir "$tmp/ckpt2" "$tmp/replay.rec" 2> /dev/null || fail "a run to resume"
stream-cat --head 12 "$tmp/replay.rec" > "$tmp/lost.rec"
refused "qattn-train --follow --resume on a shorter replay" "checkpoint was taken after|lost records" "" -- \
  timeout 60 qattn-train --follow --resume --steps 4 --start-after 0 --checkpoint-dir "$tmp/ckpt2" "$tmp/lost.rec"

# A text file shorter than a record header: the same line as a longer one.
printf 'hello\n' > "$tmp/short.txt"
refused "a short text file" "bad magic|a QTE record stream|68 65 6c 6c 6f 0a" "" -- stream-dump "$tmp/short.txt"
head -c 200 /dev/zero | tr '\0' 'x' > "$tmp/long.txt"
refused "a long text file" "bad magic|a QTE record stream" "" -- stream-dump "$tmp/long.txt"

# Standard input at a terminal: said at once, exit 2 (script(1) gives the program a terminal).
if command -v script > /dev/null; then
  for program in "stream-dump" "sim-step --task reach_target --output $tmp/s.rec"; do
    timeout 20 script -qec "$program" /dev/null < /dev/null > "$tmp/tty" 2>&1
    status=$?
    [ "$status" = 2 ] || fail "$program at a terminal: exit $status (124: it waited): $(cat "$tmp/tty")"
    grep -q "standard input is a terminal" "$tmp/tty" || fail "$program at a terminal: $(cat "$tmp/tty")"
  done
  [ ! -e "$tmp/s.rec" ] || fail "sim-step at a terminal left its output"
fi
# Options checked as options, before any input is read: a task's variation out of its range is
# a usage error naming the option (not a record of standard input), an empty --judge refused.
refused "sim-step --variation 99" "--variation|0..19" "$tmp/v.rec" -- \
  sim-step --task reach_target --variation 99 --output "$tmp/v.rec"
! grep -q "stdin" "$tmp/err" || fail "--variation 99 blamed standard input: $(cat "$tmp/err")"
mkdir -p "$tmp/spool"
refused "robot-step --judge ''" "--judge" "" -- robot-step --spool "$tmp/spool" --camera front --judge '' --output "$tmp/j.rec"
for program in "robot-step --spool $tmp/spool --outcomes /dev/null --intrinsics 1,1,1,1" "obs-pack --pcd $tmp/x_%d.pcd"; do
  refused "$program --camera ''" "--camera|'' is not a camera name" "$tmp/c.rec" -- \
    $program --camera '' --camera-pose 0,0,0,0,0,0,1 --output "$tmp/c.rec"
  ! grep -q "stdin" "$tmp/err" || fail "$program --camera '': blamed standard input: $(cat "$tmp/err")"
done
echo "wrong inputs named"
