"""Serves a Gymnasium environment with continuous spaces as a lockstep driver for the rig
(docs/driver.md, "Lockstep"), given a task file and a small mapping module.

    python3 examples/gymnasium/adapter.py --mapping examples/gymnasium/pendulum_v1.py
    rig run --plant external --task examples/gymnasium/pendulum-v1.toml --algo sac

The mapping module says how the environment and the task meet:

    ENV_ID = "Pendulum-v1"        the environment, made with gymnasium.make(ENV_ID)
    TASK = "pendulum-v1.toml"     the task file (relative to the module), unless --task
    def state(env) -> list        the task's state x (n floats) of the environment now
    def place(env, x0) -> None    put the environment (after its reset) at state x0

A RESET resets the environment (seeded from --seed and the reset's sequence number, so
two runs see the same environment) and places it at the rig's start state; each action
is one env.step(u) of the environment's own dt, which must be the task's sampling time.
The environment's own reward, termination and truncation go to the rig with each sample
(the driver provides the reward, docs/driver.md): the rig learns them as they are —
terminated ends the trial at a terminal state, truncated (the environment's time limit)
ends it and the critic bootstraps through it. With --task-reward the rig computes the
task file's reward and ends trials by the task instead (the task file must then express
the environment's reward; for Pendulum-v1 it does, exactly). Needs gymnasium
(`pip install "./python[gymnasium]"`).
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import gymnasium
import numpy as np

from .lockstep import Outcome, Services
from .serving import serve_until_signalled
from .model_driver import task_and_driver_id
from .task import Task


def load(path: str) -> ModuleType:
    """The mapping module at `path`."""
    spec = importlib.util.spec_from_file_location("mapping", path)
    if spec is None or spec.loader is None:
        raise ValueError(f"{path}: not a Python module")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class Environment:
    """A Gymnasium environment as the lockstep driver's simulation."""

    def __init__(self, mapping: Any, task: Task, seed: int, provides_reward: bool) -> None:
        self.mapping, self.task, self.seed = mapping, task, seed
        self.provides_reward = provides_reward
        self.last: Outcome = (0.0, False, False)  # the last step's reward, terminated, truncated
        self.env = gymnasium.make(mapping.ENV_ID)
        space = self.env.action_space
        if not isinstance(space, gymnasium.spaces.Box) or space.shape != (task.m,):
            raise ValueError(f"{mapping.ENV_ID}: action space {space}, the task has {task.m} actions")
        dt = getattr(self.env.unwrapped, "dt", None)
        if dt is not None and abs(dt - task.ts) > 1e-9 * task.ts:
            raise ValueError(f"{mapping.ENV_ID}: dt {dt} s, the task's sampling time is {task.ts} s")
        self.resets = 0

    def place(self, x0: list[float]) -> None:
        self.env.reset(seed=self.seed * 1_000_003 + self.resets)
        self.resets += 1
        self.mapping.place(self.env, x0)

    def step(self, u: list[float], dt: float) -> None:
        _, reward, terminated, truncated, _ = self.env.step(np.asarray(u, dtype=np.float64))
        self.last = (float(reward), bool(terminated), bool(truncated))

    def outcome(self) -> Outcome:
        """The last step's reward, terminated and truncated, as the environment said."""
        return self.last

    def state(self) -> list[float]:
        return [float(v) for v in self.mapping.state(self.env)]


def main() -> int:
    p = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    p.add_argument("--mapping", required=True, help="the mapping module (see above)")
    p.add_argument("--task", help="the task file [default: the mapping's TASK]")
    p.add_argument(
        "--driver-id",
        help="services rig/driver/ID/...; letters, digits, '-' and '_' "
        "[default: the task's name without dots]",
    )
    p.add_argument("--seed", type=int, default=1, help="seeds the environment's resets [default: 1]")
    p.add_argument(
        "--task-reward",
        action="store_true",
        help="leave the reward and the trials' endings to the rig (the task file's) instead "
        "of sending the environment's own [default: the environment's]",
    )
    p.add_argument("--verbose", action="store_true", help="log resets to stderr")
    args = p.parse_args()
    mapping = load(args.mapping)
    task_path = args.task or str(Path(args.mapping).resolve().parent / mapping.TASK)
    task, driver_id = task_and_driver_id(p, task_path, args.driver_id)
    try:
        sim = Environment(mapping, task, args.seed, provides_reward=not args.task_reward)
    except ValueError as e:
        p.error(str(e))
    reward = "the task's (the rig computes it)" if args.task_reward else "the environment's"
    print(
        f"adapter {driver_id!r}: {mapping.ENV_ID} as task {task.name}, Ts {task.ts * 1e3:g} ms, lockstep, "
        f"reward {reward}",
        file=sys.stderr,
        flush=True,
    )
    serve_until_signalled(Services(driver_id), task, sim, "adapter", args.verbose)
    return 0


if __name__ == "__main__":
    sys.exit(main())
