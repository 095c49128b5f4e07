#!/usr/bin/env python3
"""How far from upright a linear controller can balance the acrobot within its torque
bound: a discrete LQR on the model (acrobot.py) linearised at upright, sampled every TS
(default 50 ms), its torque saturated, simulated for 3 s from the first link deflected by
THETA1 at rest. A start "balances" if both angles end within 0.05 rad.

    python3 examples/acrobot/lqr_region.py            # the task's weights, +-6/10/20 N m
    python3 examples/acrobot/lqr_region.py --sweep    # 243 weightings, +-6 N m
    python3 examples/acrobot/lqr_region.py --ts 0.02 --bound 10 --starts 2
    python3 examples/acrobot/lqr_region.py --bound 20 --starts 1 --gamma 0.95

Prints, per torque bound and weighting, the largest THETA1 (in steps of 5 mrad) from
which it balances. `--ts S` sets the sampling time, `--bound B` a single torque bound
(N m); `--starts F` also checks the balance task's start states scaled by F; `--gamma G`
makes the LQR the discounted one, sum of G^k times the cost (the LQR of sqrt(G) A,
sqrt(G) B), the controller a learner with discount G would converge to.
Needs numpy.
"""

import argparse
import importlib.util
import itertools
import sys

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: lqr_region.py needs the rig's Python package rigkit: pip install ./python")

from rigkit.script import need  # noqa: E402

need("lqr_region.py", modules=["numpy"])

import numpy as np  # noqa: E402

import acrobot  # noqa: E402

TS = 0.05  # the sampling time [s], --ts
SAMPLES = 60  # a 3 s trial, round(3 / TS)
# acrobot-balance.toml's start states (theta1, theta2), at rest.
STARTS = [(0.05, 0.0), (-0.05, 0.0), (0.0, 0.1), (0.025, -0.05)]


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


def balances(k, theta1: float, bound: float, theta2: float = 0.0) -> bool:
    """Whether u = sat(-K x) brings the model from (theta1, theta2, 0, 0) to upright."""
    x = np.array([theta1, theta2, 0.0, 0.0])
    for _ in range(SAMPLES):
        x = step(x, float(np.clip(-(k @ x)[0], -bound, bound)))
    return max(abs(x[0]), abs(x[1])) < 0.05


def region(k, bound: float) -> float:
    """The largest theta1 (5 mrad steps, up to 0.4 rad) from which every smaller one balances."""
    best = 0.0
    for th in np.arange(0.005, 0.4001, 0.005):
        if not balances(k, th, bound):
            break
        best = th
    return best


def starts(k, bound: float, scale: float) -> str:
    """Which of the balance task's start states, scaled by `scale`, the LQR balances."""
    ok = [balances(k, scale * t1, bound, scale * t2) for t1, t2 in STARTS]
    return f"{sum(ok)}/{len(ok)} start states x{scale:g}"


def arguments():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    p.add_argument("--ts", type=float, default=TS, metavar="S", help=f"the sampling time [s] [default: {TS}]")
    p.add_argument("--bound", type=float, metavar="B",
                   help="one torque bound [N m] [default: 6, 10 and 20 in turn]")
    p.add_argument("--starts", type=float, metavar="F",
                   help="also check the balance task's start states scaled by F [default: not]")
    p.add_argument("--gamma", type=float, default=1.0, metavar="G",
                   help="the discounted LQR: sum of G^k times the cost [default: 1, undiscounted]")
    p.add_argument("--sweep", action="store_true",
                   help="the largest region over 243 weightings at +-6 N m instead")
    args = p.parse_args()
    if not args.ts > 0.0:
        p.error(f"--ts {args.ts}: must be positive")
    if not 0.0 < args.gamma <= 1.0:
        p.error(f"--gamma {args.gamma}: must be in (0, 1]")
    return args


def main():
    global TS, SAMPLES
    args = arguments()
    TS = args.ts
    SAMPLES = round(3.0 / TS)
    only, scale = args.bound, args.starts
    a, b = linearised()
    a, b = np.sqrt(args.gamma) * a, np.sqrt(args.gamma) * b
    if args.sweep:
        weights = itertools.product((1, 5, 50), (0.1, 1, 10), (0.01, 0.1, 1), (0.01, 0.1, 1), (0.01, 1, 100))
        best = max((region(lqr(a, b, np.diag(w[:4]), np.array([[w[4]]])), 6.0), w) for w in weights)
        print(f"+-6 N m, 243 weightings: at most theta1 = {best[0]:.3f} rad (Q, R = {best[1]})")
        return
    q = np.diag([5.0, 1.0, 0.05, 0.05])  # the task's reward weights
    for bound in (6.0, 10.0, 20.0) if only is None else (only,):
        for r in (0.01, 1.0):
            k = lqr(a, b, q, np.array([[r]]))
            line = f"Ts {TS * 1000:g} ms, +-{bound:g} N m, R {r}: balances from theta1 up to {region(k, bound):.3f} rad"
            line += f" (K_theta1 {k[0, 0]:.0f} N m/rad)"
            if scale is not None:
                line += "; " + starts(k, bound, scale)
            print(line)


if __name__ == "__main__":
    main()
