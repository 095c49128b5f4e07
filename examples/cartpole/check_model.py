#!/usr/bin/env python3
"""Checks the cart-pole model (cartpole.py): without force it keeps its energy (to 1e-9 J
over 10 s), and its accelerations are Gymnasium CartPole-v1's (classic_control/cartpole.py)
at 1000 random states, for both of CartPole's forces (+-10 N), to 1e-9. Exits 1 on a
failure; without gymnasium, the second check is skipped and said so.

    python3 examples/cartpole/check_model.py
"""

import importlib.util
import math
import random
import sys

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: check_model.py needs the rig's Python package rigkit: pip install ./python")

from cartpole import CartPole, derivative, energy  # noqa: E402
from rigkit.model_check import Check, verdict  # noqa: E402


def energy_drift() -> float:
    """The largest energy change [J] over 10 s without force, from three start states."""
    worst = 0.0
    for x0 in ([0.0, 2.0, 0.3, 1.0], [0.5, 0.1, -1.0, 0.0], [0.0, math.pi - 0.01, 0.0, 0.0]):
        c = CartPole()
        c.place(x0)
        e0 = energy(c.state())
        for _ in range(500):
            c.step([0.0], 0.02)
        worst = max(worst, abs(energy(c.state()) - e0))
    return worst


def gymnasium_difference() -> float | None:
    """The largest difference from CartPole-v1's accelerations (read back from its Euler
    step, kinematics integration), or None without gymnasium."""
    try:
        import gymnasium
        import numpy as np
    except ImportError:
        return None
    env = gymnasium.make("CartPole-v1").unwrapped
    env.reset(seed=0)
    rng = random.Random(1)
    worst = 0.0
    for _ in range(1000):
        s = [rng.uniform(-2.0, 2.0), rng.uniform(-math.pi, math.pi), rng.uniform(-3, 3), rng.uniform(-6, 6)]
        for action, force in ((1, env.force_mag), (0, -env.force_mag)):
            # Gymnasium's state is [x, x_dot, theta, theta_dot].
            env.state = np.array([s[0], s[2], s[1], s[3]])
            env.steps_beyond_terminated = None
            env.step(action)
            xacc = (env.state[1] - s[2]) / env.tau
            thacc = (env.state[3] - s[3]) / env.tau
            ours = derivative(s, force)
            worst = max(worst, abs(xacc - ours[2]), abs(thacc - ours[3]))
    return worst


def main():
    return verdict(
        Check("energy drift over 10 s without force", "J", energy_drift(), 1e-9),
        Check("largest difference from CartPole-v1's accelerations", "", gymnasium_difference(), 1e-9),
        skipped="the comparison with CartPole-v1",
    )


if __name__ == "__main__":
    sys.exit(main())
