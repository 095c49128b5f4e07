"""The example simulations' integrator (rigkit.rk4)."""

import math
from collections.abc import Sequence

from rigkit import rk4


def test_one_step_is_exact_for_a_cubic_in_time() -> None:
    # dx/dt = 3 t^2 as the state [t, x]: RK4 integrates polynomials of degree 3 exactly.
    x = rk4.step(lambda s: [1.0, 3.0 * s[0] ** 2], [0.0, 0.0], 2.0)
    assert x == [2.0, 8.0]


def test_integration_splits_the_period_into_steps_no_longer_than_the_longest() -> None:
    calls: list[Sequence[float]] = []

    def f(s: Sequence[float]) -> list[float]:
        calls.append(s)
        return [-s[0]]

    x = rk4.integrate(f, [1.0], 0.05, 0.01)
    assert len(calls) == 4 * 5  # five steps of 10 ms, four evaluations each
    assert abs(x[0] - math.exp(-0.05)) < 1e-10  # RK4: about h^5/120 a step
    calls.clear()
    rk4.integrate(f, [1.0], 0.001, 0.01)
    assert len(calls) == 4  # one step at least
