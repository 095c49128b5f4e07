"""One learning run for a study: `rig learn --runs 1` on a simulated task, or `rig run
--plant external` against a lockstep driver, followed greedy evaluation by greedy
evaluation as its rows reach `runs.csv` / `returns.csv`."""

from __future__ import annotations

import csv
import io
import shlex
import shutil
import signal
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from .config import last_line, rig

POLL_S = 0.2


class RunFailed(Exception):
    """A learning run ended with an error; the message names it and the rig's reason."""


class Stopped(Exception):
    """A run stopped early because its follower asked (a pruned trial)."""


@dataclass
class Runner:
    """How a study's runs are made: `trials` learning trials each (None: the
    configuration's), against an external driver when `driver` names one."""

    trials: int | None = None
    driver: str | None = None
    keep_recordings: bool = False
    extra: list[str] = field(default_factory=list)

    def command(self, config: Path, seed: int, out: Path) -> list[str]:
        """The rig command of one run."""
        if self.driver is None:
            cmd = [rig(), "learn", "--runs", "1", "--threads", "1"]
        else:
            cmd = [rig(), "run", "--plant", "external", "--driver", self.driver]
        cmd += ["--config", str(config), "--seed", str(seed), "--out", str(out), "--quiet"]
        if self.trials is not None:
            cmd += ["--trials", str(self.trials)]
        return cmd + self.extra

    def rows_file(self, out: Path) -> Path:
        return out / ("runs.csv" if self.driver is None else "returns.csv")

    def run(
        self, config: Path, seed: int, out: Path, on_greedy: Callable[[float], bool] | None = None
    ) -> list[float]:
        """Runs one seed; calls `on_greedy` with each greedy return as it is written (a
        true answer stops the run: `Stopped`); returns every greedy return."""
        out.mkdir(parents=True, exist_ok=True)
        cmd = self.command(config, seed, out)
        log = out / "rig.log"
        with open(log, "w") as sink:
            proc = subprocess.Popen(cmd, stdout=sink, stderr=subprocess.STDOUT)
            follower = Follower(self.rows_file(out))
            try:
                while True:
                    done = proc.poll() is not None
                    for g in follower.new_greedy():
                        if on_greedy is not None and on_greedy(g):
                            raise Stopped()
                    if done:
                        break
                    time.sleep(POLL_S)
            finally:
                end(proc)
        if proc.returncode != 0:
            reason = last_line(log.read_text(errors="replace"))
            raise RunFailed(f"`{shlex.join(cmd)}` exited with {proc.returncode}: {reason}")
        if self.driver is not None and not self.keep_recordings:
            discard_recording(out)
        return follower.greedy


def discard_recording(out: Path) -> None:
    """Removes what a finished `rig run` keeps besides its returns: the recording of every
    message and the checkpoints (megabytes a run, where a study makes hundreds)."""
    (out / "run.mcap").unlink(missing_ok=True)
    shutil.rmtree(out / "checkpoints", ignore_errors=True)


def end(proc: subprocess.Popen, sig: int = signal.SIGINT) -> None:
    """Stops a process still going (a run as Ctrl-C would), then waits for it."""
    if proc.poll() is None:
        proc.send_signal(sig)
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


class Follower:
    """Reads the complete rows a run has appended to its rows file so far."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.offset = 0
        self.header: list[str] | None = None
        self.greedy: list[float] = []

    def new_greedy(self) -> list[float]:
        """The greedy returns of the rows written since the last call."""
        try:
            with open(self.path, "rb") as f:
                f.seek(self.offset)
                chunk = f.read()
        except FileNotFoundError:
            return []
        complete = chunk[: chunk.rfind(b"\n") + 1]
        self.offset += len(complete)
        new = []
        for row in csv.reader(io.StringIO(complete.decode())):
            if self.header is None:
                self.header = row
                continue
            g = row[self.header.index("greedy_return")]
            if g:
                new.append(float(g))
        self.greedy += new
        return new


class Driver:
    """A lockstep driver a worker starts from the study's `--driver-cmd` template, with
    an id of its own (`{id}` in the template)."""

    def __init__(self, template: str, driver_id: str, log: Path) -> None:
        self.id = driver_id
        argv = shlex.split(template.replace("{id}", driver_id))
        log.parent.mkdir(parents=True, exist_ok=True)
        self.sink = open(log, "w")
        self.proc = subprocess.Popen(argv, stdout=self.sink, stderr=subprocess.STDOUT)

    def close(self) -> None:
        end(self.proc, signal.SIGTERM)
        self.sink.close()
