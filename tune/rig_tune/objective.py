"""One trial of a study: the configuration it samples, learned on each of the study's
seeds in turn, followed evaluation by evaluation so that a poor trial is pruned early.

The objective, maximised: the mean over the study's seeds of each run's mean greedy
return over its last `last` evaluations (the figure `rig learn` reports as a run's final
greedy return)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from statistics import fmean
from typing import Any

import optuna

from . import config
from .runner import Runner, RunFailed, Stopped
from .space import Param


def final(greedy: list[float], last: int) -> float:
    """A run's final greedy return: the mean of its last `last` evaluations."""
    if not greedy:
        raise RunFailed(
            "the run made no greedy evaluation: lower run.eval_every or learn more trials"
        )
    return fmean(greedy[-last:])


@dataclass
class Objective:
    """What every trial of a study shares."""

    base: dict[str, Any]
    space: list[Param]
    seeds: list[int]
    last: int
    runner: Runner
    out: Path

    def __call__(self, trial: optuna.Trial) -> float:
        values = {p.key: p.suggest(trial) for p in self.space}
        folder = self.out / "trials" / f"{trial.number:05d}"
        path = config.write(config.with_values(self.base, values), folder / "config.toml")
        trial.set_user_attr("folder", str(folder))
        step = 0

        def follow(greedy: float) -> bool:
            nonlocal step
            trial.report(greedy, step)
            step += 1
            return trial.should_prune()

        finals = []
        for seed in self.seeds:
            try:
                greedy = self.runner.run(path, seed, folder / f"seed-{seed}", follow)
            except Stopped:
                raise optuna.TrialPruned(f"pruned at evaluation {step}") from None
            except RunFailed as e:
                trial.set_user_attr("error", str(e))
                raise
            finals.append(final(greedy, self.last))
        trial.set_user_attr("finals", finals)
        return fmean(finals)
