#!/usr/bin/env python3
"""Checks that a task file's reward is the environment's: steps the environment from
random states with random actions and compares each reward with the task's rho(x, u)
(rigkit.task: the quadratic form and any further terms, as the rig computes it) of the
mapped state before the step and the action clipped to the bounds.

    python3 examples/gymnasium/check_reward.py --mapping examples/gymnasium/pendulum_v1.py

Prints the largest difference and exits 1 if it exceeds 1e-9.
"""

import argparse
import importlib.util
import random
import sys
from pathlib import Path

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: check_reward.py needs the rig's Python package rigkit: pip install ./python")

from rigkit.script import need  # noqa: E402

need("check_reward.py", modules=["gymnasium", "iceoryx2"])

import gymnasium  # noqa: E402
import numpy as np  # noqa: E402

from rigkit.adapter import load  # noqa: E402
from rigkit.task import Task  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--mapping", required=True, help="the mapping module (rigkit.adapter)")
    p.add_argument("--steps", type=int, default=2000, help="environment steps [default: 2000]")
    args = p.parse_args()
    mapping = load(args.mapping)
    task = Task.read(str(Path(args.mapping).resolve().parent / mapping.TASK))
    env = gymnasium.make(mapping.ENV_ID)
    rng = random.Random(7)
    worst = 0.0
    for k in range(args.steps):
        if k % 50 == 0:
            env.reset(seed=k)
            x0 = [rng.uniform(lo, hi) for lo, hi in task.ranges]
            mapping.place(env, x0)
        x = mapping.state(env)
        u = [rng.uniform(2 * lo, 2 * hi) for lo, hi in zip(task.low, task.high)]
        _, reward, _, _, _ = env.step(np.asarray(u))
        clipped = [min(max(v, lo), hi) for v, lo, hi in zip(u, task.low, task.high)]
        worst = max(worst, abs(float(reward) - task.reward(x, clipped)))
    print(f"{mapping.ENV_ID}: {args.steps} steps, largest |reward - rho(x, u)| = {worst:.3g}")
    return 0 if worst <= 1e-9 else 1


if __name__ == "__main__":
    sys.exit(main())
