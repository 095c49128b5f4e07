"""The fourth-order Runge-Kutta integrator of the example simulations (examples/acrobot,
examples/furuta, examples/cartpole): an action held over a sample period, split into
equal steps no longer than a model's longest."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

# dx/dt at x, the action held.
Derivative = Callable[[Sequence[float]], Sequence[float]]


def step(f: Derivative, x: Sequence[float], h: float) -> list[float]:
    """One fourth-order Runge-Kutta step of `h` seconds of dx/dt = f(x) from `x`."""
    k1 = f(x)
    k2 = f([a + 0.5 * h * k for a, k in zip(x, k1)])
    k3 = f([a + 0.5 * h * k for a, k in zip(x, k2)])
    k4 = f([a + h * k for a, k in zip(x, k3)])
    return [a + h / 6.0 * (p + 2.0 * q + 2.0 * r + w) for a, p, q, r, w in zip(x, k1, k2, k3, k4)]


def integrate(f: Derivative, x: Sequence[float], dt: float, h_max: float) -> list[float]:
    """`dt` seconds of dx/dt = f(x) from `x`, in the fewest equal steps of at most
    `h_max` seconds (one at least)."""
    n = max(1, math.ceil(dt / h_max - 1e-9))
    out = list(x)
    for _ in range(n):
        out = step(f, out, dt / n)
    return out
