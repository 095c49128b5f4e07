#!/usr/bin/env python3
"""A driver for the rig (docs/driver.md) that simulates the cart-pole of Barto, Sutton and
Anderson (cartpole.py) in lockstep: a system the rig does not contain, served through the
official iceoryx2 bindings with the task file cartpole-balance.toml or
cartpole-swing-balance.toml.

    python3 examples/cartpole/driver.py [--driver-id ID] [--task FILE] [--verbose]
    rig run --plant external --task examples/cartpole/cartpole-balance.toml

The driver id defaults to the task's name, the one `rig run --task` looks for. Stop it
with Ctrl-C or SIGTERM.
"""

import importlib.util
import sys
from pathlib import Path

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: driver.py needs the rig's Python package rigkit: pip install ./python")

from cartpole import CartPole  # noqa: E402
from rigkit.model_driver import run  # noqa: E402

HERE = Path(__file__).resolve().parent

if __name__ == "__main__":
    sys.exit(
        run(
            __doc__,
            lambda args: CartPole(),
            default_task=HERE / "cartpole-balance.toml",
            shape=(4, 1),
            what="Barto-Sutton-Anderson cart-pole",
        )
    )
