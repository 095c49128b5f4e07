"""`rig tune` (or `python3 -m rig_tune` with `RIG_BIN` naming the rig): see `cli`."""

from __future__ import annotations

import argparse
import importlib.util
import sys
import tempfile
import warnings
from pathlib import Path
from typing import Any

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: rig tune needs the rig's Python package rigkit: python3 -m pip install ./python")

from rigkit import script  # noqa: E402

script.need("rig tune", modules=["optuna", "matplotlib", "tomli_w"])

import optuna  # noqa: E402

# The heartbeat that fails a killed worker's trial is "experimental" in Optuna: used on
# purpose. Optuna's own log lines would repeat what the progress says.
warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
optuna.logging.set_verbosity(optuna.logging.WARNING)

from . import check, report, study  # noqa: E402
from .cli import parser, selection  # noqa: E402
from .config import RigError, accepted, rig_config, tunable, with_values  # noqa: E402
from .objective import Objective  # noqa: E402
from .runner import Runner, RunFailed  # noqa: E402
from .space import Param, SpaceError, load, starting_space  # noqa: E402

INTERRUPTED = 130


def main(argv: list[str]) -> int:
    script.interrupt_on_sigterm()
    args = parser().parse_args(argv)
    try:
        if args.space_for:
            return space_for(args)
        return tune(args, argv)
    except (RigError, SpaceError, RunFailed, study.FolderTaken) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return INTERRUPTED


def space_for(args: argparse.Namespace) -> int:
    """Prints the starting space of a preset, once the rig has accepted its every end."""
    base = rig_config(selection(args, args.space_for))
    what = " ".join(selection(args, args.space_for))
    text = starting_space(tunable(base), f"`{what}`")
    with tempfile.TemporaryDirectory() as scratch:
        path = Path(scratch) / "space.toml"
        path.write_text(text)
        searchable(base, load(path, tunable(base)), path, Path(scratch))
    print(text, end="")
    return 0


def searchable(base: dict[str, Any], space: list[Param], source: Path, scratch: Path) -> None:
    """Refuses a space whose ends the rig would refuse, before any trial runs."""
    for p in space:
        for v in p.extremes():
            refused = accepted(with_values(base, {p.key: v}), scratch / "config.toml")
            if refused:
                raise SpaceError(f'{source}: param "{p.key}": the rig refuses {v!r}: {refused}')


def tune(args: argparse.Namespace, argv: list[str]) -> int:
    if args.space is None:
        raise SpaceError("--space FILE is needed (`rig tune --space-for ALGO > space.toml` writes a starting one)")
    base = rig_config(selection(args))
    space = load(args.space, tunable(base))
    trials = args.trials or base["run"]["trials"]
    eval_every = base["run"]["eval_every"]
    if eval_every == 0 or trials < eval_every:
        raise RigError(f"no greedy evaluation in a run of {trials} trials with run.eval_every = {eval_every}: a study needs them")
    runner = Runner(args.trials, keep_recordings=args.keep_recordings)
    objective = Objective(base, space, list(range(1, args.seeds + 1)), args.last, runner, args.out)
    name = study.name(args, str(sorted(base.items())), args.space.read_text())
    if args.worker_index is not None:
        study.work(args, name, objective, trials // eval_every)
        return 0
    args.out.mkdir(parents=True, exist_ok=True)
    study.claim(args.out, name)
    searchable(base, space, args.space, args.out / "scratch")
    url = study.storage_url(args)
    s = optuna.create_study(study_name=name, storage=study.storage(args), direction="maximize", load_if_exists=True)
    done = study.finished(s.get_trials(deepcopy=False))
    print(f"study {name} ({url.split('@')[-1]}): {done} of {args.n_trials} trials finished", flush=True)
    if done < args.n_trials:
        procs = study.start_workers(argv, args.workers, args.out)
        study.forward_sigterm(procs)
        try:
            study.watch(s, args.n_trials, procs)
        except KeyboardInterrupt:
            study.stop(procs)
            done = study.finished(s.get_trials(deepcopy=False))
            print(f"stopped with {done} of {args.n_trials} trials finished; the same command continues the study",
                  file=sys.stderr)
            return INTERRUPTED
    return conclude(args, s, base, url, eval_every, runner)


def conclude(
    args: argparse.Namespace, s: optuna.Study, base: dict[str, Any], url: str, eval_every: int, runner: Runner
) -> int:
    """The check and the report, once the study has its trials."""
    trials = s.get_trials(deepcopy=False)
    if study.finished(trials) < args.n_trials:
        failed = [t for t in trials if t.state == optuna.trial.TrialState.FAIL]
        why = failed[-1].user_attrs.get("error", "see OUT/workers/") if failed else "the workers stopped"
        print(f"error: the study stopped with {study.finished(trials)} of {args.n_trials} trials finished "
              f"({len(failed)} failed; last: {why})", file=sys.stderr)
        return 1
    best = check.best_config(s, base, args.out)
    print(f"best: trial {s.best_trial.number}, {s.best_value:.1f}; configuration {best}", flush=True)
    arms = []
    if args.check_seeds > 0:
        print(f"check: the best and the preset on seeds {check.seeds(args.check_seeds)}", flush=True)
        arms = check.check(args, s, base, runner)
        finals = {a.label: a.finals(args.last) for a in arms}
        print(check.verdict(finals["best"], finals["preset"]), flush=True)
    path = report.write(args, s, url, arms, eval_every)
    print(f"report: {path}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
