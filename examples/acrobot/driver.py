#!/usr/bin/env python3
"""A driver for the rig (docs/driver.md) that simulates the acrobot (acrobot.py) in
lockstep: a system the rig does not contain, served through the official iceoryx2
bindings with the task file acrobot.toml.

    python3 examples/acrobot/driver.py [--driver-id acrobot] [--task FILE]
    rig run --plant external --task examples/acrobot/acrobot.toml

Stop it with Ctrl-C or SIGTERM.
"""

import argparse
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "python_driver"))  # the contract's modules

from acrobot import Acrobot  # noqa: E402
from lockstep import Services, serve_until_signalled  # noqa: E402
from task import Task, TaskError  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--driver-id",
        help="services rig/driver/ID/...; letters, digits, '-' and '_' [default: the task's name]",
    )
    p.add_argument(
        "--task",
        default=str(HERE / "acrobot.toml"),
        help="the task file served: the acrobot's shape (4 states, 1 action) "
        "[default: acrobot.toml next to this file]",
    )
    p.add_argument("--verbose", action="store_true", help="log resets to stderr")
    args = p.parse_args()
    try:
        task = Task.read(args.task)
    except TaskError as e:
        p.error(f"--task: {e}")
    if (task.n, task.m) != (4, 1):
        p.error(f"--task {args.task}: {task.n} states and {task.m} actions, not 4 and 1")
    driver_id = args.driver_id or task.name.replace(".", "-")
    print(
        f"driver {driver_id!r}: task {task.name} (acrobot), Ts {task.ts * 1e3:g} ms, lockstep",
        file=sys.stderr,
        flush=True,
    )
    serve_until_signalled(Services(driver_id), task, Acrobot(), "driver", args.verbose)
    return 0


if __name__ == "__main__":
    sys.exit(main())
