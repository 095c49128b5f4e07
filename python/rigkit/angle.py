"""Angles as the rig wraps them (plant/src/angle.rs)."""

import math


def wrap(a: float) -> float:
    """`a` wrapped to [-pi, pi) with the rig's floating-point operations: an angle inside
    is returned as it is, and Rust's `rem_euclid` is C's fmod plus the divisor if
    negative, so that a wrapped angle is the rig's bit for bit."""
    if -math.pi <= a < math.pi:
        return a
    w = math.fmod(a + math.pi, 2.0 * math.pi)
    if w < 0.0:
        w += 2.0 * math.pi
    w -= math.pi
    # The remainder can round to exactly 2 pi for a tiny negative `a + pi`.
    return w - 2.0 * math.pi if w >= math.pi else w
