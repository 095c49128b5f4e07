"""The final check: the study's best configuration and the preset, each learned on fresh
seeds the study never chose by, for the report."""

from __future__ import annotations

import argparse
from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from statistics import fmean
from typing import Any

import optuna

from . import config
from .objective import final
from .runner import Driver, Runner

CHECK_SEED = 1001


@dataclass
class Arm:
    """One configuration of the check: its file and, per seed, every greedy return."""

    label: str
    config: Path
    greedy: dict[int, list[float]]

    def finals(self, last: int) -> list[float]:
        return [final(g, last) for g in self.greedy.values()]


def seeds(count: int) -> list[int]:
    return list(range(CHECK_SEED, CHECK_SEED + count))


def best_config(study: optuna.Study, base: dict[str, Any], out: Path) -> Path:
    """Writes the best trial's configuration as OUT/best.toml."""
    return config.write(config.with_values(base, study.best_trial.params), out / "best.toml")


def check(args: argparse.Namespace, study: optuna.Study, base: dict[str, Any], runner: Runner) -> list[Arm]:
    """Runs (or reads back, when another machine ran it) the best and the preset on the
    check's seeds."""
    best = best_config(study, base, args.out)
    preset = config.write(base, args.out / "check" / "preset.toml")
    key = f"check-{study.best_trial.number}-{args.check_seeds}-{args.trials}"
    done = study.user_attrs.get(key)
    if done is None:
        done = {label: run_arm(args, runner, path, args.out / "check" / label)
                for label, path in (("best", best), ("preset", preset))}
        study.set_user_attr(key, done)
    return [Arm(label, path, {int(s): g for s, g in done[label].items()})
            for label, path in (("best", best), ("preset", preset))]


def run_arm(args: argparse.Namespace, runner: Runner, path: Path, out: Path) -> dict[str, list[float]]:
    """One configuration on every check seed: in parallel on simulated tasks, one after
    the other against a driver of its own."""
    todo = seeds(args.check_seeds)
    if args.driver_cmd is None:
        return {str(s): g for s, g in zip(todo, in_parallel(runner, path, todo, out, args.workers))}
    driver = Driver(args.driver_cmd, f"tune-check-{out.name}", out / "driver.log")
    try:
        external = Runner(runner.trials, driver, runner.keep_recordings)
        return {str(s): external.run(path, s, out / f"seed-{s}") for s in todo}
    finally:
        driver.close()


def in_parallel(runner: Runner, path: Path, todo: list[int], out: Path, workers: int) -> list[list[float]]:
    """Runs of `path` on the seeds `todo`, `workers` at a time. The first to fail (or
    Ctrl-C) stops the others at once, so that the check ends with its error instead of
    after every run."""
    with ThreadPoolExecutor(max_workers=workers) as pool:
        futures = [pool.submit(runner.run, path, s, out / f"seed-{s}") for s in todo]
        try:
            done, _ = wait(futures, return_when=FIRST_EXCEPTION)
            for f in done:
                f.result()  # the first failure, raised
            return [f.result() for f in futures]
        except BaseException:
            runner.cancelled.set()
            pool.shutdown(cancel_futures=True)
            raise


def verdict(best: list[float], preset: list[float]) -> str:
    """Whether the best configuration learned better than the preset on the check."""
    wins = sum(b > p for b, p in zip(best, preset))
    diff = fmean(best) - fmean(preset)
    word = "better than" if diff > 0 else "not better than"
    return (f"On the check's {len(best)} fresh seeds the best configuration is {word} the preset: "
            f"mean final greedy return {fmean(best):.1f} against {fmean(preset):.1f} "
            f"({diff:+.1f}); better on {wins} of {len(best)} seeds.")
