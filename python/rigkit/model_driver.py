"""The command line of a lockstep driver for one simulated model (examples/acrobot/,
examples/furuta/): the driver id, the task file (checked for the model's shape),
--verbose and the model's own options, then lockstep.serve_until_signalled.

    from rigkit.model_driver import run
    run(__doc__, lambda args: Acrobot(), default_task=HERE / "acrobot.toml", shape=(4, 1), what="acrobot")
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from . import script
from .realtime import check_driver_id
from .task import Task, TaskError

if TYPE_CHECKING:
    from .lockstep import Simulation


def run(
    doc: str,
    simulation: Callable[[argparse.Namespace], Simulation],
    default_task: Path,
    shape: tuple[int, int],
    what: str | Callable[[argparse.Namespace], str],
    options: Sequence[tuple[str, dict[str, Any]]] = (),
) -> int:
    """Parses the command line described by `doc` and serves the model `simulation(args)`
    makes from the parsed arguments (n states and m actions, `shape`) for the task file
    given, until a signal. `options` are the model's own flags, `(flag, keywords of
    argparse's add_argument)` pairs; `what` names the model, a string or a function of
    the parsed arguments. Ends in one line if iceoryx2 is not installed."""
    script.need(Path(sys.argv[0]).name, modules=["iceoryx2"])
    from .lockstep import Services, serve_until_signalled

    p = argparse.ArgumentParser(description=" ".join(doc.split("\n\n")[0].split()))
    p.add_argument(
        "--driver-id",
        help="services rig/driver/ID/...; letters, digits, '-' and '_' [default: the task's name]",
    )
    p.add_argument(
        "--task",
        default=str(default_task),
        help=f"the task file served: {shape[0]} states and {shape[1]} action(s) [default: {default_task.name} next to the driver]",
    )
    for flag, keywords in options:
        p.add_argument(flag, **keywords)
    p.add_argument("--verbose", action="store_true", help="log resets to stderr")
    args = p.parse_args()
    task, driver_id = task_and_driver_id(p, args.task, args.driver_id)
    if (task.n, task.m) != tuple(shape):
        p.error(f"--task {args.task}: {task.n} states and {task.m} actions, not {shape[0]} and {shape[1]}")
    name = what(args) if callable(what) else what
    print(
        f"driver {driver_id!r}: task {task.name} ({name}), Ts {task.ts * 1e3:g} ms, lockstep",
        file=sys.stderr,
        flush=True,
    )
    serve_until_signalled(Services(driver_id), task, simulation(args), "driver", args.verbose)
    return 0


def task_and_driver_id(p: argparse.ArgumentParser, path: str, driver_id: str | None) -> tuple[Task, str]:
    """The task file at `path` (`--task`) and the driver id, `driver_id` (`--driver-id`)
    or else the task's name; the parser's error if either is bad."""
    try:
        task = Task.read(path)
    except TaskError as e:
        p.error(f"--task: {e}")
    chosen = driver_id or task.name.replace(".", "-")
    try:
        check_driver_id(chosen)
    except ValueError as e:
        p.error(f"--driver-id {e}")
    return task, chosen
