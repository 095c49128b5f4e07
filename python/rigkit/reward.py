"""A task's reward rho(x, u) as the rig computes it (plant/src/reward, docs/tasks.md):
the quadratic form and the terms a task file adds, in the rig's order of operations, so
that the numbers are the rig's bit for bit.

    rho(x, u) = -e'Qe - u'Pu - sum_i w_i (1 - cos(x_i - x_r,i)) - sum_j c_j |u_j|
                + bonus if x lies in the reward's goal region

with e = x - x_r, angle components wrapped to [-pi, pi). Standard library only.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence

from .angle import wrap


class Region:
    """A box (low, high) or a ball (centre, radius) in the state space; an angle's
    offset from the box's middle or the ball's centre is taken on the circle."""

    def __init__(self, kind: str, first: list[float], second: list[float]) -> None:
        self.kind, self.first, self.second = kind, first, second

    def contains(self, x: Sequence[float], angles: Sequence[bool]) -> bool:
        if not all(math.isfinite(v) for v in x):
            return False

        def offset(i: int, origin: float) -> float:
            d = x[i] - origin
            return wrap(d) if angles[i] else d

        if self.kind == "box":
            for i, (lo, hi) in enumerate(zip(self.first, self.second)):
                if not (math.isfinite(lo) and math.isfinite(hi)) or not angles[i]:
                    if not lo <= x[i] <= hi:
                        return False
                    continue
                half = 0.5 * (hi - lo)
                if not (half >= math.pi or abs(offset(i, lo + half)) <= half):
                    return False
            return True
        s = 0.0
        for i, (c, r) in enumerate(zip(self.first, self.second)):
            if math.isfinite(r):
                d = offset(i, c) / r
                s += d * d
        return s <= 1.0

    def digest(self) -> bytes:
        """The region's canonical bytes: kind (0 box, 1 ball), then pairs per state."""
        out = bytearray([0 if self.kind == "box" else 1])
        for a, b in zip(self.first, self.second):
            out.extend(_f64(a) + _f64(b))
        return bytes(out)


def _f64(v: float) -> bytes:
    return struct.pack("<d", v)


class Reward:
    """rho(x, u) of a task: `q`, `p`, `reference`, `angles` (the quadratic form) and the
    optional `cosine` weights, `abs_action` weights and `goal` = (Region, bonus)."""

    def __init__(
        self,
        q: list[float],
        p: list[float],
        reference: list[float],
        angles: list[bool],
        cosine: list[float] | None = None,
        abs_action: list[float] | None = None,
        goal: tuple[Region, float] | None = None,
    ) -> None:
        self.q, self.p, self.reference, self.angles = q, p, reference, angles
        self.cosine, self.abs_action, self.goal = cosine, abs_action, goal

    def error(self, x: Sequence[float], i: int) -> float:
        e = x[i] - self.reference[i]
        return wrap(e) if self.angles[i] else e

    def __call__(self, x: Sequence[float], u: Sequence[float]) -> float:
        r = 0.0
        for i, q in enumerate(self.q):
            e = self.error(x, i)
            r -= q * e * e
        for j, p in enumerate(self.p):
            r -= p * u[j] * u[j]
        # The terms in the rig's order, each its state value plus its action value.
        if self.cosine is not None:
            s = 0.0
            for w, xi, ri in zip(self.cosine, x, self.reference):
                s += w * (1.0 - math.cos(xi - ri))
            r += -s + 0.0
        if self.abs_action is not None:
            s = 0.0
            for c, uj in zip(self.abs_action, u):
                s += c * abs(uj)
            r += 0.0 + -s
        if self.goal is not None:
            region, bonus = self.goal
            r += (bonus if region.contains(x, self.angles) else 0.0) + 0.0
        return r
