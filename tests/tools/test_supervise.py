#!/usr/bin/env python3
"""examples/supervise.py, the learning loop's supervision, against a stand-in learn.sh whose
parts are small shell loops (a test double: the real parts are covered by test_learn_budget.sh,
test_learn_actors.sh and test_standin_loop.sh):

1. the processor time of a process tree, read from /proc, against wait4's account of the same
   tree once it has ended (every tick counted once);
2. a budgeted run: each chunk's gate opens only once the learner has the steps the replay ratio
   allows, the evaluations fall on their marks with the accounts as columns, the roles' ticks
   are saved, and a chunk whose actor dies runs again;
3. a chunk that fails twice, a learner that dies and a learner that stalls each stop the run
   with exit status 1, one line naming it, and nothing of the run left running;
4. a run stopped by SIGTERM leaves nothing running and resumes to its end, its accounts kept.
"""
import os
import signal
import subprocess
import sys
import tempfile
import textwrap
import time

SOURCE = os.environ.get("QTE_SOURCE") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SUPERVISE = os.path.join(SOURCE, "examples", "supervise.py")
sys.path.insert(0, os.path.join(SOURCE, "examples"))
import supervise  # noqa: E402

failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message)


# The stand-in learn.sh: the learner takes a step (a checkpoint file) whenever the replay ratio
# allows one for the transitions the actors have written (one line each in RUN/transitions), and
# ends once actor.done exists; an actor runs its chunks as their gates open (CHUNK_STEPS
# transitions each), noting the learner's step at each opening, and dies (SIGKILL of its
# "qte-select") the first time it reaches FAIL_CHUNK, every time with FAIL_ALWAYS; an evaluation
# prints one CSV row. LEARNER_DIES_AT / LEARNER_STALLS_AT stop the learner's progress.
STAND_IN = textwrap.dedent(r'''
    task=$1 run=$2 part=$4; shift 4
    newest() { ls "$run/ckpt" | sed -n 's/^step-0*\([0-9][0-9]*\)\.rec$/\1/p' | sort -n | tail -1; }
    case $part in
      learner)
        echo "learner started" >> "$run/train.log"
        mkdir -p "$run/ckpt"
        step=$(newest); step=${step:-0}
        while [ ! -f "$run/actor.done" ]; do
          n=$(cat "$run/transitions" 2>/dev/null | wc -l)
          allowed=$(awk -v n=$n -v p=$PRETRAIN -v r=$RATIO 'BEGIN { printf "%d", p + int(r * n) }')
          if [ "$step" -lt "$allowed" ]; then
            step=$(( step + 1 ))
            [ "$step" != "${LEARNER_DIES_AT:-}" ] || { echo "learner gives up at $step" >> "$run/train.log"; exit 3; }
            [ "$step" != "${LEARNER_STALLS_AT:-}" ] || exec sleep 1000
            touch "$run/ckpt/step-$(printf %08d $step).rec"
            cp "$run/ckpt/step-$(printf %08d $step).rec" "$run/ckpt/latest.rec"
            echo "step $step" >> "$run/train.csv"
          fi
          sleep 0.02
        done ;;
      actor)
        i=$1 c=$2 gate=$run/actors/gate-$1
        mkdir -p "$gate"
        while :; do
          f=$gate/$(printf %04d $c)
          until [ -f "$f.go" ] || [ -f "$gate/stop" ]; do sleep 0.02; done
          [ -f "$f.go" ] || break
          echo "$c $(newest) $(cat "$run/transitions" 2>/dev/null | wc -l)" >> "$run/openings"
          if [ "$c" = "${FAIL_CHUNK:-}" ] && { [ -n "${FAIL_ALWAYS:-}" ] || [ ! -f "$run/failed-once" ]; }; then
            touch "$run/failed-once"; echo "0 137 0 0 0" > "$run/actors/status-$i"; echo "stand-in actor died" >> "$run/actor.log"
            exit 0
          fi
          for ((k = 0; k < CHUNK_STEPS; k++)); do echo "$c" >> "$run/transitions"; done
          x=0; for ((k = 0; k < 20000; k++)); do x=$(( x + k )); done  # some processor time
          echo $CHUNK_STEPS > "$f.steps"
          c=$(( c + ACTORS ))
        done
        echo "0 0 0 0 0" > "$run/actors/status-$i" ;;
      evaluate)
        echo "label,seed,env_steps,train_step,eval_point,train_s,cpu_s,episodes,successes,success_rate,ci95_low,ci95_high"
        cpu=$(echo "$@" | sed -n 's/.*cpu_s=\([0-9]*\).*/\1/p')
        echo "stand-in,0,$2,$3,$4,$5,$cpu,2,1,0.5,0.1,0.9" ;;
    esac
''')


def start(run, extra=(), env=None, **settings):
    options = dict(task="reach_target", run=run, label="stand-in", seed=0, env_steps=40, eval_every=20,
                   pretrain=3, ratio=0.5, checkpoint_every=1, cpu_budget=100000, account_every=1, stall_seconds=600)
    options.update(settings)
    argv = [sys.executable, SUPERVISE, "--learn-sh", os.path.join(os.path.dirname(run), "learn.sh")]
    for name, value in options.items():
        argv += ["--" + name.replace("_", "-"), str(value)]
    environment = dict(os.environ, PRETRAIN=str(options["pretrain"]), RATIO=str(options["ratio"]),
                       CHUNK_STEPS="5", ACTORS=str(options.get("actors", 1)))
    environment.update(env or {})
    os.makedirs(os.path.join(run, "actors"), exist_ok=True)
    return subprocess.Popen(argv + list(extra), env=environment, stderr=subprocess.PIPE, text=True)


def left_running(run):
    """Processes whose command line names the run directory."""
    found = []
    for name in os.listdir("/proc"):
        if name.isdigit() and int(name) != os.getpid():
            try:
                with open(f"/proc/{name}/cmdline", "rb") as f:
                    if run.encode() in f.read():
                        found.append(int(name))
            except OSError:
                pass
    return found


def finish(process, timeout=120):
    try:
        _, err = process.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        _, err = process.communicate()
        err += "\n(timed out)"
    return process.returncode, err


def test_tree_ticks(tmp):
    # A shell with two children that each burn processor time, then wait for a file.
    release = os.path.join(tmp, "release")
    burn = f"x=0; for ((k = 0; k < 150000; k++)); do x=$((x + k)); done; touch {tmp}/burnt-$$; until [ -f {release} ]; do sleep 0.05; done"
    root = subprocess.Popen(["bash", "-c", f"bash -c '{burn}' & bash -c '{burn}' & wait"])
    deadline = time.time() + 60
    while len([n for n in os.listdir(tmp) if n.startswith("burnt-")]) < 2 and time.time() < deadline:
        time.sleep(0.05)
    time.sleep(0.2)
    live = supervise.tree_ticks(root.pid)
    open(release, "w").close()
    _, status, rusage = os.wait4(root.pid, 0)
    ended = supervise.rusage_ticks(rusage)
    check(live > 0.2 * supervise.TICKS_PER_SECOND, f"tree ticks {live}: the two children's time is missing")
    # What the tree spends after the reading (two polls of the release file) is a few ticks.
    check(0 <= ended - live <= 0.15 * supervise.TICKS_PER_SECOND + 3,
          f"tree ticks {live} while it ran, {ended} from wait4 once it had ended")
    check(supervise.process_ticks(root.pid) == 0, "a process that has ended has ticks")
    print(f"ok: tree {live} ticks while running, {ended} at its end")


def test_budgeted_run(tmp):
    run = os.path.join(tmp, "run")
    process = start(run, env={"FAIL_CHUNK": "2"})
    code, err = finish(process)
    check(code == 0, f"the run failed: exit {code}: {err}")
    # Paced: each gate opened once the learner had the steps allowed for the transitions so far.
    with open(os.path.join(run, "openings")) as f:
        openings = [tuple(int(x) for x in line.split()) for line in f]
    for chunk, step, transitions in openings:
        want = supervise.steps_allowed(transitions, 3, 0.5)
        check(step >= want, f"chunk {chunk} opened at learner step {step}, {transitions} transitions allowing {want}")
    check([c for c, _, _ in openings] == [0, 1, 2, 2, 3, 4, 5, 6, 7],
          f"the chunks opened: {[c for c, _, _ in openings]} (chunk 2 twice: its actor died once)")
    check("actor 0 failed in chunk 2 (attempt 1): qte-select killed by signal KILL; last line of "
          f"{run}/actor.log: stand-in actor died" in err, f"no line naming the failed chunk: {err}")
    # Evaluations at 0, 20 and the end, each a row with its mark and the accounts.
    marks = sorted(os.listdir(os.path.join(run, "eval")))
    check(marks == ["000000.csv", "000001.csv", "999999.csv", "checkpoint.rec"], f"evaluations: {marks}")
    for name, point in (("000000.csv", 0), ("000001.csv", 20), ("999999.csv", 40)):
        with open(os.path.join(run, "eval", name)) as f:
            row = f.read().splitlines()[1].split(",")
        check(int(row[4]) == point, f"{name}: eval_point {row[4]}, expected {point}")
        check(int(row[3]) >= supervise.steps_allowed(int(row[2]), 3, 0.5), f"{name}: learner step {row[3]} for {row[2]} transitions")
    check(err.count("held-out episodes, 95% interval 0.10-0.90") == 3, f"evaluations in words: {err}")
    with open(os.path.join(run, "cpu_ticks")) as f:
        roles = [int(x) for x in f.read().split()]
    check(len(roles) == 5 and roles[3] > 0 and roles[1] + roles[2] > 0, f"saved accounts (demos pretrain learner actor other): {roles}")
    check(os.path.exists(os.path.join(run, "actor.done")), "no actor.done at the end")
    check(not left_running(run), f"still running: {left_running(run)}")
    print(f"ok: budgeted run, {len(openings)} gates opened, accounts {roles}")


def test_stops(tmp):
    cases = [
        ("chunk twice", {"FAIL_CHUNK": "1", "FAIL_ALWAYS": "1"}, {}, "chunk 1 failed twice: stopping"),
        ("learner dies", {"LEARNER_DIES_AT": "6"}, {},
         "died, exit status 3; last line of {run}/train.log: learner gives up at 6"),
        ("learner stalls", {"LEARNER_STALLS_AT": "6"}, {"stall_seconds": 2}, "made no progress in 2 s"),
    ]
    for name, env, settings, expected in cases:
        run = os.path.join(tmp, name.replace(" ", "-"))
        began = time.time()
        code, err = finish(start(run, env=env, **settings), timeout=60)
        expected = expected.format(run=run)
        check(code == 1, f"{name}: exit {code}, expected 1: {err}")
        check(expected in err, f"{name}: no line '{expected}': {err}")
        time.sleep(0.3)
        check(not left_running(run), f"{name}: still running: {left_running(run)}")
        print(f"ok: {name} stops the run in {time.time() - began:.1f} s")


def test_terminate_and_resume(tmp):
    run = os.path.join(tmp, "resumed")
    process = start(run, env_steps=60)
    deadline = time.time() + 60
    while not os.path.exists(os.path.join(run, "actors", "gate-0", "0003.steps")) and time.time() < deadline:
        time.sleep(0.05)
    time.sleep(1.2)  # an account save (every second)
    process.send_signal(signal.SIGTERM)
    code, _ = finish(process)
    check(code != 0, "a run stopped by SIGTERM exited 0")
    time.sleep(0.3)
    check(not left_running(run), f"after SIGTERM, still running: {left_running(run)}")
    with open(os.path.join(run, "cpu_ticks")) as f:
        before = [int(x) for x in f.read().split()]
    code, err = finish(start(run, env_steps=60))
    check(code == 0, f"the resumed run failed: {err}")
    with open(os.path.join(run, "cpu_ticks")) as f:
        after = [int(x) for x in f.read().split()]
    check(all(a >= b for a, b in zip(after, before)) and after[3] > before[3], f"accounts {before} then {after}")
    with open(os.path.join(run, "eval", "999999.csv")) as f:
        check(f.read().splitlines()[1].split(",")[4] == "60", "the resumed run's final evaluation")
    print(f"ok: stopped by SIGTERM and resumed, accounts {before} -> {after}")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        with open(os.path.join(tmp, "learn.sh"), "w") as f:
            f.write(STAND_IN)
        test_tree_ticks(tmp)
        test_budgeted_run(tmp)
        test_stops(tmp)
        test_terminate_and_resume(tmp)
    if failures:
        sys.exit(1)


if __name__ == "__main__":
    main()
