"""Gymnasium's MountainCarContinuous-v0 as the rig's task mountain-car-continuous.toml.

The environment's state is [position, velocity] (float32 after a step; a reset draws the
position from [-0.6, -0.4] at rest); the mapping reads it and places the reset
environment at the rig's start state.
"""

import numpy as np

ENV_ID = "MountainCarContinuous-v0"
TASK = "mountain-car-continuous.toml"


def state(env):
    position, velocity = env.unwrapped.state
    return [float(position), float(velocity)]


def place(env, x0):
    env.unwrapped.state = np.array(x0, dtype=np.float32)
