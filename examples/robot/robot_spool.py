"""The driver's side of the robot spool (formats/robot-spool.md): finding the requests of one
kind in the order they were written, answering each once and atomically, and honouring `stop`;
and writing `stop` itself, saying why, when the driver ends for any other reason (SIGINT,
SIGTERM, an error), so that robot-step stops at once instead of waiting for an answer that will
not come, and nothing is carried out until a person has looked and removed it.
Imported by examples/robot/xarm_driver.py and examples/robot/realsense_recorder.py; the standard library only.
"""
import os
import re
import shutil
import signal
import sys
import time

REQUEST = re.compile(r"^(motion|capture)-([0-9]+)-([0-9]{6,})\.(xarm\.csv|request)$")
SUFFIX = {"motion": "xarm.csv", "capture": "request"}


def in_words(error, expected=()):
    """A .fault's one line for an exception: its words, after its type's name unless it is one
    of the `expected` kinds (whose words say enough)."""
    words = " ".join(str(error).split())
    if isinstance(error, expected) and words:
        return words
    return f"{type(error).__name__}: {words}" if words else type(error).__name__


class Spool:
    """A spool directory as one driver sees it: requests of `kind`, answered with one of
    `final_suffixes` (an answer exists once one of them does)."""

    def __init__(self, directory, kind, final_suffixes, poll_s=0.02):
        self.directory, self.kind, self.final_suffixes, self.poll_s = directory, kind, final_suffixes, poll_s
        self.answered = set()  # names answered by this process, whatever happens to the files
        self.interrupted = None  # the signal's name, once one came
        if not os.path.isdir(directory):
            raise SystemExit(f"{directory}: no such spool directory")

    def path(self, name):
        return os.path.join(self.directory, name)

    def stopped(self):
        """`stop` is in the spool, or the process was interrupted (SIGINT, SIGTERM)."""
        return bool(self.interrupted) or os.path.exists(self.path("stop"))

    def catch_signals(self):
        """SIGINT and SIGTERM set a flag the loops check, so a motion is stopped, not cut."""
        def handler(signum, frame):
            self.interrupted = signal.Signals(signum).name
        signal.signal(signal.SIGINT, handler)
        signal.signal(signal.SIGTERM, handler)

    def write_stop(self, why):
        """Writes `stop`, one line saying why, unless it is there already (whoever wrote it
        first said why)."""
        if not os.path.exists(self.path("stop")):
            self.write("stop", " ".join(why.split()) + "\n")

    def pending(self):
        """Unanswered requests of this driver's kind, oldest first, as (stem, name): one
        robot-step's by its counter (numerically: it may outgrow six digits); a later
        robot-step's after an earlier one's."""
        sessions = {}
        for name in os.listdir(self.directory):
            m = REQUEST.match(name)
            if not m or m.group(1) != self.kind or m.group(4) != SUFFIX[self.kind]:
                continue
            stem = name[: -len(SUFFIX[self.kind]) - 1]
            if name in self.answered or any(os.path.exists(self.path(f"{stem}.{s}")) for s in self.final_suffixes):
                continue
            try:
                written_ns = os.stat(self.path(name)).st_mtime_ns
            except FileNotFoundError:  # robot-step took it back
                continue
            sessions.setdefault(m.group(2), []).append((int(m.group(3)), written_ns, stem, name))
        order = sorted(sessions.values(), key=lambda requests: min(r[1] for r in requests))
        return [(stem, name) for requests in order for _, _, stem, name in sorted(requests)]

    def write(self, name, data):
        """Writes the file whole under a name starting with '.', then renames it."""
        temporary = self.path(f".{name}.{os.getpid()}.tmp")
        with open(temporary, "wb") as f:
            f.write(data.encode() if isinstance(data, str) else data)
        os.replace(temporary, self.path(name))

    def copy(self, source, name):
        """Copies a file byte for byte into the spool, whole or not at all."""
        temporary = self.path(f".{name}.{os.getpid()}.tmp")
        shutil.copyfile(source, temporary)
        os.replace(temporary, self.path(name))

    def answer(self, request_name, stem, suffix, text):
        """The request's one answer: `stem.suffix` holding one line (or nothing)."""
        if request_name in self.answered:
            raise AssertionError(f"{request_name} answered twice")
        self.write(f"{stem}.{suffix}", text + "\n" if text else "")
        self.answered.add(request_name)

    def serve(self, handle, program):
        """Calls handle(stem, name) for each request in order until `stop` appears or the
        process is interrupted; returns the exit status (0 on stop, 130 on a signal). Ended by a
        signal or by an exception (raised on), it writes `stop` saying why first."""
        self.catch_signals()
        in_hand = None  # the request being handled, or handled and left unanswered
        try:
            while not self.stopped():
                requests = self.pending()
                if not requests:
                    time.sleep(self.poll_s)
                    continue
                for stem, name in requests:
                    if self.stopped():
                        break
                    in_hand = name
                    handle(stem, name)
                    if name in self.answered:
                        in_hand = None
        except BaseException as e:
            self.write_stop(f"{program} ended by an error ({type(e).__name__}: {e})"
                            + (f" while handling {in_hand}, left unanswered" if in_hand else ""))
            raise
        if self.interrupted:
            self.write_stop(f"{program} was interrupted ({self.interrupted})"
                            + (f" while handling {in_hand}, left unanswered" if in_hand else ""))
        why = f"interrupted ({self.interrupted})" if self.interrupted else f"{self.path('stop')} appeared"
        print(f"{program}: {why}; answering nothing more", file=sys.stderr)
        return 130 if self.interrupted else 0
