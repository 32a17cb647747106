#!/usr/bin/env bash
# qte-select reads and checks the whole checkpoint and finds the online networks by role: damage
# in any record is an error naming it; records in another order give the same actions.
source "$(dirname "$0")/common.sh"
src=${QTE_SOURCE:?set QTE_SOURCE to the repository}
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-PASSIVE}

cp "$src/tests/data/reach_target_demo.rec" "$tmp/demos.rec"
keyframe "$tmp/demos.rec" > "$tmp/transitions.rec" 2>/dev/null || fail "keyframe"
# Three steps: the target networks (soft-updated) differ from the online ones by then.
qattn-train --steps 3 --batch 4 --start-after 0 --seed 1 --checkpoint-dir "$tmp/ckpt" "$tmp/transitions.rec" 2>/dev/null \
  || fail "qattn-train --steps 3"
ckpt=$tmp/ckpt/latest.rec
stream-cat --type obs --head 2 "$tmp/demos.rec" > "$tmp/obs.rec"
qte-select --checkpoint "$ckpt" --seed 3 "$tmp/obs.rec" > "$tmp/a.rec" 2>"$tmp/err" || fail "qte-select: $(cat "$tmp/err")"

# Target networks first, the online ones last: the same actions and Q values (a reader taking
# the first record would act with the target networks: other bytes).
{ stream-cat --where role=target "$ckpt"; stream-cat --exclude checkpoint "$ckpt"; stream-cat --head 1 "$ckpt"; } > "$tmp/reordered.rec"
[ "$(stream-dump --summary "$tmp/reordered.rec" | cut -f2)" = "$(stream-dump --summary "$ckpt" | cut -f2)" ] || fail "reordering lost records"
qte-select --checkpoint "$tmp/reordered.rec" --seed 3 "$tmp/obs.rec" > "$tmp/b.rec" 2>"$tmp/err" || fail "reordered checkpoint: $(cat "$tmp/err")"
cmp -s "$tmp/a.rec" "$tmp/b.rec" || fail "a reordered checkpoint gave other actions (networks taken by position)"

# Damage in the last record (the learner's state, not the online networks) is still an error.
cp "$ckpt" "$tmp/damaged.rec"
size=$(stat -c %s "$tmp/damaged.rec")
printf '\x55' | dd of="$tmp/damaged.rec" bs=1 seek=$(( size - 100 )) conv=notrunc status=none
err=$(qte-select --checkpoint "$tmp/damaged.rec" "$tmp/obs.rec" 2>&1 >/dev/null); rc=$?
[ "$rc" = 1 ] && [ "$(wc -l <<<"$err")" = 1 ] && grep -q "damaged.rec: record 2 at byte [0-9]*: payload checksum mismatch" <<<"$err" \
  || fail "damage in the last checkpoint record: exit $rc, '$err'"
# Two online checkpoints are ambiguous.
{ stream-cat --head 1 "$ckpt"; cat "$ckpt"; } > "$tmp/two.rec"
err=$(qte-select --checkpoint "$tmp/two.rec" "$tmp/obs.rec" 2>&1 >/dev/null); rc=$?
[ "$rc" = 1 ] && grep -q "two.rec: record 1 at byte [0-9]*: a second online 'checkpoint' record" <<<"$err" || fail "two online checkpoints: exit $rc, '$err'"
echo "checkpoint roles ok"
