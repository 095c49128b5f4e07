#!/usr/bin/env python3
"""Checks the acrobot model (acrobot.py): without torque it keeps its energy (to 1e-6 J
over 10 s), and its equations of motion are Gymnasium Acrobot-v1's (`_dsdt`, the "book"
dynamics) at 1000 random states and torques, exactly. Exits 1 on a failure; without
gymnasium, the second check is skipped and said so.

    python3 examples/acrobot/check_model.py
"""

import importlib.util
import math
import random
import sys

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: check_model.py needs the rig's Python package rigkit: pip install ./python")

from acrobot import Acrobot, derivative  # noqa: E402
from rigkit.model_check import Check, verdict  # noqa: E402


def energy_drift() -> float:
    """The largest energy change [J] over 10 s without torque, from three start states."""
    worst = 0.0
    for x0 in ([2.0, 0.5, 0.0, 0.0], [0.3, -1.0, 1.0, -2.0], [math.pi - 0.1, 0.0, 0.0, 0.0]):
        a = Acrobot()
        a.place(x0)
        e0 = a.energy()
        for _ in range(200):
            a.step([0.0], 0.05)
        worst = max(worst, abs(a.energy() - e0))
    return worst


def gymnasium_difference() -> float | None:
    """The largest difference from Acrobot-v1's derivative, or None without gymnasium."""
    try:
        import gymnasium
        import numpy as np
    except ImportError:
        return None
    env = gymnasium.make("Acrobot-v1").unwrapped
    rng = random.Random(1)
    worst = 0.0
    for _ in range(1000):
        s = [rng.uniform(-math.pi, math.pi), rng.uniform(-math.pi, math.pi), rng.uniform(-12, 12), rng.uniform(-28, 28)]
        tau = rng.uniform(-6.0, 6.0)
        theirs = env._dsdt(np.array(s + [tau]))[:4]
        worst = max(worst, max(abs(a - b) for a, b in zip(theirs, derivative(s, tau))))
    return worst


def main():
    return verdict(
        Check("energy drift over 10 s without torque", "J", energy_drift(), 1e-6),
        Check("largest difference from Acrobot-v1's derivative", "", gymnasium_difference(), 0.0),
        skipped="the comparison with Acrobot-v1",
    )


if __name__ == "__main__":
    sys.exit(main())
