"""One learning run for a study: `rig learn --runs 1` on a simulated task, or `rig run
--plant external` against a lockstep driver, followed greedy evaluation by greedy
evaluation as its rows reach `runs.csv` / `returns.csv`."""

from __future__ import annotations

import shlex
import shutil
import signal
import subprocess
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from rigkit import processes, returns

from .config import last_line, rig

POLL_S = 0.2


class RunFailed(Exception):
    """A learning run ended with an error; the message names it and the rig's reason."""


class Stopped(Exception):
    """A run stopped early because its follower asked (a pruned trial), or because its
    runner was cancelled."""


@dataclass
class Runner:
    """How a study's runs are made: `trials` learning trials each (None: the
    configuration's), against an external driver when there is one. Setting `cancelled`
    stops every run under way (`Stopped`), as another thread may need when one of several
    runs in parallel has failed."""

    trials: int | None = None
    driver: Driver | None = None
    keep_recordings: bool = False
    extra: list[str] = field(default_factory=list)
    cancelled: threading.Event = field(default_factory=threading.Event)

    def command(self, config: Path, seed: int, out: Path) -> list[str]:
        """The rig command of one run."""
        if self.driver is None:
            cmd = [rig(), "learn", "--runs", "1", "--threads", "1"]
        else:
            cmd = [rig(), "run", "--plant", "external", "--driver", self.driver.id]
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
        if self.driver is not None:
            self.driver.ensure()
        cmd = self.command(config, seed, out)
        log = out / "rig.log"
        with open(log, "w") as sink:
            proc = subprocess.Popen(cmd, stdout=sink, stderr=subprocess.STDOUT)
            follower = returns.Follower(self.rows_file(out))
            greedy: list[float] = []
            try:
                while True:
                    done = proc.poll() is not None
                    for row in follower.new_rows():
                        if row.greedy is None:
                            continue
                        greedy.append(row.greedy)
                        if on_greedy is not None and on_greedy(row.greedy):
                            raise Stopped()
                    if done:
                        break
                    if self.cancelled.is_set():
                        raise Stopped()
                    if self.driver is not None and not self.driver.alive():
                        raise RunFailed(self.driver.ended())
                    time.sleep(POLL_S)
            except returns.ReturnsError as e:
                raise RunFailed(str(e)) from None
            finally:
                processes.stop(proc)  # a run still going stopped as Ctrl-C would
        if proc.returncode != 0:
            reason = last_line(log.read_text(errors="replace"))
            raise RunFailed(f"`{shlex.join(cmd)}` exited with {proc.returncode}: {reason}")
        if self.driver is not None and not self.keep_recordings:
            discard_recording(out)
        return greedy


def discard_recording(out: Path) -> None:
    """Removes what a finished `rig run` keeps besides its returns: the recording of every
    message and the checkpoints (megabytes a run, where a study makes hundreds)."""
    (out / "run.mcap").unlink(missing_ok=True)
    shutil.rmtree(out / "checkpoints", ignore_errors=True)


class Driver:
    """A lockstep driver a worker starts from the study's `--driver-cmd` template, with
    an id of its own (`{id}` in the template)."""

    def __init__(self, template: str, driver_id: str, log: Path) -> None:
        self.id = driver_id
        self.argv = shlex.split(template.replace("{id}", driver_id))
        self.log = log
        log.parent.mkdir(parents=True, exist_ok=True)
        self.sink = open(log, "w")
        self.proc = self.start()

    def start(self) -> subprocess.Popen[bytes]:
        return subprocess.Popen(self.argv, stdout=self.sink, stderr=subprocess.STDOUT)

    def alive(self) -> bool:
        return self.proc.poll() is None

    def ended(self) -> str:
        """Why the driver is gone: its command, exit status and last line of its log."""
        self.sink.flush()
        reason = last_line(self.log.read_text(errors="replace"))
        return f"the driver `{shlex.join(self.argv)}` exited with {self.proc.returncode}: {reason} (log: {self.log})"

    def ensure(self) -> None:
        """Starts the driver again if it has exited (a crash ends one run, not the study)."""
        if not self.alive():
            self.sink.write(f"--- {self.ended()}; started again\n")
            self.sink.flush()
            self.proc = self.start()

    def close(self) -> None:
        processes.stop(self.proc, signal.SIGTERM)
        self.sink.close()
