"""Gymnasium's MuJoCo InvertedPendulum-v5 as the rig's task inverted-pendulum-v5.toml.

The environment's state is MuJoCo's qpos = [slider, hinge] and qvel (their velocities);
its observation is the same four numbers, float64: the task's state
[x, theta, x_dot, theta_dot], positions first. A reset draws all four uniformly within
±0.01; the mapping then sets the rig's start state with the environment's set_state.
"""

import numpy as np

ENV_ID = "InvertedPendulum-v5"
TASK = "inverted-pendulum-v5.toml"


def state(env):
    data = env.unwrapped.data
    return [float(v) for v in (*data.qpos, *data.qvel)]


def place(env, x0):
    env.unwrapped.set_state(np.array(x0[:2], dtype=np.float64), np.array(x0[2:], dtype=np.float64))
