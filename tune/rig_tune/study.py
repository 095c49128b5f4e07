"""The study: its storage, sampler and pruner, the worker processes that run its trials,
and the progress they make."""

from __future__ import annotations

import argparse
import hashlib
import os
import random
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import optuna
import sqlalchemy.exc
from optuna.trial import FrozenTrial, TrialState
from rigkit import processes

from .objective import Objective
from .runner import Driver, Runner, RunFailed

FINISHED = (TrialState.COMPLETE, TrialState.PRUNED)
PROGRESS_S = 2.0
SCHEMA_ATTEMPTS = 5


def storage_url(args: argparse.Namespace) -> str:
    """The storage's URL: the one given, else an SQLite file in the output folder."""
    return args.storage or "sqlite:///" + str((args.out / "study.db").resolve())


def storage(args: argparse.Namespace) -> optuna.storages.RDBStorage:
    """The study's storage, with a heartbeat so that a killed worker's trial is failed.

    Machines that open a new database at the same moment race to create its tables; the
    losers find them made when they try again."""
    url = storage_url(args)
    engine = {"connect_args": {"timeout": 60}} if url.startswith("sqlite") else None
    for attempt in range(SCHEMA_ATTEMPTS):
        try:
            return optuna.storages.RDBStorage(
                url, engine_kwargs=engine, heartbeat_interval=args.heartbeat, grace_period=2 * args.heartbeat
            )
        except sqlalchemy.exc.IntegrityError:
            if attempt + 1 == SCHEMA_ATTEMPTS:
                raise
            time.sleep(random.uniform(0.2, 1.0))
    raise AssertionError("unreachable")


def name(args: argparse.Namespace, base_text: str, space_text: str) -> str:
    """The study's name: given, or the same for the same task, learner, space and runs."""
    if args.study:
        return str(args.study)
    what = "\n".join([base_text, space_text, str(args.seeds), str(args.last), str(args.trials)])
    digest = hashlib.sha256(what.encode()).hexdigest()[:10]
    return f"rig-tune-{digest}"


class FolderTaken(Exception):
    """The output folder holds another study's trials."""


def claim(out: Path, study_name: str) -> None:
    """Makes `out` the folder of study `study_name`, or refuses: trial folders are numbered
    per study, so a second study in the same folder would overwrite the first's."""
    mark = out / "study"
    held = mark.read_text().strip() if mark.exists() else None
    if held is None:
        mark.write_text(study_name + "\n")
    elif held != study_name:
        raise FolderTaken(
            f"{out} holds the trials of study {held}, not of {study_name} (another task, learner, "
            f"space or run length, or another rig version): give another --out, or --study {held} to go on with it"
        )


def sampler(args: argparse.Namespace, worker: int) -> optuna.samplers.BaseSampler:
    seed = None if args.sampler_seed is None else args.sampler_seed + worker
    if args.sampler == "random":
        return optuna.samplers.RandomSampler(seed=seed)
    return optuna.samplers.TPESampler(seed=seed)


def pruner(args: argparse.Namespace, evaluations: int) -> optuna.pruners.BasePruner:
    """The median pruner, from the sixth trial on and after half of a trial's first run."""
    if args.pruner == "none":
        return optuna.pruners.NopPruner()
    return optuna.pruners.MedianPruner(n_startup_trials=5, n_warmup_steps=max(1, evaluations // 2))


def finished(trials: list[FrozenTrial]) -> int:
    return sum(t.state in FINISHED for t in trials)


@dataclass
class FailureLimit:
    """Stops a worker after `limit` failed trials in a row."""

    limit: int
    in_a_row: int = 0

    def __call__(self, study: optuna.Study, trial: FrozenTrial) -> None:
        self.in_a_row = self.in_a_row + 1 if trial.state == TrialState.FAIL else 0
        if self.in_a_row >= self.limit:
            study.stop()


def work(args: argparse.Namespace, study_name: str, objective: Objective, evaluations: int) -> None:
    """One worker: runs trials until the study has `--n-trials` finished ones."""
    k = args.worker_index
    study = optuna.load_study(
        study_name=study_name, storage=storage(args), sampler=sampler(args, k), pruner=pruner(args, evaluations)
    )
    if finished(study.get_trials(deepcopy=False)) >= args.n_trials:
        return
    driver = None
    if args.driver_cmd:
        driver_id = f"tune-{os.getpid()}-{k}"
        driver = Driver(args.driver_cmd, driver_id, args.out / "drivers" / f"{driver_id}.log")
        objective.runner = Runner(objective.runner.trials, driver, args.keep_recordings)
    try:
        study.optimize(
            objective,
            callbacks=[optuna.study.MaxTrialsCallback(args.n_trials, states=FINISHED), FailureLimit(args.max_failures)],
            catch=(RunFailed,),
        )
    finally:
        if driver is not None:
            driver.close()


def start_workers(argv: list[str], workers: int, out: Path) -> list[subprocess.Popen[bytes]]:
    """The worker processes: this command again, each with its index."""
    logs = out / "workers"
    logs.mkdir(parents=True, exist_ok=True)
    procs = []
    for k in range(workers):
        sink = open(logs / f"worker-{os.getpid()}-{k}.log", "w")
        cmd = [sys.executable, "-m", "rig_tune", *argv, "--worker-index", str(k)]
        procs.append(subprocess.Popen(cmd, stdout=sink, stderr=subprocess.STDOUT))
        sink.close()
    return procs


def forward_sigterm(procs: list[subprocess.Popen[bytes]]) -> None:
    """SIGTERM (a timeout, a scheduler) acts as Ctrl-C: passed on to the workers, which a
    terminal's Ctrl-C reaches by itself, then KeyboardInterrupt here."""

    def stopping(signum: int, frame: object) -> None:
        for p in procs:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, stopping)


def describe(t: FrozenTrial) -> str:
    """One finished trial, as the progress shows it."""
    params = ", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in t.params.items())
    if t.state == TrialState.COMPLETE:
        what = f"{t.value:.1f}"
    elif t.state == TrialState.PRUNED:
        last = t.last_step
        what = f"pruned after {last + 1} evaluations" if last is not None else "pruned"
    else:
        what = "failed" + (f": {t.user_attrs['error']}" if "error" in t.user_attrs else "")
    return f"trial {t.number}: {what} ({params})"


def watch(study: optuna.Study, target: int, procs: list[subprocess.Popen[bytes]]) -> None:
    """Prints each trial as it ends and the study's count, until the workers exit."""
    seen: set[int] = set()
    while True:
        alive = any(p.poll() is None for p in procs)
        trials = study.get_trials(deepcopy=False)
        ended = [t for t in trials if t.state.is_finished() and t.number not in seen]
        for t in ended:
            seen.add(t.number)
            print(describe(t), flush=True)
        if ended:
            best = study.best_trial if any(t.state == TrialState.COMPLETE for t in trials) else None
            running = sum(t.state == TrialState.RUNNING for t in trials)
            lead = f", best {best.value:.1f} (trial {best.number})" if best else ""
            print(f"  {finished(trials)} trials finished of {target}, {running} running{lead}", flush=True)
        if not alive:
            return
        time.sleep(PROGRESS_S)


def stop(procs: list[subprocess.Popen[bytes]]) -> None:
    """Waits for interrupted workers to mark their trials and exit (killed after 30 s)."""
    for p in procs:
        processes.stop(p, None, patience=30)
