#!/usr/bin/env python3
"""Can the model's pendulum be swung up at all within a trial of furuta.toml? A check with
an energy-pumping controller, no learning: from hanging at rest, every Ts = 20 ms (the
task's sampling time) it applies

    u = sat(k_E E sign(alpha_dot cos alpha) - k_theta theta)

saturated at the voltage bound, with E the pendulum's energy (zero upright at rest) and
the arm pulled back to centre. For each damping set of furuta.py and voltage bound it
prints the closest approach to upright within the 4 s trial over a small family of gains
(k_E in 300, 700, 1000, 1500 V/J; k_theta in 8, 12, 16, 20 V/rad), among those that keep
the arm inside the task's operating range (|theta| < 2 rad): that approach, when, the
pendulum's speed there, and the gains. A check of the swing-up task's feasibility
(docs/results/furuta.md).

    python3 examples/furuta/pump.py
    python3 examples/furuta/pump.py --damping gym-brt --bound 5   # one damping set, one bound
"""

import argparse
import importlib.util
import math
import sys

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: pump.py needs the rig's Python package rigkit: pip install ./python")

import furuta  # noqa: E402

TS, TRIAL = 0.02, 4.0
GAINS = [(k_e, k_t) for k_e in (300.0, 700.0, 1000.0, 1500.0) for k_t in (8.0, 12.0, 16.0, 20.0)]


def pump(damping: str, v_max: float, k_e: float, k_theta: float):
    """(closest |alpha|, its time, |alpha_dot| there, largest |theta|) over one trial."""
    f = furuta.Furuta(damping)
    f.place([0.0, math.pi, 0.0, 0.0])
    closest, when, speed, arm = math.pi, 0.0, 0.0, 0.0
    for k in range(round(TRIAL / TS)):
        th, a, _, ad = f.x
        energy = 0.5 * furuta.J_B * ad * ad + furuta.M_P * furuta.G * furuta.L_CM * (math.cos(a) - 1.0)
        u = k_e * energy * (1.0 if ad * math.cos(a) > 0 else -1.0) - k_theta * th
        f.step([max(-v_max, min(v_max, u))], TS)
        arm = max(arm, abs(f.x[0]))
        if abs(f.x[1]) < closest:
            closest, when, speed = abs(f.x[1]), (k + 1) * TS, abs(f.x[3])
    return closest, when, speed, arm


BOUNDS = (3.0, 5.0, 10.0)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    p.add_argument("--damping", choices=sorted(furuta.DAMPING), action="append",
                   help="a damping set of furuta.py, repeatable [default: manual, then gym-brt]")
    p.add_argument("--bound", type=float, action="append", metavar="V",
                   help=f"a voltage bound [V], repeatable [default: {', '.join(f'{b:g}' for b in BOUNDS)}]")
    args = p.parse_args()
    for damping in args.damping or ("manual", "gym-brt"):
        d_r, d_p = furuta.DAMPING[damping]
        print(f"{damping} damping (D_r = {d_r:g}, D_p = {d_p:g} N m s/rad):")
        for v in args.bound or BOUNDS:
            runs = [(pump(damping, v, k_e, k_t), k_e, k_t) for k_e, k_t in GAINS]
            inside = [r for r in runs if r[0][3] < 2.0]
            (closest, when, speed, arm), k_e, k_t = min(inside, key=lambda r: r[0][0])
            print(
                f"  ±{v:g} V: closest {closest:.3f} rad from upright at {when:.2f} s "
                f"(|alpha_dot| {speed:.1f} rad/s, arm within {arm:.2f} rad; "
                f"k_E {k_e:g}, k_theta {k_t:g})"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
