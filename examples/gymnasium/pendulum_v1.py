"""Gymnasium's Pendulum-v1 as the rig's task pendulum-v1.toml.

The environment's state is [theta, theta_dot] (theta from upright, not wrapped); its
observation [cos, sin, theta_dot] is float32, so the mapping reads the float64 state.
"""

import numpy as np

from rigkit.angle import wrap

ENV_ID = "Pendulum-v1"
TASK = "pendulum-v1.toml"


def state(env):
    th, thdot = env.unwrapped.state
    return [wrap(float(th)), float(thdot)]


def place(env, x0):
    env.unwrapped.state = np.array(x0, dtype=np.float64)
