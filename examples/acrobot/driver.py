#!/usr/bin/env python3
"""A driver for the rig (docs/driver.md) that simulates the acrobot (acrobot.py) in
lockstep: a system the rig does not contain, served through the official iceoryx2
bindings with the task file acrobot.toml (or acrobot-balance.toml).

    python3 examples/acrobot/driver.py [--driver-id ID] [--task FILE] [--verbose]
    rig run --plant external --task examples/acrobot/acrobot.toml

The driver id defaults to the task's name, the one `rig run --task` looks for. Stop it
with Ctrl-C or SIGTERM.
"""

import sys
from pathlib import Path

try:
    from rigkit.script import need
except ModuleNotFoundError:
    sys.exit("error: driver.py needs the rig's Python package rigkit: pip install ./python")

HERE = Path(__file__).resolve().parent

if __name__ == "__main__":
    need("driver.py", modules=["iceoryx2"])
    from acrobot import Acrobot
    from rigkit.model_driver import run

    sys.exit(run(__doc__, lambda _: Acrobot(), default_task=HERE / "acrobot.toml", shape=(4, 1), what="acrobot"))
