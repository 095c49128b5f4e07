#!/usr/bin/env python3
"""The yardstick for a Gymnasium environment served to the rig (examples/gymnasium/):
the environment's own loop in Python, env.step after env.step, for as many steps as a
rig run takes, with no rig and no transport.

    python3 bench/scripts/env_step.py --env Pendulum-v1 --trials 100 --trial-steps 201

It resets the environment every --trial-steps steps (as the rig's trials do), steps it
with uniformly random actions of its action space (seeded), and prints the steps, the
time of the stepping loop alone and the time per step. Needs gymnasium and numpy.
"""

import argparse
import importlib.util
import sys
import time

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: env_step.py needs the rig's Python package rigkit: pip install ./python")

from rigkit.script import need  # noqa: E402

need("env_step.py", modules=["gymnasium"])

import gymnasium  # noqa: E402
import numpy as np  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--env", default="Pendulum-v1", help="the environment [default: Pendulum-v1]")
    p.add_argument("--trials", type=int, default=100, help="trials (resets) [default: 100]")
    p.add_argument(
        "--trial-steps",
        type=int,
        default=201,
        help="steps per trial [default: 201, a 10 s trial of Pendulum-v1's 0.05 s and its start]",
    )
    p.add_argument("--seed", type=int, default=1, help="seeds the resets and actions [default: 1]")
    args = p.parse_args()
    if args.trials < 1 or args.trial_steps < 1:
        p.error("--trials and --trial-steps must be at least 1")
    env = gymnasium.make(args.env)
    space = env.action_space
    rng = np.random.default_rng(args.seed)
    n = args.trials * args.trial_steps
    actions = rng.uniform(space.low, space.high, size=(n,) + space.shape)
    t0 = time.perf_counter()
    for k in range(n):
        if k % args.trial_steps == 0:
            env.reset(seed=args.seed * 1_000_003 + k)
        env.step(np.asarray(actions[k], dtype=np.float64))
    elapsed = time.perf_counter() - t0
    print(f"{args.env}: {n} steps in {elapsed:.4f} s, {elapsed / n * 1e6:.2f} us per step")
    return 0


if __name__ == "__main__":
    sys.exit(main())
