#!/usr/bin/env python3
"""A driver for the rig (docs/driver.md) that simulates the rotary inverted pendulum of
the Quanser QUBE-Servo 2 (furuta.py) in lockstep (or, with --clock realtime, on the
realtime clock): a system the rig does not contain, served through the official iceoryx2
bindings with the task file furuta.toml (or furuta-balance.toml, furuta-swing-balance.toml).

    python3 examples/furuta/driver.py [--driver-id ID] [--task FILE] [--damping SET]
                                      [--clock realtime [--speed S]] [--verbose]
    rig run --plant external --task examples/furuta/furuta.toml

The driver id defaults to the task's name, the one `rig run --task` looks for. Stop it
with Ctrl-C or SIGTERM.
"""

import importlib.util
import sys
from pathlib import Path

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: driver.py needs the rig's Python package rigkit: pip install ./python")

from furuta import DAMPING, DEFAULT_DAMPING, Furuta  # noqa: E402
from rigkit.model_driver import run  # noqa: E402

DAMPING_OPTION = (
    "--damping",
    dict(
        choices=sorted(DAMPING),
        default=DEFAULT_DAMPING,
        help="the viscous damping's published set (furuta.py): gym-brt (D_r = 0.00027, "
        "D_p = 0.00005 N m s/rad) or manual (the QUBE-Servo 2 User Manual's 0.0015, 0.0005) "
        f"[default: {DEFAULT_DAMPING}]",
    ),
)

if __name__ == "__main__":
    sys.exit(
        run(
            __doc__,
            lambda args: Furuta(args.damping),
            default_task=Path(__file__).resolve().parent / "furuta.toml",
            shape=(4, 1),
            what=lambda args: f"QUBE-Servo 2 rotary pendulum, {args.damping} damping",
            options=[DAMPING_OPTION],
        )
    )
