#!/usr/bin/env python3
"""Known controllers of the TRUE models on the benchmark's held-out systems: is each
success criterion (bench/python/systems.toml) reachable, and what does a controller that
knows the model score by it? No learner is involved.

    python3 bench/python/known_controllers.py [--matrix FILE]

- the linear-quadratic regulator of the true model, linearised about upright by central
  finite differences of one sampling period of the simulation (or of the environment's
  step), the discrete Riccati equation iterated to its fixed point, with the task's own
  Q and P: on every balance task;
- for the cart-pole's swing-up, an energy pump (K. J. Åström and K. Furuta, "Swinging up
  a pendulum by energy control", Automatica 36(2), 2000: push the cart so that the pole's
  energy approaches upright's, the cart held near the centre; its three gains and the
  hand-over picked among a few on this model) that hands over to the same regulator
  within 0.5 rad of upright.

Each runs one greedy trial from each of the task's start states, as the rig's greedy
evaluation does (the task's trial length, its operating range, the environment's own
endings through the Gymnasium mapping), and prints the return (the mean over the start
states, the task's reward or the environment's) and the verdict of the experiment's
success rule. Needs numpy (and gymnasium[mujoco] for the MuJoCo task).
"""

import argparse
import importlib.util
import math
import sys
import tomllib
from pathlib import Path

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: known_controllers.py needs the rig's Python package rigkit: pip install ./python")

from rigkit.script import need  # noqa: E402

need("known_controllers.py", modules=["numpy"])

import numpy as np  # noqa: E402
from rigkit.adapter import load  # noqa: E402
from rigkit.angle import wrap  # noqa: E402
from rigkit.seeds import TaskTimes, meets  # noqa: E402
from rigkit.task import Task  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
cartpole = load(str(ROOT / "examples" / "cartpole" / "cartpole.py"))


def linearise(step, x0, u0, eps=1e-5):
    """(A, B) of x_{k+1} = step(x_k, u_k) about (x0, u0), by central differences."""
    x0, u0 = np.asarray(x0, float), np.asarray(u0, float)
    n, m = len(x0), len(u0)
    a, b = np.zeros((n, n)), np.zeros((n, m))
    for i in range(n):
        d = np.zeros(n)
        d[i] = eps
        a[:, i] = (np.asarray(step(x0 + d, u0)) - np.asarray(step(x0 - d, u0))) / (2 * eps)
    for j in range(m):
        d = np.zeros(m)
        d[j] = eps
        b[:, j] = (np.asarray(step(x0, u0 + d)) - np.asarray(step(x0, u0 - d))) / (2 * eps)
    return a, b


def dlqr(a, b, q, r, iterations=100_000, tol=1e-12):
    """The gain K of u = -K x minimising the sum of x'Qx + u'Ru: the discrete Riccati
    equation iterated from Q to its fixed point."""
    p = q.copy()
    for _ in range(iterations):
        k = np.linalg.solve(r + b.T @ p @ b, b.T @ p @ a)
        nxt = q + a.T @ p @ (a - b @ k)
        if np.max(np.abs(nxt - p)) < tol * max(1.0, np.max(np.abs(p))):
            return k
        p = nxt
    raise RuntimeError("the Riccati iteration did not converge")


def regulator(task: Task, step):
    """u = -K x, saturated, K the LQR of the task's Q and P about the origin."""
    a, b = linearise(step, [0.0] * task.n, [0.0] * task.m)
    k = dlqr(a, b, np.diag(task.q), np.diag(task.p))
    low, high = np.array(task.low), np.array(task.high)

    def act(x):
        e = np.array(x, float)
        e[[i for i, is_angle in enumerate(task.angles) if is_angle]] = [
            wrap(v) for v, is_angle in zip(x, task.angles) if is_angle
        ]
        return list(np.clip(-k @ e, low, high))

    return act


def cartpole_step(x, u, ts):
    sim = cartpole.CartPole()
    sim.x = list(x)
    sim.step(list(u), ts)
    return sim.state()


def swing_up(task: Task, catch):
    """The energy pump of the docstring, `catch` within 0.5 rad of upright."""
    inertia = 4.0 / 3.0 * cartpole.M_P * cartpole.L**2  # the pole about its pivot

    def act(x):
        pos, th, v, w = x
        if abs(wrap(th)) < 0.5:
            return catch(x)
        # The pole's energy, zero upright at rest (negative below); a push along +x
        # lowers theta'' by cos(theta), so pushing against sign(w cos theta) adds energy.
        e = 0.5 * inertia * w * w + cartpole.M_P * cartpole.G * cartpole.L * (math.cos(th) - 1.0)
        f = 20.0 * e * math.copysign(1.0, w * math.cos(th)) - 4.0 * pos - 4.0 * v
        return [min(task.high[0], max(task.low[0], f))]

    return act


def model_trial(task: Task, act, x0):
    """One greedy trial of the cart-pole model: (states, return) with the task's reward
    and operating range."""
    sim = cartpole.CartPole()
    sim.place(x0)
    x, states, ret = sim.state(), [sim.state()], 0.0
    for _ in range(round(task.trial_seconds / task.ts)):
        u = act(x)
        sim.step(u, task.ts)
        nxt = sim.state()
        if task.operating_range and not all(lo <= v <= hi for v, (lo, hi) in zip(nxt, task.operating_range[0])):
            return states, ret + task.operating_range[1]
        ret += task.reward(x, u)
        x = nxt
        states.append(x)
    return states, ret


def gym_trial(task: Task, mapping, env, act, x0):
    """One greedy trial of a Gymnasium environment as the adapter serves it: (states,
    the environment's return)."""
    env.reset(seed=0)
    mapping.place(env, x0)
    x, states, ret = mapping.state(env), [mapping.state(env)], 0.0
    for _ in range(round(task.trial_seconds / task.ts)):
        _, r, terminated, truncated, _ = env.step(np.asarray(act(x), dtype=np.float64))
        ret += float(r)
        x = mapping.state(env)
        states.append(x)
        if terminated or truncated:
            break
    return states, ret


def controllers(e, task: Task):
    """[(label, a function of a start state giving (states, return))] for experiment e."""
    name = e["name"]
    if name.startswith("cartpole"):
        lqr = regulator(task, lambda x, u: cartpole_step(x, u, task.ts))
        rows = [("LQR of the true model", lambda x0: model_trial(task, lqr, x0))]
        if "swing" in name:
            pump = swing_up(task, lqr)
            rows = [("energy pump + LQR of the true model", lambda x0: model_trial(task, pump, x0))]
        return rows
    need("known_controllers.py", modules=["gymnasium"])
    import gymnasium

    mapping = load(str(ROOT / e["driver"][e["driver"].index("--mapping") + 1]))
    env = gymnasium.make(mapping.ENV_ID)

    def env_step(x, u):
        env.reset(seed=0)
        mapping.place(env, list(x))
        env.step(np.asarray(u, dtype=np.float64))
        return mapping.state(env)

    lqr = regulator(task, env_step)
    return [("LQR of the true model", lambda x0: gym_trial(task, mapping, env, lqr, x0))]


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--matrix", type=Path, default=Path(__file__).resolve().parent / "systems.toml")
    args = p.parse_args()
    with open(args.matrix, "rb") as f:
        experiments = [e for e in tomllib.load(f)["experiment"] if e.get("held_out")]
    print("| system | controller | return (mean over the start states) | success rule | met |")
    print("|---|---|---:|---|---|")
    for e in experiments:
        task = Task.read(str(ROOT / e["task"]))
        for label, trial in controllers(e, task):
            times = TaskTimes(task.ts, task.trial_seconds, [i for i, a in enumerate(task.angles) if a])
            trials = [trial(x0) for x0 in task.starts]
            mean, ok = meets(e["success"], times, trials)
            rule = ", ".join(f"{k} = {v}" for k, v in e["success"].items())
            print(f"| {e['system']} | {label} | {mean:.2f} | {rule} | {'yes' if ok else 'no'} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
