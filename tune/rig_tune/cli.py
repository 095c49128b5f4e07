"""The command line of `rig tune`."""

from __future__ import annotations

import argparse
from pathlib import Path

DESCRIPTION = """\
Find the learner configuration that learns a task: a hyperparameter study with Optuna
over a search space (a TOML file of configuration keys and ranges), each trial a
configuration learned on the study's seeds by `rig learn` (or by `rig run --plant
external` against a lockstep driver), pruned early when its greedy returns fall below
the median of earlier trials at the same evaluation. The study lives in a file next to
the output (SQLite), or in a PostgreSQL database that several machines share: run the
same command on each. When it has its trials, the best configuration is written as
OUT/best.toml (for `rig learn --config`), re-run on fresh seeds beside the preset, and
reported in OUT/report.md. Ctrl-C stops cleanly; the same command continues the study.
"""

EPILOG = """\
examples:
  rig tune --space-for mlac --task examples/furuta/furuta.toml > space.toml
  rig tune --task examples/furuta/furuta.toml --algo mlac --space space.toml --workers 2
  rig tune ... --storage postgresql://rig:secret@db.lab/rig   # the same on every machine

objective (maximised): the mean over the study's seeds of each run's mean greedy return
over its last --last evaluations. Study seeds are 1..--seeds; the check's seeds start
at 1001, so the check never reuses a seed the study chose by.
"""


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="rig tune",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    learner = p.add_argument_group("what is learned (as `rig learn` and `rig config` take it)")
    learner.add_argument("--task", metavar="FILE", help="a task file (docs/tasks.md)")
    learner.add_argument("--system", help="a built-in system (pendulum, arm-vertical, ...)")
    learner.add_argument("--algo", default="mlac", help="sac, mlac, rmac, vgbp or sarsa (default: mlac)")
    learner.add_argument("--approx", help="llr, rbf, tiles or lstd (default: the rig's)")
    learner.add_argument("--horizon", help="infinite or finite (default: infinite)")
    learner.add_argument(
        "--config", metavar="FILE", help="values every trial starts from, over the preset (as `rig learn --config`)"
    )
    learner.add_argument(
        "--trials", type=positive, metavar="T",
        help="learning trials per run (default: the configuration's run.trials)",
    )

    space = p.add_argument_group("the search space")
    space.add_argument("--space", type=Path, metavar="FILE", help="the search space (TOML; docs/tune.md)")
    space.add_argument(
        "--space-for", metavar="ALGO",
        help="print a starting search space for ALGO, derived from its preset (with --approx, --task, ...), and exit",
    )

    study = p.add_argument_group("the study")
    study.add_argument(
        "--n-trials", type=positive, default=50, metavar="N",
        help="finished trials (complete or pruned) the study needs, counted over every worker and machine; "
        "each worker may finish one more (default: 50)",
    )
    study.add_argument("--workers", type=positive, default=1, metavar="N", help="worker processes on this machine (default: 1)")
    study.add_argument("--out", type=Path, default=Path("out/tune"), metavar="DIR", help="output folder (default: out/tune)")
    study.add_argument(
        "--storage", metavar="URL",
        help="where the study lives (default: sqlite:///OUT/study.db); a postgresql://USER:PASSWORD@HOST/DB "
        "URL shares it between machines",
    )
    study.add_argument(
        "--study", metavar="NAME",
        help="the study's name (default: from the task, learner, space, seeds and trials, so that the same command names the same study)",
    )
    study.add_argument("--sampler", choices=("tpe", "random"), default="tpe", help="Optuna's sampler (default: tpe)")
    study.add_argument(
        "--sampler-seed", type=int, metavar="S",
        help="seed of the sampler, for a study repeatable on one machine: worker k uses S + k (default: a fresh "
        "seed for every worker, so that workers on several machines do not propose the same configurations)",
    )
    study.add_argument(
        "--pruner", choices=("median", "none"), default="median",
        help="median: stop a trial whose greedy return falls below the median of earlier trials at the same "
        "evaluation, after 5 trials and the first half of a run (default: median)",
    )
    study.add_argument(
        "--heartbeat", type=positive, default=10, metavar="S",
        help="a worker records that it lives every S seconds; a trial silent for 2 S (a killed worker) is "
        "marked failed and the study goes on (default: 10)",
    )
    study.add_argument(
        "--max-failures", type=positive, default=3, metavar="N",
        help="a worker stops after N failed trials in a row (default: 3)",
    )

    runs = p.add_argument_group("seeds and the final check")
    runs.add_argument("--seeds", type=positive, default=3, metavar="N", help="seeds per trial: 1..N (default: 3)")
    runs.add_argument(
        "--last", type=positive, default=3, metavar="K",
        help="a run's final greedy return is the mean of its last K evaluations (default: 3)",
    )
    runs.add_argument(
        "--check-seeds", type=nonnegative, default=5, metavar="M",
        help="fresh seeds 1001..1000+M on which the best configuration and the preset are re-run for the report; 0: no check (default: 5)",
    )
    runs.add_argument(
        "--driver-cmd", metavar="TEMPLATE",
        help="learn against an external lockstep driver: the command that starts one, with {id} for its "
        "driver id (each worker starts its own), e.g. 'python3 examples/furuta/driver.py --driver-id {id} --clock lockstep'",
    )
    runs.add_argument(
        "--keep-recordings", action="store_true",
        help="with --driver-cmd: keep each run's run.mcap and checkpoints (default: removed once the run has "
        "finished, its returns.csv kept)",
    )
    p.add_argument("--worker-index", type=int, help=argparse.SUPPRESS)
    return p


def positive(text: str) -> int:
    return bounded(text, 1)


def nonnegative(text: str) -> int:
    return bounded(text, 0)


def bounded(text: str, low: int) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if v < low:
        raise argparse.ArgumentTypeError(f"must be at least {low}, not {v}")
    return v


def selection(args: argparse.Namespace, algo: str | None = None) -> list[str]:
    """The flags that select the learner, as `rig config` and `rig learn` take them."""
    flags = ["--algo", algo or args.algo]
    for name in ("task", "system", "approx", "horizon", "config"):
        value = getattr(args, name)
        if value is not None:
            flags += [f"--{name}", str(value)]
    return flags
