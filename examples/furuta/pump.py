#!/usr/bin/env python3
"""How close a bang-bang energy-pumping controller swings the model's pendulum to upright
from hanging at rest: u = -k (E_up - E) sign(alpha_dot cos alpha), saturated at each
voltage bound, every 2 ms for 6 s, with E the pendulum's energy (zero upright at rest).
A check of the swing-up task's difficulty (docs/results/furuta.md).

    python3 examples/furuta/pump.py
"""

import math

import furuta


def closest_to_upright(v_max: float, seconds: float = 6.0, dt: float = 0.002) -> float:
    f = furuta.Furuta()
    f.place([0.0, math.pi, 0.0, 0.0])
    closest = math.pi
    for _ in range(round(seconds / dt)):
        _, a, _, ad = f.x
        energy = 0.5 * furuta.J_B * ad * ad + furuta.M_P * furuta.G * furuta.L_CM * (math.cos(a) - 1.0)
        u = 2000.0 * energy * (1.0 if ad * math.cos(a) > 0 else -1.0)
        f.step([max(-v_max, min(v_max, u))], dt)
        closest = min(closest, abs(f.x[1]))
    return closest


if __name__ == "__main__":
    for v in (3.0, 5.0, 10.0, 15.0):
        print(f"±{v:g} V: closest {closest_to_upright(v):.3f} rad from upright in 6 s")
