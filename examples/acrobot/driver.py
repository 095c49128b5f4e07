#!/usr/bin/env python3
"""A driver for the rig (docs/driver.md) that simulates the acrobot (acrobot.py) in
lockstep (or, with --clock realtime, on the realtime clock): a system the rig does not
contain, served through the official iceoryx2 bindings with the task file acrobot.toml
(or acrobot-balance.toml).

    python3 examples/acrobot/driver.py [--driver-id ID] [--task FILE]
                                       [--clock realtime [--speed S]] [--verbose]
    rig run --plant external --task examples/acrobot/acrobot.toml

The driver id defaults to the task's name, the one `rig run --task` looks for. Stop it
with Ctrl-C or SIGTERM.
"""

import importlib.util
import sys
from pathlib import Path

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: driver.py needs the rig's Python package rigkit: pip install ./python")

from acrobot import Acrobot  # noqa: E402
from rigkit.model_driver import run  # noqa: E402

if __name__ == "__main__":
    task = Path(__file__).resolve().parent / "acrobot.toml"
    sys.exit(run(__doc__, lambda _: Acrobot(), default_task=task, shape=(4, 1), what="acrobot"))
