#!/usr/bin/env bash
# Label slurm (make check-slurm): on a real single-node Slurm cluster started here, examples/
# Makefile's `grid` runs 2 tasks x 2 methods x 1 seed as one job array and a collection job
# makes their curves and tables; `split` runs one run as a learner job and 2 actor array
# tasks; and a grid task requeued while its run is midway finishes with nothing lost.
source "$(dirname "$0")/../tools/common.sh"
source "$(dirname "$0")/cluster.sh"
examples=${QTE_SOURCE:?}/examples
build=$(dirname "$tools")
for p in slurmctld slurmd munged sbatch; do command -v $p > /dev/null || fail "$p is not installed (make check-slurm installs it)"; done
cluster_start "$tmp/cluster" || fail "no cluster"
trap 'cluster_stop; rm -rf "$tmp"' EXIT

tiny="DEMOS=2 IMAGE=48x48 CHUNK_EPISODES=2 EVAL_EVERY=1000 EVAL_EPISODES=2 BATCH=4 PRETRAIN=2 RATIO=0.2 CHECKPOINT_EVERY=1"
make -C "$examples" --no-print-directory grid SCHEDULER=slurm RUNS="$tmp/grid" BUILD="$build" RUN_CPUS=1 RUN_MEM=2G \
  GRID_TASKS="reach_target pick_and_lift" GRID_SEEDS=0 GRID_SETTINGS="$tiny ENV_STEPS=40" > "$tmp/grid.out" 2>&1 \
  || fail "grid submission: $(cat "$tmp/grid.out")"
array=$(sed -n 's/.*job array \([0-9]*\),.*/\1/p' "$tmp/grid.out")
[ -n "$array" ] || fail "no job array: $(cat "$tmp/grid.out")"
make -C "$examples" --no-print-directory split SCHEDULER=slurm TASK=reach_target ACTORS=2 METHOD=c2farm SEED=1 \
  RUNS="$tmp/split" BUILD="$build" LEARNER_CPUS=1 RUN_MEM=2G $tiny ENV_STEPS=24 > "$tmp/split.out" 2>&1 \
  || fail "split submission: $(cat "$tmp/split.out")"

# Requeue array task 0 (reach_target, c2farm) once its run is midway: a chunk finished and
# checkpoints written, the run not done. Slurm kills it and starts it again; it resumes.
run0=$tmp/grid/reach_target/c2farm-k1-t0-seed0
for _ in $(seq 1 600); do
  [ -f "$run0/actors/gate-0/0000.steps" ] && break
  sleep 0.5
done
[ -f "$run0/actors/gate-0/0000.steps" ] || fail "task 0 never finished a chunk: $(squeue; tail -3 "$tmp"/grid/slurm-*_0.out)"
[ ! -f "$run0/eval.csv" ] || fail "task 0 finished before it could be requeued"
learner_steps() { grep -E '^[0-9]' "$run0/train.csv" | cut -d, -f1; }
before=$(learner_steps | tail -n 1)
scontrol requeue "${array}_0" || fail "scontrol requeue failed"

# Everything ends (the queue empties) within 15 minutes.
for _ in $(seq 1 900); do
  [ -z "$(squeue -h)" ] && break
  sleep 1
done
[ -z "$(squeue -h)" ] || fail "jobs still queued after 15 minutes: $(squeue)"

for run in reach_target/c2farm-k1-t0-seed0 reach_target/qte-k10-t10-seed0 pick_and_lift/c2farm-k1-t0-seed0 pick_and_lift/qte-k10-t10-seed0; do
  [ -f "$tmp/grid/$run/eval.csv" ] || fail "$run has no eval.csv: $(tail -5 "$tmp"/grid/slurm-*.out)"
done
for task in reach_target pick_and_lift; do
  [ -s "$tmp/grid/$task/curves.png" ] || fail "the collection job made no curves for $task: $(cat "$tmp"/grid/slurm-*.out | tail -5)"
  grep -q "c2farm-k1-t0" "$tmp/grid/$task/table.md" && grep -q "qte-k10-t10" "$tmp/grid/$task/table.md" \
    || fail "$task's table lacks a method: $(cat "$tmp/grid/$task/table.md")"
done

# The requeued run: started twice, resumed from its checkpoint (the learner's metrics go on
# from where they were, no step twice), every finished chunk's actions in the replay.
steps=$(learner_steps)
[ "$(sort -n <<<"$steps" | uniq -d)" = "" ] || fail "learner steps repeated after the requeue: $(sort -n <<<"$steps" | uniq -d)"
[ "$(tail -n 1 <<<"$steps")" -ge "${before:-0}" ] || fail "the learner went back from step $before"
requeued=$(scontrol show job "${array}_0" 2>/dev/null | sed -n 's/.*Restarts=\([0-9]*\).*/\1/p')
[ "${requeued:-0}" -ge 1 ] || fail "task 0 was not restarted (Restarts=${requeued:-?})"
count() { stream-dump --summary | awk '$1 == "transition" { print $2 }'; }
actions=$(cat "$run0"/actors/gate-*/*.steps | awk '{ n += $1 } END { print n }')
agent=$(( $(count < "$run0/replay.rec") - $(stream-cat --type transition --where demo=1 "$run0/replay.rec" | count) ))
[ "$agent" -ge "$actions" ] || fail "requeued run: $agent agent transitions for $actions actions"

# The split run: the learner's evaluations, both actors' replay files, chunks from both.
split=$tmp/split/reach_target/c2farm-k1-t0-seed1
[ -f "$split/eval.csv" ] || fail "the split run has no eval.csv: $(tail -5 "$tmp"/split/slurm-*.out)"
for i in 0 1; do
  [ -s "$split/actors/replay-$i.rec" ] || fail "actor $i wrote no episodes"
done
[ -f "$split/actors/gate-0/0000.steps" ] && [ -f "$split/actors/gate-1/0001.steps" ] || fail "chunks: $(ls "$split"/actors/gate-*)"
grep -q "actor 1 done" "$tmp"/split/slurm-*_1.out || fail "actor 1 did not finish: $(cat "$tmp"/split/slurm-*_1.out)"
echo "ok: grid (array $array, task 0 restarted $requeued time(s), $actions actions, $agent agent transitions), split run"
