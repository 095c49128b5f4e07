#!/usr/bin/env python3
"""Serves a Gymnasium environment with continuous spaces as a lockstep driver for the rig,
given a task file and a small mapping module (rigkit.adapter says how; README.md beside
this file shows the mappings here).

    python3 examples/gymnasium/adapter.py --mapping examples/gymnasium/pendulum_v1.py
    rig run --plant external --task examples/gymnasium/pendulum-v1.toml --algo sac

Stop it with Ctrl-C or SIGTERM.
"""

import importlib.util
import sys

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: adapter.py needs the rig's Python package rigkit: pip install ./python")

from rigkit.script import need  # noqa: E402

if __name__ == "__main__":
    need("adapter.py", modules=["iceoryx2", "gymnasium"])
    from rigkit.adapter import main

    sys.exit(main())
