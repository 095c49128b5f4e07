import math
import random

from rigkit.angle import wrap


def test_an_angle_inside_is_kept_to_the_bit() -> None:
    rng = random.Random(1)
    for _ in range(1000):
        a = rng.uniform(-math.pi, math.pi)
        assert wrap(a) == a


def test_wraps_into_the_half_open_interval_as_the_rig() -> None:
    # plant/src/angle.rs's own cases.
    assert wrap(math.pi) == -math.pi
    assert wrap(-math.pi) == -math.pi
    assert abs(wrap(3.0 * math.pi + 0.1) - (-math.pi + 0.1)) < 1e-12
    for i in range(-1000, 1000):
        assert -math.pi <= wrap(i * 0.37) < math.pi


def test_a_remainder_that_rounds_to_two_pi_is_wrapped_to_minus_pi() -> None:
    # (a + pi) is a tiny negative number: fmod plus 2 pi rounds to 2 pi exactly.
    a = -math.pi - 1e-17
    assert wrap(a) == -math.pi


def test_the_rigs_formula_not_the_modulo_one() -> None:
    # (a + pi) % 2pi - pi moves an angle inside the interval by a rounding error.
    a = 0.1
    assert (a + math.pi) % (2.0 * math.pi) - math.pi != a
    assert wrap(a) == a
