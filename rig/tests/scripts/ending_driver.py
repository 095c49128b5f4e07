#!/usr/bin/env python3
"""A lockstep driver of the pendulum's task that provides its own reward and trial
endings (docs/driver.md, PROVIDES_REWARD), for the rig's tests: the state stays where
the reset put it, each step's reward is 1, and each trial ends at step --end-at,
terminated or truncated (--ending). --nan-at K sends a NaN reward at step K instead.
--old-version publishes the previous protocol's info (rig.DriverInfo.v2) instead.

    python3 rig/tests/scripts/ending_driver.py --driver-id ID --end-at 5 --ending terminated
"""

import argparse
import ctypes
import math
import sys
from pathlib import Path

from rigkit import messages
from rigkit.angle import wrap
from rigkit.lockstep import Services
from rigkit.serving import serve_until_signalled
from rigkit.task import Task

ROOT = Path(__file__).resolve().parents[3]


class Still:
    """A system that stays at its start state and rewards every step with 1."""

    provides_reward = True

    def __init__(self, task, end_at: int, ending: str, nan_at: int):
        self.task, self.end_at, self.ending, self.nan_at = task, end_at, ending, nan_at
        self.x, self.k = [0.0] * task.n, 0

    def place(self, x0):
        self.x = [wrap(v) if a else v for v, a in zip(x0, self.task.angles)]
        self.k = 0

    def step(self, u, dt):
        self.k += 1

    def state(self):
        return self.x

    def outcome(self):
        reward = math.nan if self.k == self.nan_at else 1.0
        end = self.k == self.end_at
        return reward, end and self.ending == "terminated", end and self.ending == "truncated"


class OldInfo(ctypes.Structure):
    """The previous protocol's info: version 2, without `provides`."""

    _fields_ = messages.DriverInfo._fields_[:-1]

    def __init__(self, provides=0, **fields):
        super().__init__(**fields)

    @staticmethod
    def type_name() -> str:
        return "rig.DriverInfo.v2"


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--driver-id", required=True, help="services rig/driver/ID/...")
    p.add_argument("--end-at", type=int, default=5, help="the step each trial ends at [default: 5]")
    p.add_argument(
        "--ending",
        choices=["terminated", "truncated"],
        default="terminated",
        help="how the trial ends there [default: terminated]",
    )
    p.add_argument("--nan-at", type=int, default=-1, help="a NaN reward at this step [default: none]")
    p.add_argument("--old-version", action="store_true", help="publish a version 2 info")
    args = p.parse_args()
    task = Task.read(str(ROOT / "plant" / "tasks" / "pendulum.toml"))
    services = Services(args.driver_id, info_type=OldInfo if args.old_version else messages.DriverInfo)
    sim = Still(task, args.end_at, args.ending, args.nan_at)
    serve_until_signalled(services, task, sim, "ending driver", False)
    return 0


if __name__ == "__main__":
    sys.exit(main())
