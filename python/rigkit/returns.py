"""A run's returns: `returns.csv` of `rig run` (one run) and `runs.csv` of `rig learn`
(several), rows `run,trial,sim_time_s,return,greedy_return`, one per learning trial,
`greedy_return` blank where no greedy evaluation followed the trial.

    rows = read("out/run/returns.csv")
    [r.greedy for r in rows if r.greedy is not None]
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

HEADER = ["run", "trial", "sim_time_s", "return", "greedy_return"]


class ReturnsError(ValueError):
    """A returns file that is not one: the message names the file and the line."""


@dataclass(frozen=True)
class Row:
    """One learning trial: its run, number (from 1), simulated seconds of learning at its
    end, return, and the greedy return of the evaluation after it (None: none)."""

    run: int
    trial: int
    sim_time_s: float
    ret: float
    greedy: float | None


def parse(header: list[str], row: list[str], where: str) -> Row:
    """A row of a file whose header is `header`; `where` names it in errors."""
    if header != HEADER:
        raise ReturnsError(f"{where}: header {header}, expected {HEADER}")
    if len(row) != len(HEADER):
        raise ReturnsError(f"{where}: {len(row)} columns, expected {len(HEADER)}")
    run, trial, t, ret, greedy = row
    try:
        return Row(int(run), int(trial), float(t), float(ret), float(greedy) if greedy else None)
    except ValueError as e:
        raise ReturnsError(f"{where}: {e}") from None


def read(path: str | Path) -> list[Row]:
    """Every row of the returns file at `path`, in file order."""
    try:
        with open(path, newline="") as f:
            lines = list(csv.reader(f))
    except OSError as e:
        raise ReturnsError(f"{path}: cannot read: {e.strerror}") from None
    if not lines or lines[0] != HEADER:
        raise ReturnsError(f"{path}: header {lines[:1]}, expected {HEADER}")
    return [parse(lines[0], row, f"{path}:{n}") for n, row in enumerate(lines[1:], start=2)]


def count(path: str | Path) -> int:
    """How many complete rows a returns file has so far (0 before it exists), without
    reading them: for following a run that is writing it."""
    try:
        with open(path, "rb") as f:
            lines = f.read().count(b"\n")
    except FileNotFoundError:
        return 0
    return max(0, lines - 1)


def evaluations(rows: list[Row]) -> list[Row]:
    """The rows a greedy evaluation follows."""
    return [r for r in rows if r.greedy is not None]


class Follower:
    """Reads the complete rows a run appends to its returns file, as they come."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.offset = 0
        self.header: list[str] | None = None
        self.lines = 1

    def new_rows(self) -> list[Row]:
        """The rows written since the last call (none while the file does not exist)."""
        try:
            with open(self.path, "rb") as f:
                f.seek(self.offset)
                chunk = f.read()
        except FileNotFoundError:
            return []
        complete = chunk[: chunk.rfind(b"\n") + 1]
        self.offset += len(complete)
        new = []
        for row in csv.reader(complete.decode().splitlines()):
            if self.header is None:
                self.header = row
                continue
            self.lines += 1
            new.append(parse(self.header, row, f"{self.path}:{self.lines}"))
        return new
