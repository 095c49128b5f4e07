#!/usr/bin/env python3
"""A driver for the rig (docs/driver.md) that simulates the rotary inverted pendulum of
the Quanser QUBE-Servo 2 (furuta.py) in lockstep: a system the rig does not contain,
served through the official iceoryx2 bindings with the task file furuta.toml.

    python3 examples/furuta/driver.py [--driver-id furuta] [--task FILE] [--damping SET]
    rig run --plant external --task examples/furuta/furuta.toml

Stop it with Ctrl-C or SIGTERM.
"""

import argparse
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "python_driver"))  # the contract's modules

from furuta import DAMPING, DEFAULT_DAMPING, Furuta  # noqa: E402
from lockstep import Services, serve_until_signalled  # noqa: E402
from task import Task, TaskError  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--driver-id",
        default="furuta",
        help="services rig/driver/ID/...; letters, digits, '-' and '_' [default: furuta]",
    )
    p.add_argument(
        "--task",
        default=str(HERE / "furuta.toml"),
        help="the task file served: the Furuta pendulum's shape (4 states, 1 action) "
        "[default: furuta.toml next to this file]",
    )
    p.add_argument(
        "--damping",
        choices=sorted(DAMPING),
        default=DEFAULT_DAMPING,
        help="the viscous damping's published set (furuta.py): gym-brt (D_r = 0.00027, "
        "D_p = 0.00005 N m s/rad) or manual (the QUBE-Servo 2 User Manual's 0.0015, 0.0005) "
        f"[default: {DEFAULT_DAMPING}]",
    )
    p.add_argument("--verbose", action="store_true", help="log resets to stderr")
    args = p.parse_args()
    try:
        task = Task.read(args.task)
    except TaskError as e:
        p.error(f"--task: {e}")
    if (task.n, task.m) != (4, 1):
        p.error(f"--task {args.task}: {task.n} states and {task.m} actions, not 4 and 1")
    print(
        f"driver {args.driver_id!r}: task {task.name} (QUBE-Servo 2 rotary pendulum, "
        f"{args.damping} damping), Ts {task.ts * 1e3:g} ms, lockstep",
        file=sys.stderr,
        flush=True,
    )
    serve_until_signalled(Services(args.driver_id), task, Furuta(args.damping), "driver", args.verbose)
    return 0


if __name__ == "__main__":
    sys.exit(main())
