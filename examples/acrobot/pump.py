#!/usr/bin/env python3
"""How soon an energy-pumping controller swings the acrobot (acrobot.py) up, per torque
bound: Spong's swing-up (M. W. Spong, "The swing up control problem for the Acrobot",
IEEE Control Systems Magazine 15(1), 1995) — the elbow driven by partial feedback
linearisation, q2'' = k_p (q2* - q2) - k_d q2', towards q2* = (2 alpha / pi) atan(q1'),
after a first push towards q2* = alpha for 0.25 s — over 100 gain sets (alpha, k_p, k_d),
from hanging at rest, the torque saturated to the bound and held for 50 ms.

    python3 examples/acrobot/pump.py
    python3 examples/acrobot/pump.py --bound 4 --gains=-2.5,10,1   # one bound, one gain set

Prints, per bound, the earliest time the tip comes within 0.1 m of its highest point (2 m
above the pivot) within 10 s, and the gains that do it.
"""

import argparse
import importlib.util
import itertools
import math
import sys

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: pump.py needs the rig's Python package rigkit: pip install ./python")

from acrobot import Acrobot, elbow_drift, elbow_inertia  # noqa: E402

TS, SECONDS = 0.05, 10.0


def torque(s, v: float) -> float:
    """The elbow torque that gives q2'' = v (partial feedback linearisation)."""
    return v * elbow_inertia(s) - elbow_drift(s)


def swing_up(bound: float, alpha: float, kp: float, kd: float):
    """The first time [s] the tip is within 0.1 m of its top, or None."""
    a = Acrobot()
    a.place([math.pi, 0.0, 0.0, 0.0])
    for k in range(round(SECONDS / TS)):
        q1, q2, dq1, dq2 = a.s
        target = alpha if k < 5 else 2.0 * alpha / math.pi * math.atan(dq1)
        u = torque(a.s, kp * (target - math.remainder(q2, 2.0 * math.pi)) - kd * dq2)
        a.step([min(max(u, -bound), bound)], TS)
        q1, q2 = a.s[0], a.s[1]
        if -math.cos(q1) - math.cos(q1 + q2) >= 1.9:
            return (k + 1) * TS
    return None


BOUNDS = [1.0, 2.0, 3.0, 4.0, 6.0]
GAINS = list(itertools.product([-0.5, -1.0, -1.5, -2.0, -2.5], [5, 10, 20, 50, 100], [1, 2, 5, 10]))


def gain_set(text: str):
    """ALPHA,K_P,K_D."""
    try:
        alpha, kp, kd = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: three numbers ALPHA,K_P,K_D") from None
    return alpha, kp, kd


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    p.add_argument("--bound", type=float, action="append", metavar="B",
                   help=f"a torque bound [N m], repeatable [default: {', '.join(f'{b:g}' for b in BOUNDS)}]")
    p.add_argument("--gains", type=gain_set, action="append", metavar="ALPHA,K_P,K_D",
                   help="a gain set, repeatable [default: the 100 of alpha in -0.5..-2.5, "
                   "k_p in 5..100, k_d in 1..10]")
    args = p.parse_args()
    gains = args.gains or GAINS
    for bound in args.bound or BOUNDS:
        found = [(t, g) for g in gains if (t := swing_up(bound, *g)) is not None]
        if found:
            t, g = min(found)
            print(f"±{bound:g} N m: within 0.1 m of the top at {t:.2f} s (alpha {g[0]}, k_p {g[1]}, k_d {g[2]})")
        else:
            print(f"±{bound:g} N m: never within 0.1 m of the top in {SECONDS:g} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
