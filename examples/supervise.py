#!/usr/bin/env python3
"""The supervision of one learn.sh run: the part of the learning loop that is bookkeeping.

learn.sh keeps the pipelines (the demonstrations, the learner's command, an actor's closed
loop, an evaluation) and starts this program to run them: it starts the learner and the actors
as `learn.sh TASK RUN --part NAME ...` and, while they run,

  * paces the actors by the learner: a chunk of episodes starts once the learner has taken the
    steps the replay ratio allows for the transitions so far (budgeted runs), and every
    evaluation waits for them;
  * opens each chunk's gate (actors/gate-I/CCCC.go) and waits for its end (CCCC.steps); an actor
    that dies is started again on its chunk, and a chunk that fails twice stops the run;
  * evaluates every EVAL_EVERY environment steps and at the end, on a snapshot of the newest
    checkpoint, with the run's accounts as columns;
  * keeps the accounts: processor time by role over each role's whole process tree, and
    wall-clock training time, saved every ACCOUNT_EVERY seconds and before each evaluation so
    that a killed run resumes with them (RUN/cpu_ticks, RUN/train_seconds);
  * stops the run, with one line naming it, when the learner dies or makes no progress for
    STALL_SECONDS, and enforces CPU_BUDGET and TIME_BUDGET.

Why a Python program and not bash or C++: supervision polls a few times a second for the
whole run, and bash forks a process for nearly every reading (`$(...)`, pgrep, cat); on a busy
machine that cost a fifth of a processor budget. Here every reading is a read of /proc or a
stat() in this one process, and the children's times at their end come from wait4(). It is
Debian's Python without third-party modules, like the rest of examples/, and nothing in it is
on a hot path that C++ would speed up; its logic is unit-tested (tests/tools/test_supervise.py).

Usage: supervise.py --learn-sh PATH --task TASK --run RUN [settings...]
(learn.sh passes its settings; see `supervise.py --help`).
"""

import argparse
import csv
import glob
import os
import re
import shutil
import signal
import sys
import time

TICKS_PER_SECOND = os.sysconf("SC_CLK_TCK")
ROLES = ("demos", "pretrain", "learner", "actor", "other")


def steps_allowed(transitions, pretrain, ratio):
    """The learner steps the replay ratio allows after `transitions` agent transitions, as
    `qattn-train --steps-allowed` counts them: pretrain + floor(ratio * transitions)."""
    # qattn-train computes in double precision and truncates; so does this. The rule is written
    # here again, not asked of qattn-train at each gate, because asking starts LibTorch: 0.45
    # processor seconds a call, about 1% of a 1,200 s budget over a run's gates, where the
    # supervision books 0.3% in all. test_learn_budget holds the two equal.
    return pretrain + int(float(ratio) * transitions)


def process_ticks(pid, with_children=True):
    """Processor ticks of one live process (utime + stime, and with_children the times of the
    children it has reaped); 0 once it is gone."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            stat = f.read()
    except OSError:
        return 0
    fields = stat[stat.rindex(b")") + 2:].split()  # from field 3 on: the name may hold ')'
    n = int(fields[14 - 3]) + int(fields[15 - 3])
    if with_children:
        n += int(fields[16 - 3]) + int(fields[17 - 3])
    return n


def parents():
    """{pid: parent pid} of every live process, read from /proc without a fork."""
    table = {}
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat", "rb") as f:
                stat = f.read()
        except OSError:
            continue
        table[int(name)] = int(stat[stat.rindex(b")") + 2:].split()[1])
    return table


def tree_ticks(root, parent_of=None):
    """Processor ticks of a live process and all its live descendants, each with the children
    it has reaped: every tick of the tree counted once."""
    parent_of = parents() if parent_of is None else parent_of
    children = {}
    for pid, ppid in parent_of.items():
        children.setdefault(ppid, []).append(pid)
    total, stack = 0, [root]
    while stack:
        pid = stack.pop()
        total += process_ticks(pid)
        stack.extend(children.get(pid, ()))
    return total


def rusage_ticks(rusage):
    return round((rusage.ru_utime + rusage.ru_stime) * TICKS_PER_SECOND)


def describe_status(status):
    """A wait status in words: "exit status N" or "killed by signal NAME"."""
    if os.WIFSIGNALED(status):
        number = os.WTERMSIG(status)
        try:
            return f"killed by signal {signal.Signals(number).name[3:]}"
        except ValueError:
            return f"killed by signal {number}"
    return f"exit status {os.waitstatus_to_exitcode(status)}"


def newest_checkpoint_step(directory):
    """The step of the newest numbered checkpoint DIR/step-NNNNNNNN.rec, -1 for none (the
    names qattn-train gives them: CheckpointDirectory::path_for)."""
    best = -1
    try:
        names = os.listdir(directory)
    except OSError:
        return best
    for name in names:
        if name.startswith("step-") and name.endswith(".rec") and name[5:-4].isdigit():
            best = max(best, int(name[5:-4]))
    return best


def checkpoint_path(directory, step):
    return os.path.join(directory, f"step-{step:08d}.rec")


def tail_lines(path):
    """The lines of a text file's last 8 KiB, [] when there are none (a log's end, for messages)."""
    try:
        with open(path, "rb") as f:
            f.seek(0, os.SEEK_END)
            f.seek(max(0, f.tell() - 8192))
            return f.read().decode("utf-8", "replace").splitlines()
    except OSError:
        return []


def last_line(path):
    """The last line of a text file, '' when there is none."""
    lines = tail_lines(path)
    return lines[-1] if lines else ""


def evaluation_summary(path):
    """An evaluation's row (episode-stats' CSV) in words."""
    with open(path, newline="") as f:
        row = next(csv.DictReader(f))
    return (f"success {row['success_rate']} ({row['successes']} of {row['episodes']} held-out episodes, "
            f"95% interval {float(row['ci95_low']):.2f}-{float(row['ci95_high']):.2f}), "
            f"{row['train_s']} s of training")


def write_atomically(path, text):
    with open(path + ".tmp", "w") as f:
        f.write(text)
    os.replace(path + ".tmp", path)


class RunStopped(Exception):
    """The run stops with exit status 1; the message has been logged."""


class Supervisor:
    def __init__(self, settings):
        self.s = settings
        self.run = settings.run
        self.ckpt = os.path.join(self.run, "ckpt")
        self.actors_dir = os.path.join(self.run, "actors")
        self.who = f"{settings.task} {settings.label} seed {settings.seed}"
        self.parent = os.getppid()
        self.children = {}  # pid -> what it is, for the clean-up
        self.learner = None
        self.actor_pids = {}  # actor index -> pid of its pipeline (`learn.sh --part actor I`)
        self.actor_ticks = {}  # actor index -> its tree's last reading
        self.reaped_actor_ticks = 0  # actors that have ended, from wait4
        self.failures = {}  # chunk -> failed attempts
        self.pretraining = False
        self.pretrain_ticks = 0
        self.demos_ticks = settings.demos_ticks
        self.startup_ticks = settings.startup_ticks
        self.cpu_base = [0] * len(ROLES)
        try:
            with open(os.path.join(self.run, "cpu_ticks")) as f:
                saved = [int(x) for x in f.read().split()]
            if len(saved) == len(ROLES):
                self.cpu_base = saved
        except (OSError, ValueError):
            pass
        self.clock = int(time.time())
        self.stall_mark, self.stall_since = None, time.monotonic()

    # -- messages ---------------------------------------------------------------------------
    def log(self, text):
        sys.stderr.write(f"{time.strftime('%H:%M:%S')} {text}\n")
        sys.stderr.flush()

    # -- children ---------------------------------------------------------------------------
    def start_part(self, name, *args, stdout=None):
        """`learn.sh TASK RUN --part NAME ARGS...` as a child in a session of its own (so that
        the clean-up reaches every program it starts), standard output to the file descriptor
        `stdout` if given. posix_spawn, not subprocess: only this program reaps its children,
        and wait4() gives each one's processor time with that of everything it started."""
        command = ["bash", self.s.learn_sh, self.s.task, self.run, "--part", name, *map(str, args)]
        actions = [(os.POSIX_SPAWN_OPEN, 0, os.devnull, os.O_RDONLY, 0)]
        if stdout is not None:
            actions.append((os.POSIX_SPAWN_DUP2, stdout, 1))
        pid = os.posix_spawnp("bash", command, os.environ, file_actions=actions, setsid=True)
        self.children[pid] = name
        return pid

    def reap(self, pid, block=False):
        """(status, ticks) of a child that has ended, None while it runs."""
        try:
            got, status, rusage = os.wait4(pid, 0 if block else os.WNOHANG)
        except ChildProcessError:
            self.children.pop(pid, None)
            return (0, 0)
        if got == 0:
            return None
        self.children.pop(pid, None)
        return (status, rusage_ticks(rusage))

    def stop_children(self):
        """Every child's process group: its programs end (a stopped one is continued so that
        it sees the signal)."""
        for pid in list(self.children):
            for sig in (signal.SIGTERM, signal.SIGCONT):
                try:
                    os.killpg(pid, sig)
                except OSError:
                    pass
        for pid in list(self.children):
            self.reap(pid, block=True)

    # -- accounts ---------------------------------------------------------------------------
    def learner_ticks(self):
        return process_ticks(self.learner, with_children=False) if self.learner else 0

    def cpu_roles(self):
        """Ticks of demos, pretrain, learner, actor and other, this run so far."""
        learner_now = self.learner_ticks()
        pretrain = learner_now if self.pretraining else self.pretrain_ticks
        live = [i for i, pid in self.actor_pids.items() if pid in self.children]
        if live:
            table = parents()
            for i in live:
                self.actor_ticks[i] = tree_ticks(self.actor_pids[i], table)
        actors = self.reaped_actor_ticks + sum(self.actor_ticks.get(i, 0) for i in live)
        own = os.times()
        other = self.startup_ticks + round((own.user + own.system) * TICKS_PER_SECOND)
        now = [self.demos_ticks, pretrain, learner_now - pretrain, actors, other]
        return [base + n for base, n in zip(self.cpu_base, now)]

    def cpu_seconds(self):
        return sum(self.cpu_roles()) // TICKS_PER_SECOND

    def train_seconds_at(self, now):
        try:
            with open(os.path.join(self.run, "train_seconds")) as f:
                saved = int(f.read().strip() or 0)
        except (OSError, ValueError):
            saved = 0
        return saved + now - self.clock

    def count_training_time(self):
        now = int(time.time())
        write_atomically(os.path.join(self.run, "train_seconds"), f"{self.train_seconds_at(now)}\n")
        write_atomically(os.path.join(self.run, "cpu_ticks"), " ".join(map(str, self.cpu_roles())) + "\n")
        self.clock = now

    def keep_accounts(self):
        if self.s.role != "actor" and int(time.time()) - self.clock >= self.s.account_every:
            self.count_training_time()

    def cpu_columns(self):
        """The evaluation CSV's processor-time columns: cpu_s, then cpu_<role>_s."""
        roles = self.cpu_roles()
        t = TICKS_PER_SECOND
        columns = [f"cpu_s={sum(roles) // t}"] + [f"cpu_{r}_s={n / t:.1f}" for r, n in zip(ROLES, roles)]
        return [x for c in columns for x in ("--column", c)]

    def budgeted(self):
        return self.s.cpu_budget > 0 or self.s.time_budget > 0

    def out_of_budget(self):
        return ((self.s.cpu_budget > 0 and self.cpu_seconds() >= self.s.cpu_budget)
                or (self.s.time_budget > 0 and self.train_seconds_at(int(time.time())) >= self.s.time_budget))

    # -- waiting ----------------------------------------------------------------------------
    def nap(self, seconds):
        time.sleep(seconds)
        if os.getppid() != self.parent:  # learn.sh is gone (killed): so is its run
            self.log(f"{self.who}: learn.sh ended; stopping the run")
            raise RunStopped()
        self.keep_accounts()

    def check_learner(self):
        if self.learner is None:  # a split run's actor: the learner runs elsewhere
            return
        ended = self.reap(self.learner)
        if ended is None:
            return
        self.log(f"{self.who}: the learner (qattn-train, pid {self.learner}) died, {describe_status(ended[0])}; "
                 f"last line of {self.run}/train.log: {last_line(os.path.join(self.run, 'train.log'))}")
        self.learner = None
        raise RunStopped()

    def watch_learner_from_now(self):
        self.stall_mark, self.stall_since = None, time.monotonic()

    def check_progress(self):
        """A dead learner, or one alive that has made no progress (no new checkpoint, no new
        line in train.csv or train.log) for STALL_SECONDS, stops the run."""
        self.check_learner()
        if self.learner is None:
            return
        sizes = []
        for name in ("train.csv", "train.log"):
            try:
                sizes.append(os.stat(os.path.join(self.run, name)).st_size)
            except OSError:
                sizes.append(-1)
        mark = (newest_checkpoint_step(self.ckpt), *sizes)
        if mark != self.stall_mark:
            self.stall_mark, self.stall_since = mark, time.monotonic()
            return
        if time.monotonic() - self.stall_since < self.s.stall_seconds:
            return
        self.log(f"{self.who}: the learner (qattn-train, pid {self.learner}) made no progress in "
                 f"{self.s.stall_seconds} s (no new checkpoint, no new line in train.csv or train.log; "
                 f"STALL_SECONDS); stopping the run; last line of {self.run}/train.log: "
                 f"{last_line(os.path.join(self.run, 'train.log'))}")
        raise RunStopped()

    def wait_for_learner(self, transitions):
        """Until the learner has the steps the replay ratio allows (to a checkpoint's step)."""
        want = steps_allowed(transitions, self.s.pretrain, self.s.ratio)
        want = want // self.s.checkpoint_every * self.s.checkpoint_every
        self.watch_learner_from_now()
        while newest_checkpoint_step(self.ckpt) < want:
            self.check_progress()
            self.nap(0.5)
        # Pretraining ends at step PRETRAIN (to a checkpoint interval when PRETRAIN is not a
        # multiple of CHECKPOINT_EVERY).
        if self.pretraining and newest_checkpoint_step(self.ckpt) >= self.s.pretrain:
            self.pretrain_ticks, self.pretraining = self.learner_ticks(), False

    # -- chunks -----------------------------------------------------------------------------
    def gate_dir(self, actor):
        return os.path.join(self.actors_dir, f"gate-{actor}")

    def chunk_file(self, chunk, suffix):
        return os.path.join(self.gate_dir(chunk % self.s.actors), f"{chunk:04d}.{suffix}")

    def chunk_done(self, chunk):
        return os.path.exists(self.chunk_file(chunk, "steps"))

    def next_chunk(self, actor):
        c = actor
        while self.chunk_done(c):
            c += self.s.actors
        return c

    def finished_steps(self):
        """Environment steps of the finished chunks."""
        total = 0
        for path in glob.glob(os.path.join(self.actors_dir, "gate-*", "[0-9]*.steps")):
            try:
                with open(path) as f:
                    total += int(f.read().split()[0])
            except (OSError, ValueError, IndexError):
                pass
        return total

    def start_actor(self, actor):
        os.makedirs(self.gate_dir(actor), exist_ok=True)
        try:
            os.remove(os.path.join(self.actors_dir, f"status-{actor}"))
        except FileNotFoundError:
            pass
        self.actor_ticks[actor] = 0
        self.actor_pids[actor] = self.start_part("actor", actor, self.next_chunk(actor))

    def actor_failure(self, actor):
        """Which program of an ended actor's pipeline failed, how (its status file: the exit
        statuses of sim-step, qte-select, plan-path, tee, keyframe)."""
        programs = (self.s.stage_program, "qte-select", "plan-path", "tee", "keyframe")
        try:
            with open(os.path.join(self.actors_dir, f"status-{actor}")) as f:
                statuses = f.read().split()
        except OSError:
            return "its pipeline was killed"
        for name, status in zip(programs, statuses):
            if status != "0":
                code = int(status)
                return f"{name} " + (f"killed by signal {signal.Signals(code - 128).name[3:]}"
                                     if code > 128 and code - 128 in signal.valid_signals() else f"exit status {code}")
        return "its pipeline ended before the chunk did"

    def run_round(self, chunks):
        """Opens the chunks and waits until each has ended: a dead learner stops the run; a
        dead actor is started again on its chunk (its finished episodes stay in the replay),
        and a chunk that fails twice stops the run."""
        for c in chunks:
            open(self.chunk_file(c, "go"), "a").close()
        while True:
            pending = False
            for c in chunks:
                if self.chunk_done(c):
                    continue
                pending = True
                i = c % self.s.actors
                ended = self.reap(self.actor_pids[i])
                if ended is None:
                    continue
                self.reaped_actor_ticks += ended[1]
                self.actor_ticks[i] = 0
                if self.chunk_done(c):
                    continue
                self.failures[c] = self.failures.get(c, 0) + 1
                log_line = [line for line in tail_lines(os.path.join(self.run, "actor.log"))
                            if not re.match(r" *[0-9]* Done ", line)]  # bash's notes of jobs ended
                self.log(f"{self.who}: actor {i} failed in chunk {c} (attempt {self.failures[c]}): "
                         f"{self.actor_failure(i)}; last line of {self.run}/actor.log: {log_line[-1] if log_line else ''}")
                if self.failures[c] >= 2:
                    self.log(f"chunk {c} failed twice: stopping")
                    raise RunStopped()
                self.start_actor(i)
            if not pending:
                return
            self.check_learner()
            self.nap(0.2)

    def stop_actors(self):
        """At a chunk boundary: every actor ends its pipeline."""
        for i in self.actor_pids:
            open(os.path.join(self.gate_dir(i), "stop"), "a").close()
        for i, pid in self.actor_pids.items():
            ended = self.reap(pid, block=True)
            if ended:
                self.reaped_actor_ticks += ended[1]
                self.actor_ticks[i] = 0

    def remove_stale_gates(self, actors):
        for gate in actors:
            for path in glob.glob(os.path.join(gate, "*.go")) + [os.path.join(gate, "stop")]:
                try:
                    os.remove(path)
                except FileNotFoundError:
                    pass

    # -- the roles --------------------------------------------------------------------------
    def actor_role(self):
        """Actor I of a split run: chunks I, I + ACTORS, ... until the run has its environment
        steps or the learner says it is done."""
        i = self.s.actor_index
        os.makedirs(self.actors_dir, exist_ok=True)
        while not os.path.exists(os.path.join(self.ckpt, "latest.rec")):
            self.nap(2)
        self.remove_stale_gates([self.gate_dir(i)])
        self.start_actor(i)
        chunk = self.next_chunk(i)
        while (not os.path.exists(os.path.join(self.run, "actor.done"))
               and self.finished_steps() < self.s.env_steps):
            self.run_round([chunk])
            chunk += self.s.actors
        self.stop_actors()
        self.log(f"{self.who}: actor {i} done")

    def evaluate(self, snapshot, env_steps, out, step, point):
        """Greedy episodes of a checkpoint on the held-out scenes -> one CSV row (its processor
        time is the evaluation's, in no role)."""
        with open(os.path.join(self.run, "train_seconds")) as f:
            train_s = f.read().strip()
        with open(out + ".tmp", "wb") as csv_out:
            pid = self.start_part("evaluate", snapshot, env_steps, step, point, train_s, *self.cpu_columns(),
                                  stdout=csv_out.fileno())
            status, _ = self.reap(pid, block=True)
        if status != 0:
            self.log(f"{self.who}: the evaluation of learner step {step} failed ({describe_status(status)}); see {self.run}/actor.log")
            raise RunStopped()
        os.replace(out + ".tmp", out)

    def learn(self):
        """ROLE=all or learner: the learner, the actors (ROLE=all), the evaluations."""
        s = self.s
        self.pretraining = newest_checkpoint_step(self.ckpt) < s.pretrain
        self.learner = self.start_part("learner")
        self.watch_learner_from_now()
        while not os.path.exists(os.path.join(self.ckpt, "latest.rec")):
            self.check_progress()
            self.nap(0.5)
        os.makedirs(self.actors_dir, exist_ok=True)
        self.remove_stale_gates(glob.glob(os.path.join(self.actors_dir, "gate-*")))
        if s.role == "all":
            for i in range(s.actors):
                self.start_actor(i)
        os.makedirs(os.path.join(self.run, "eval"), exist_ok=True)
        while True:
            env_steps = self.finished_steps()
            finished = 1 if env_steps >= s.env_steps else 2 if self.out_of_budget() else 0
            # Every EVAL_EVERY environment steps and at the end: what the learner has made of
            # the experience so far, once it has the steps the replay ratio allows.
            mark = 999999 if finished else env_steps // s.eval_every
            eval_csv = os.path.join(self.run, "eval", f"{mark:06d}.csv")
            if not os.path.exists(eval_csv):
                if finished != 2:
                    self.wait_for_learner(env_steps)
                snapshot = os.path.join(self.run, "eval", "checkpoint.rec")
                while True:
                    step = newest_checkpoint_step(self.ckpt)
                    try:  # the learner keeps 4 checkpoints: the newest may be gone already
                        shutil.copyfile(checkpoint_path(self.ckpt, step), snapshot + ".tmp")
                        os.replace(snapshot + ".tmp", snapshot)
                        break
                    except OSError:
                        self.nap(0.2)
                self.count_training_time()
                # eval_point: the budget the evaluation stands for; out of budget, the steps it bought.
                point = env_steps if finished == 2 else s.env_steps if finished else mark * s.eval_every
                self.evaluate(snapshot, env_steps, eval_csv, step, point)
                self.clock = int(time.time())  # evaluations are not training time
                self.log(f"{self.who}: env steps {env_steps}, learner step {step}: {evaluation_summary(eval_csv)}")
            if finished:
                break
            if s.role == "learner":  # the actors, elsewhere, add chunks: look again in a while
                self.check_learner()
                self.nap(5)
                continue
            if self.budgeted():  # under a budget the actor is paced by the learner
                self.wait_for_learner(env_steps)
                if self.out_of_budget():
                    continue
            # One round: the chunks of the lowest round not finished, side by side.
            first = 0
            while self.chunk_done(first):
                first += 1
            low = first // s.actors * s.actors
            self.run_round([c for c in range(low, low + s.actors) if not self.chunk_done(c)])
        self.stop_actors()
        open(os.path.join(self.run, "actor.done"), "a").close()
        # Out of budget the learner would go on to the steps the replay allows, past the budget
        # and never evaluated: stop it (its checkpoints are whole files, renamed into place).
        if finished == 2:
            try:
                os.kill(self.learner, signal.SIGTERM)
            except OSError:
                pass
        self.reap(self.learner, block=True)
        self.learner = None


def parse(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--learn-sh", help="learn.sh, whose parts this program runs")
    p.add_argument("--task")
    p.add_argument("--run", help="the run directory")
    p.add_argument("--label")
    p.add_argument("--seed", type=int)
    p.add_argument("--role", choices=("all", "learner", "actor"), default="all")
    p.add_argument("--actors", type=int, default=1)
    p.add_argument("--actor-index", type=int, default=0)
    p.add_argument("--env-steps", type=int)
    p.add_argument("--eval-every", type=int)
    p.add_argument("--pretrain", type=int)
    p.add_argument("--ratio", type=float)
    p.add_argument("--checkpoint-every", type=int)
    p.add_argument("--cpu-budget", type=int, default=0)
    p.add_argument("--time-budget", type=int, default=0)
    p.add_argument("--account-every", type=int, default=30)
    p.add_argument("--stall-seconds", type=int, default=1800)
    p.add_argument("--demos-ticks", type=int, default=0, help="the demonstrations' processor ticks, this start")
    p.add_argument("--startup-ticks", type=int, default=0, help="learn.sh's own ticks before this program, this start")
    p.add_argument("--stage-program", default="sim-step", help="the program of the actors' world (sim-step, robot-step)")
    p.add_argument("--steps-allowed", type=int, metavar="N", help="print the learner steps allowed after N transitions, and exit")
    args = p.parse_args(argv)
    needed = ("pretrain", "ratio") if args.steps_allowed is not None else \
        ("learn_sh", "task", "run", "label", "seed", "env_steps", "eval_every", "pretrain", "ratio", "checkpoint_every")
    missing = [name for name in needed if getattr(args, name) is None]
    if missing:
        p.error("expected " + ", ".join("--" + name.replace("_", "-") for name in missing))
    return args


def main(argv=None):
    settings = parse(argv)
    if settings.steps_allowed is not None:
        print(steps_allowed(settings.steps_allowed, settings.pretrain, settings.ratio))
        return 0
    supervisor = Supervisor(settings)

    def stop(number, _frame):
        raise SystemExit(128 + number)
    for sig in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
        signal.signal(sig, stop)
    try:
        if settings.role == "actor":
            supervisor.actor_role()
        else:
            supervisor.learn()
        return 0
    except RunStopped:
        return 1
    finally:
        supervisor.stop_children()


if __name__ == "__main__":
    sys.exit(main())
