#!/usr/bin/env python3
"""A driver for the rig (docs/driver.md) that simulates the rotary inverted pendulum of
the Quanser QUBE-Servo 2 (furuta.py) in lockstep: a system the rig does not contain,
served through the official iceoryx2 bindings with the task file furuta.toml.

    python3 examples/furuta/driver.py [--driver-id furuta] [--task FILE]
    rig run --plant external --task examples/furuta/furuta.toml

Stop it with Ctrl-C or SIGTERM.
"""

import argparse
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "python_driver"))  # the contract's modules

from furuta import Furuta  # noqa: E402
from lockstep import Services, serve_until_signalled  # noqa: E402
from task import Task  # noqa: E402


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
    p.add_argument("--verbose", action="store_true", help="log resets to stderr")
    args = p.parse_args()
    task = Task.read(args.task)
    if (task.n, task.m) != (4, 1):
        p.error(f"--task {args.task}: {task.n} states and {task.m} actions, not 4 and 1")
    print(
        f"driver {args.driver_id!r}: task {task.name} (QUBE-Servo 2 rotary pendulum), "
        f"Ts {task.ts * 1e3:g} ms, lockstep",
        file=sys.stderr,
        flush=True,
    )
    serve_until_signalled(Services(args.driver_id), task, Furuta(), "driver", args.verbose)
    return 0


if __name__ == "__main__":
    sys.exit(main())
