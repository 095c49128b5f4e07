#!/usr/bin/env python3
"""How far from upright a linear controller can balance the acrobot within its torque
bound: a discrete LQR on the model (acrobot.py) linearised at upright, sampled at the
task's 50 ms, its torque saturated, simulated for 3 s (60 samples) from the first link
deflected by THETA1 at rest. A start "balances" if both angles end within 0.05 rad.

    python3 examples/acrobot/lqr_region.py            # the task's weights, +-6/10/20 N m
    python3 examples/acrobot/lqr_region.py --sweep    # 243 weightings, +-6 N m

Prints, per torque bound and weighting, the largest THETA1 (in steps of 5 mrad) from
which it balances. Needs numpy.
"""

import itertools
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import acrobot  # noqa: E402

TS = 0.05  # the task's sampling time [s]
SAMPLES = 60  # a 3 s trial


def step(x, u: float):
    """The model's state after one sample with torque `u` held."""
    a = acrobot.Acrobot()
    a.place(list(x))
    a.step([u], TS)
    return np.array(a.state(), float)


def linearised():
    """(A, B) of the sampled model at upright, by central differences."""
    x0, e = np.zeros(4), 1e-6
    a = np.column_stack([(step(x0 + d, 0.0) - step(x0 - d, 0.0)) / (2 * e) for d in np.eye(4) * e])
    b = ((step(x0, e) - step(x0, -e)) / (2 * e)).reshape(4, 1)
    return a, b


def lqr(a, b, q, r):
    """The discrete LQR gain K (u = -K x), the Riccati equation iterated to convergence."""
    p = q.copy()
    for _ in range(20000):
        k = np.linalg.solve(r + b.T @ p @ b, b.T @ p @ a)
        nxt = q + a.T @ p @ (a - b @ k)
        if np.max(np.abs(nxt - p)) < 1e-10:
            break
        p = nxt
    return k


def balances(k, theta1: float, bound: float) -> bool:
    """Whether u = sat(-K x) brings the model from (theta1, 0, 0, 0) to upright."""
    x = np.array([theta1, 0.0, 0.0, 0.0])
    for _ in range(SAMPLES):
        x = step(x, float(np.clip(-(k @ x)[0], -bound, bound)))
    return max(abs(x[0]), abs(x[1])) < 0.05


def region(k, bound: float) -> float:
    """The largest theta1 (5 mrad steps, up to 0.2 rad) from which every smaller one balances."""
    best = 0.0
    for th in np.arange(0.005, 0.2001, 0.005):
        if not balances(k, th, bound):
            break
        best = th
    return best


def main():
    a, b = linearised()
    if "--sweep" in sys.argv:
        weights = itertools.product((1, 5, 50), (0.1, 1, 10), (0.01, 0.1, 1), (0.01, 0.1, 1), (0.01, 1, 100))
        best = max((region(lqr(a, b, np.diag(w[:4]), np.array([[w[4]]])), 6.0), w) for w in weights)
        print(f"+-6 N m, 243 weightings: at most theta1 = {best[0]:.3f} rad (Q, R = {best[1]})")
        return
    q = np.diag([5.0, 1.0, 0.05, 0.05])  # the task's reward weights
    for bound in (6.0, 10.0, 20.0):
        for r in (0.01, 1.0):
            k = lqr(a, b, q, np.array([[r]]))
            print(f"+-{bound:.0f} N m, R {r}: balances from theta1 up to {region(k, bound):.3f} rad (K_theta1 {k[0, 0]:.0f} N m/rad)")


if __name__ == "__main__":
    main()
