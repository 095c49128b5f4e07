"""The command line of a lockstep driver for one simulated model (examples/acrobot/): the
driver id, the task file (checked for the model's shape) and --verbose, then
lockstep.serve_until_signalled.

    from model_driver import run
    run(__doc__, Acrobot(), default_task=HERE / "acrobot.toml", shape=(4, 1), what="acrobot")
"""

import argparse
import sys

from lockstep import Services, serve_until_signalled
from task import Task, TaskError


def run(doc: str, simulation, default_task, shape, what: str) -> int:
    """Parses the command line described by `doc` and serves `simulation` (n states and
    m actions, `shape`) for the task file given, until a signal."""
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
    p.add_argument("--verbose", action="store_true", help="log resets to stderr")
    args = p.parse_args()
    try:
        task = Task.read(args.task)
    except TaskError as e:
        p.error(f"--task: {e}")
    if (task.n, task.m) != tuple(shape):
        p.error(f"--task {args.task}: {task.n} states and {task.m} actions, not {shape[0]} and {shape[1]}")
    driver_id = args.driver_id or task.name.replace(".", "-")
    print(
        f"driver {driver_id!r}: task {task.name} ({what}), Ts {task.ts * 1e3:g} ms, lockstep",
        file=sys.stderr,
        flush=True,
    )
    serve_until_signalled(Services(driver_id), task, simulation, "driver", args.verbose)
    return 0
