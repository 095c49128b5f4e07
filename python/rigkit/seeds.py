"""The folder of a seeds experiment (examples/python_driver/seeds.sh: OUT/seed-K/ a run's
folder per seed, OUT/wall.csv each run's wall time) judged seed by seed: the greedy
return at the last evaluation, whether it succeeds, when it first did and from when it
held to the end of the run (`to_success`), the agent's step per sample. bench/python/seeds_report.py prints it; systems.py and furuta_report.py use
it. Success is one of

  return_at_least R   the evaluation's greedy return (the mean over the task's start
                      states) is at least R;
  upright A, hold S   every greedy trial of the evaluation (one per start state, read
                      from the run's recording) runs its full length and its last S
                      seconds keep every angle state within A rad of 0 (upright).

Needs mcap (rigkit.recording).
"""

from __future__ import annotations

import csv
import math
import statistics
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from . import recording, returns
from .angle import wrap

if sys.version_info >= (3, 11):
    import tomllib
else:  # the same parser, from PyPI
    import tomli as tomllib

# A trial's states, one list per step.
Trial = list[list[float]]


@dataclass
class Seed:
    """One seed's verdict (see the module): `ts` the task's sampling time, `final` the
    greedy return at the last evaluation, `first_success_s` the simulated seconds of
    learning until the first evaluation that succeeds (None: none did), `holds_s` until
    the first evaluation from which every later one succeeds too (None: the last one
    fails), `first_success_samples` and `holds_samples` the same in samples of
    learning, `learning_mean` the mean return of the
    last 100 learning trials, `agent_ms` the agent's step per sample (median and 99th
    percentile, ms; None without timing), `curve` [(simulated s, greedy return)] of
    every evaluation, `verdicts` whether each evaluation succeeds, in order, `notes` (with
    `upright`) when each last greedy trial is upright."""

    seed: int
    ts: float
    trials: int
    final: float
    succeeds: bool
    first_success_s: float | None
    holds_s: float | None
    first_success_samples: int | None
    holds_samples: int | None
    learning_mean: float
    wall_s: float
    agent_ms: tuple[float, float] | None
    curve: list[tuple[float, float]]
    verdicts: list[bool] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class TaskTimes:
    """What the verdicts need of a run's task: its sampling time and trial length [s],
    and the indices of its angle states."""

    ts: float
    length: float
    angles: list[int]


def task_of(run_dir: Path) -> TaskTimes:
    """The task of the run in `run_dir`, from its config.toml."""
    with open(run_dir / "config.toml", "rb") as f:
        task: dict[str, Any] = tomllib.load(f)["task"]
    angles = [i for i, s in enumerate(task["state"]) if s.get("angle")]
    return TaskTimes(task["sampling_time"], task["trial_seconds"], angles)


def walls(out: Path) -> dict[int, float]:
    """Seed -> the run's wall time [s], from OUT/wall.csv."""
    with open(out / "wall.csv") as f:
        return {int(r["seed"]): float(r["wall_s"]) for r in csv.DictReader(f)}


def greedy_states(measurements: list[recording.Message]) -> dict[int, list[Trial]]:
    """Evaluation -> the states of each of its greedy trials, of a run's measurements."""
    return {
        e: [[recording.vector(m, "y_") for m in t] for t in trials]
        for e, trials in recording.greedy_trials(measurements).items()
    }


def percentile(sorted_values: list[float], q: float) -> float:
    """The nearest-rank `q` percentile (0 < q <= 100) of a sorted list."""
    return sorted_values[max(0, math.ceil(q / 100 * len(sorted_values)) - 1)]


def upright_at_end(trial: Trial, task: TaskTimes, tol: float, hold: float) -> bool:
    """Whether `trial` runs the task's length and its last `hold` seconds keep every
    angle within `tol` of 0."""
    samples = round(task.length / task.ts) + 1
    tail = round(hold / task.ts) + 1
    return len(trial) >= samples and all(
        abs(wrap(x[i])) < tol for x in trial[-tail:] for i in task.angles
    )


def upright_times(trial: Trial, task: TaskTimes, tol: float) -> tuple[float | None, float]:
    """(the first time [s] every angle is within `tol` of 0, or None; the share of the
    trial's samples where they are)."""
    up = [all(abs(wrap(x[i])) < tol for i in task.angles) for x in trial]
    first = next((k * task.ts for k, u in enumerate(up) if u), None)
    return first, sum(up) / len(up)


def meets(success: dict[str, float], task: TaskTimes, trials: list[tuple[Trial, float]]) -> tuple[float, bool]:
    """(the mean return, whether a success rule holds) of one greedy evaluation, its
    trials `[(states, return)]` one per start state: `success` is an experiment's rule,
    {"return_at_least": R} or {"upright": A, "hold": S} (bench/python/systems.toml)."""
    mean = sum(r for _, r in trials) / len(trials)
    if "return_at_least" in success:
        return mean, mean >= success["return_at_least"]
    return mean, all(upright_at_end(s, task, success["upright"], success["hold"]) for s, _ in trials)


def to_success(evals: list[tuple[float, bool]]) -> tuple[float | None, float | None]:
    """(first, holds) of a run's evaluations `[(interaction so far, succeeds)]` in order:
    the interaction until the first evaluation that succeeds, and until the first one
    from which every later evaluation succeeds too (it meets the criterion and holds it
    to the end of the run); None for one that never comes."""
    first = next((t for t, good in evals if good), None)
    holds = None
    for t, good in reversed(evals):
        if not good:
            break
        holds = t
    return first, holds


def verdict_line(verdicts: list[bool]) -> str:
    """Every evaluation's verdict in order, `1` a success and `.` a miss."""
    return "".join("1" if v else "." for v in verdicts)


def last_successes(verdicts: list[bool], last: int = 10) -> tuple[int, int]:
    """(successes, evaluations) among the `last` evaluations (all, if fewer)."""
    tail = verdicts[-last:] if last > 0 else []
    return sum(tail), len(tail)


def median_to_success(values: list[float | None]) -> float | None:
    """The median over seeds of `to_success`'s figures, a seed that never got there
    counting as later than any that did: None if the median seed never did."""
    if not values:
        return None
    ranked = sorted(values, key=lambda v: (v is None, v or 0))
    n = len(ranked)
    middle = ranked[(n - 1) // 2 : n // 2 + 1]
    if any(v is None for v in middle):
        return None
    return sum(v for v in middle if v is not None) / len(middle)


def judge(
    out: Path, seed: int, wall_s: float, return_at_least: float | None,
    upright: float | None, hold: float,
) -> Seed:
    """One seed of experiment folder `out` (see the module)."""
    run = out / f"seed-{seed}"
    rows = returns.read(run / "returns.csv")
    evals = returns.evaluations(rows)
    if not evals:
        raise returns.ReturnsError(
            f"{run}: no greedy evaluation in returns.csv (learn more trials than eval_every)"
        )
    topics = [recording.AGENT_TIMING] + ([recording.MEASUREMENT] if upright is not None else [])
    rec = recording.read(run / "run.mcap", topics)
    steps = sorted(float(s) for s in recording.agent_steps_ns(rec.of(recording.AGENT_TIMING)))
    notes = []
    task = task_of(run)
    if upright is None:
        assert return_at_least is not None
        good = [e.greedy is not None and e.greedy >= return_at_least for e in evals]
    else:
        greedy = greedy_states(rec.of(recording.MEASUREMENT))
        good = [all(upright_at_end(t, task, upright, hold) for t in greedy[e.trial]) for e in evals]
        for k, trial in enumerate(greedy[evals[-1].trial]):
            at, share = upright_times(trial, task, upright)
            notes.append(
                f"seed {seed}, last greedy trial from start state {k}: "
                + ("never upright" if at is None else f"first upright at {at:.2f} s, upright {100 * share:.0f} % of it")
            )
    last = evals[-1]
    assert last.greedy is not None
    first, holds = to_success([(e.sim_time_s, g) for e, g in zip(evals, good)])
    return Seed(
        seed=seed,
        ts=task.ts,
        trials=last.trial,
        final=last.greedy,
        succeeds=good[-1],
        first_success_s=first,
        holds_s=holds,
        first_success_samples=None if first is None else round(first / task.ts),
        holds_samples=None if holds is None else round(holds / task.ts),
        learning_mean=statistics.mean(r.ret for r in rows[-100:]),
        wall_s=wall_s,
        agent_ms=(percentile(steps, 50) / 1e6, percentile(steps, 99) / 1e6) if steps else None,
        curve=[(e.sim_time_s, e.greedy) for e in evals if e.greedy is not None],
        verdicts=good,
        notes=notes,
    )


def seed_results(
    out: Path, return_at_least: float | None = None, upright: float | None = None, hold: float = 1.5
) -> list[Seed]:
    """Every seed of experiment folder `out` (seeds.sh's OUT), in seed order; give one of
    `return_at_least` and `upright`."""
    return [judge(out, s, w, return_at_least, upright, hold) for s, w in sorted(walls(out).items())]
