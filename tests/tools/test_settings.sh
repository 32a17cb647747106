#!/usr/bin/env bash
# The learning loop's settings are declared once (examples/settings.txt): docs/learning-loop.md's
# table is `make -C examples help`'s; a misspelt setting, a value out of range and a task the
# simulator does not have each stop learn.sh with one line and exit status 2 before anything of
# the run exists; make's command line refuses a name that is neither a setting nor one of the
# Makefile's variables, naming the nearest.
source "$(dirname "$0")/common.sh"
src=${QTE_SOURCE:?set QTE_SOURCE to the repository}

make -s -C "$src/examples" help > "$tmp/help.md" || fail "make -C examples help"
sed -n '/^<!-- the settings table/,/^<!-- end of the settings table/p' "$src/docs/learning-loop.md" | sed '1d;$d' > "$tmp/doc.md"
[ -s "$tmp/doc.md" ] && diff "$tmp/help.md" "$tmp/doc.md" > "$tmp/diff" \
  || fail "docs/learning-loop.md's settings table is not make -C examples help's: $(head -5 "$tmp/diff")"
[ "$(grep -c '^| `' "$tmp/help.md")" = "$(grep -c '^[A-Z]' "$src/examples/settings.txt")" ] \
  || fail "make help shows $(grep -c '^| `' "$tmp/help.md") settings, settings.txt declares $(grep -c '^[A-Z]' "$src/examples/settings.txt")"

# refused WORDS -- ENV... : learn.sh with these settings exits 2, one line with each |-separated word, no run.
refused() {
  local words=$1; shift 2
  env "$@" bash "$src/examples/learn.sh" "${task:-reach_target}" "$tmp/run" > "$tmp/out" 2> "$tmp/err"
  local status=$?
  [ "$status" = 2 ] || fail "$* learn.sh: exit $status, expected 2: $(cat "$tmp/err")"
  [ "$(wc -l < "$tmp/err")" = 1 ] || fail "$*: not one line: $(cat "$tmp/err")"
  local word
  IFS='|' read -ra list <<< "$words"
  for word in "${list[@]}"; do grep -qF -- "$word" "$tmp/err" || fail "$*: no '$word' in: $(cat "$tmp/err")"; done
  [ ! -e "$tmp/run" ] || fail "$*: the run directory was made"
}
refused "EVAL_EPISODE is not a setting|did you mean EVAL_EPISODES?" -- EVAL_EPISODE=20
refused "PRETRIAN is not a setting|did you mean PRETRAIN?" -- PRETRIAN=1000
refused "EVAL_EPISODES=0|at least 1" -- EVAL_EPISODES=0
refused "EPSILON=1.5|from 0 to 1" -- EPSILON=1.5
refused "METHOD=qtee|one of qte, c2farm, adaptive" -- METHOD=qtee
refused "IMAGE=128|WIDTHxHEIGHT" -- IMAGE=128
refused "CROP_AUGMENTATION=no|one of on, off" -- CROP_AUGMENTATION=no
task=reach_targe refused "reach_targe is not a task|reach_target" -- SEED=0
# Names of the system that are near no setting pass (the shell's, make's); so do settings.
HOME_DIR=x LANGUAGE=en ASAN_OPTIONS=x LSAN_OPTIONS=x TSAN_OPTIONS=x bash -c ". '$src/examples/common.sh'; . '$src/examples/settings.sh'; settings_load test" \
  || fail "settings_load refused ordinary environment variables"
defaults=$(bash -c ". '$src/examples/common.sh'; . '$src/examples/settings.sh'; METHOD=c2farm; settings_load test; echo \$ACT_K \$TARGET_K \$LABEL \$STAGE")
[ "$defaults" = "1 0 c2farm-k1-t0 sim-step --image-size 128x128" ] || fail "defaults from the settings above: $defaults"

# make's command line: a name that is neither a setting nor the Makefile's, before any run.
for name in EVAL_EPISODE TAKEAWAY2_SEED; do
  make -C "$src/examples" -n reach_target "$name=3" > "$tmp/make.out" 2> "$tmp/make.err" && fail "make $name=3: accepted"
  grep -q "$name is not a setting of examples/ (did you mean ${name}S?)" "$tmp/make.err" || fail "make $name=3: $(cat "$tmp/make.err")"
done
make -C "$src/examples" -n reach_target SEED=3 "TAKEAWAY2_SEEDS=7 8" RUNS="$tmp/runs" > /dev/null 2> "$tmp/make.err" \
  || fail "make with known names refused: $(cat "$tmp/make.err")"
# The task table (examples/tasks.txt): a row for every task the simulator has, in its order,
# each budget made of settings that pass their checks; the Makefile's lists come from it.
table_tasks=$(sed -n 's/^\([a-z_]\{1,\}\) *|.*/\1/p' "$src/examples/tasks.txt" | xargs)
[ "$table_tasks" = "$(sim-step --list-tasks | cut -f1 | xargs)" ] \
  || fail "examples/tasks.txt's tasks ($table_tasks) are not sim-step --list-tasks' ($(sim-step --list-tasks | cut -f1 | xargs))"
sed -n 's/^[a-z_]\{1,\} *| *[a-z0-9]\{1,\} *| *[a-z]\{1,\} *| *//p' "$src/examples/tasks.txt" | tr ' ' '\n' | sort -u > "$tmp/budget"
while IFS='=' read -r name value; do
  row=$(grep "^$name " "$src/examples/settings.txt") || fail "tasks.txt: $name is not a setting"
  check=$(cut -d'|' -f3 <<< "$row" | sed 's/^ //; s/ $//')
  problem=$(bash -c ". '$src/examples/settings.sh'; setting_problem \"\$1\" \"\$2\"" x "$value" "$check")
  [ -z "$problem" ] || fail "tasks.txt: $name=$value: $problem"
done < "$tmp/budget"
listed=$(make -s -C "$src/examples" --eval 'print-task-lists: ; @echo $(TASK_SET_1) / $(APPROACH_TASKS)' print-task-lists)
[ "$listed" = "take_lid_off_saucepan pick_up_cup put_rubbish_in_bin stack_wine phone_on_base take_umbrella_out_of_umbrella_stand / stack_blocks setup_checkers pick_up_cup put_rubbish_in_bin stack_wine phone_on_base take_umbrella_out_of_umbrella_stand" ] \
  || fail "the Makefile's task lists from tasks.txt: $listed"
echo "ok: settings declared once, misspellings, ranges and tasks refused before a run starts"
