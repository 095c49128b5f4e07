#!/usr/bin/env python3
"""Stable-Baselines3's SAC, with rl-baselines3-zoo's tuned hyperparameters, on a Gymnasium
experiment of the systems benchmark (bench/python/systems.toml): environment steps,
simulated seconds and wall time of learning until its greedy policy first meets the
experiment's success rule, and until it meets it for the rest of the run, per seed.

    python3 bench/python/sb3_sac.py OUT --experiment pendulum-v1 [--seeds 5] [--steps N]
    python3 bench/python/sb3_sac.py OUT --experiment inverted-pendulum-v5 --matrix FILE

The greedy policy is evaluated as the rig's greedy evaluations are: one deterministic
episode from each start state of the experiment's task file (the environment reset with
a seed, then placed at the start state by the experiment's mapping module, as
examples/gymnasium/adapter.py places it), each the task's trial long unless the
environment ends it first; the environment's own reward; success by the experiment's
rule (the mean return at least R, or every episode's last S seconds within A rad of
upright). SAC learns on the environment as users run it: gymnasium.make(ENV_ID), its own
random starts. Steps count learning steps only (evaluations are not interaction).

The hyperparameters (HYPERPARAMETERS) are rl-baselines3-zoo's hyperparams/sac.yml; its
n_timesteps is the default budget, capped by BUDGET_CAP where it is longer than this
machine can give. PyTorch runs on one CPU thread.

Writes OUT/curves.csv (seed, steps, sim_s, wall_s, greedy_return, success: one row per
evaluation), each seed's rows as it finishes; a second call keeps the seeds there and
runs the rest (a folder holding runs of another length is refused). Needs
stable-baselines3 (with torch), gymnasium and what the environment needs.
"""

import argparse
import csv
import importlib.util
import sys
import time
from pathlib import Path

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: sb3_sac.py needs the rig's Python package rigkit: pip install ./python")

from rigkit.script import fail, need  # noqa: E402

WHO = "sb3_sac.py"
need(WHO, modules=["numpy", "gymnasium"])

import numpy as np  # noqa: E402
from rigkit.adapter import load  # noqa: E402
from rigkit.seeds import TaskTimes, meets  # noqa: E402
from rigkit.task import Task  # noqa: E402

from interaction import Evaluation, read_sac  # noqa: E402  (beside this script)

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]

# rl-baselines3-zoo, hyperparams/sac.yml (github.com/DLR-RM/rl-baselines3-zoo, commit
# 22e3ff2450fd92033f7f032915e1f64894a09584; the file as of eec15dc22e1e): the entries of
# the environments benchmarked here, as SAC's keyword arguments, and n_timesteps. The zoo
# has no SAC entry for InvertedPendulum-v5 (nor v4): the nearest is its tuned entry for
# the same cart-and-pole in PyBullet, InvertedPendulumSwingupBulletEnv-v0 (the file's
# pybullet-defaults, n_timesteps 3e5).
HYPERPARAMETERS = {
    "Pendulum-v1": dict(n_timesteps=20_000, learning_rate=1e-3),
    "MountainCarContinuous-v0": dict(
        n_timesteps=50_000, learning_rate=3e-4, buffer_size=50_000, batch_size=512, ent_coef=0.1,
        train_freq=32, gradient_steps=32, gamma=0.9999, tau=0.01, learning_starts=0, use_sde=True,
        policy_kwargs=dict(log_std_init=-3.67, net_arch=[64, 64]),
    ),
    "InvertedPendulum-v5": dict(
        zoo_entry="InvertedPendulumSwingupBulletEnv-v0",
        n_timesteps=300_000, learning_rate=7.3e-4, buffer_size=300_000, batch_size=256, ent_coef="auto",
        gamma=0.98, tau=0.02, train_freq=8, gradient_steps=8, learning_starts=10_000, use_sde=True,
        policy_kwargs=dict(log_std_init=-3, net_arch=[400, 300]),
    ),
}
# Learning steps at most, where the zoo's budget is longer: InvertedPendulum-v5's 3e5 steps
# of a 400x300 network take hours per seed on this 2-core machine (about 40 ms per
# gradient step there); 30 000 steps are the zoo's 10 000 random ones and 20 000 of
# learning, for every seed.
BUDGET_CAP = {"InvertedPendulum-v5": 30_000}
# Learning steps between evaluations, per environment: the rig's ten trials of 200 steps
# on Pendulum-v1; 1000 steps (one full episode) on the others.
EVAL_EVERY = {"Pendulum-v1": 2000, "MountainCarContinuous-v0": 1000, "InvertedPendulum-v5": 1000}

HEADER = ["seed", "steps", "sim_s", "wall_s", "greedy_return", "success"]


def gymnasium_experiment(e):
    """(mapping module, task) of a matrix experiment served by the Gymnasium adapter; exits
    in one line for another."""
    driver = e["driver"]
    if not driver or not driver[0].endswith("gymnasium/adapter.py") or "--mapping" not in driver:
        fail(WHO, f"experiment {e['name']}: not a Gymnasium environment (its driver is not "
             "examples/gymnasium/adapter.py --mapping M)")
    mapping = load(str(ROOT / driver[driver.index("--mapping") + 1]))
    if mapping.ENV_ID not in HYPERPARAMETERS:
        fail(WHO, f"experiment {e['name']}: no rl-baselines3-zoo hyperparameters here for "
             f"{mapping.ENV_ID}; known: {sorted(HYPERPARAMETERS)}")
    return mapping, Task.read(str(ROOT / e["task"]))


def observation(env):
    """The environment's observation of its state now (after the mapping placed it)."""
    unwrapped = env.unwrapped
    if hasattr(unwrapped, "_get_obs"):
        return unwrapped._get_obs()
    return np.array(unwrapped.state, dtype=np.float32)  # classic control's MountainCar


def greedy_episodes(env, mapping, task: Task, act):
    """[(states, return)]: one deterministic episode from each of the task's start states,
    the task's trial long unless the environment ends it."""
    episodes = []
    for k, x0 in enumerate(task.starts):
        env.reset(seed=k)
        mapping.place(env, x0)
        obs, states, total = observation(env), [mapping.state(env)], 0.0
        for _ in range(round(task.trial_seconds / task.ts)):
            obs, r, terminated, truncated, _ = env.step(act(obs))
            total += float(r)
            states.append(mapping.state(env))
            if terminated or truncated:
                break
        episodes.append((states, total))
    return episodes


def budget(env_id: str) -> int:
    """The learning steps per run: the zoo's n_timesteps, capped."""
    return min(HYPERPARAMETERS[env_id]["n_timesteps"], BUDGET_CAP.get(env_id, 10**12))


def learn(e, mapping, task: Task, seed: int, steps: int):
    """SB3 SAC on the experiment's environment: its Evaluation every EVAL_EVERY steps."""
    import gymnasium
    import torch
    from stable_baselines3 import SAC
    from stable_baselines3.common.callbacks import BaseCallback

    torch.set_num_threads(1)
    env_id = mapping.ENV_ID
    every = EVAL_EVERY[env_id]
    times = TaskTimes(task.ts, task.trial_seconds, [i for i, a in enumerate(task.angles) if a])
    kwargs = {k: v for k, v in HYPERPARAMETERS[env_id].items() if k not in ("n_timesteps", "zoo_entry")}
    eval_env = gymnasium.make(env_id)
    curve: list[Evaluation] = []
    t0 = time.monotonic()

    class Evaluate(BaseCallback):
        def _on_step(self) -> bool:
            if self.num_timesteps % every == 0:
                act = lambda obs: self.model.predict(obs, deterministic=True)[0]  # noqa: E731
                episodes = greedy_episodes(eval_env, mapping, task, act)
                ret, ok = meets(e["success"], times, episodes)
                n = self.num_timesteps
                curve.append(Evaluation(n, n * task.ts, time.monotonic() - t0, ret, ok))
                print(f"  seed {seed}, {n} steps: greedy {ret:.2f}, meets the rule: {'yes' if ok else 'no'}",
                      flush=True)
            return True

    model = SAC("MlpPolicy", gymnasium.make(env_id), seed=seed, device="cpu", verbose=0, **kwargs)
    model.learn(total_timesteps=steps, callback=Evaluate())
    return curve


def kept_runs(path: Path, steps: int):
    """The seeds an earlier call finished, {seed: curve}; exits in one line if they learned
    for another number of steps."""
    if not path.exists():
        return {}
    runs = read_sac(path)
    if other := sorted({c[-1].steps for c in runs.values()} - {steps}):
        fail(WHO, f"{path}: holds runs of {other[0]} steps, not {steps}: use another folder or the same --steps")
    return runs


def append(path: Path, seed: int, curve: list[Evaluation]):
    """One finished seed's evaluations, appended to curves.csv (its header if new)."""
    new = not path.exists()
    with open(path, "a", newline="") as f:
        w = csv.writer(f)
        if new:
            w.writerow(HEADER)
        for c in curve:
            w.writerow([seed, c.steps, f"{c.sim_s:g}", f"{c.wall_s:.3f}", c.greedy_return, int(c.success)])


def run(out: Path, e, seeds: int, steps: int | None = None):
    """Seeds 1..`seeds` of experiment `e` in `out` (kept ones kept): {seed: curve}."""
    mapping, task = gymnasium_experiment(e)
    steps = steps or budget(mapping.ENV_ID)
    every = EVAL_EVERY[mapping.ENV_ID]
    if steps < every or steps % every:
        fail(WHO, f"--steps must be a positive multiple of {every} (one evaluation each)")
    out.mkdir(parents=True, exist_ok=True)
    table = out / "curves.csv"
    runs = kept_runs(table, steps)
    for seed in range(1, seeds + 1):
        if seed in runs:
            print(f"SB3 SAC {e['name']} seed {seed}: kept from {table}", flush=True)
            continue
        print(f"SB3 SAC {e['name']} seed {seed}: {steps} steps", flush=True)
        runs[seed] = learn(e, mapping, task, seed, steps)
        append(table, seed, runs[seed])
        print(f"SB3 SAC {e['name']} seed {seed}: last evaluation {runs[seed][-1]}", flush=True)
    return {s: runs[s] for s in range(1, seeds + 1)}


def main():
    from systems import read_matrix

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out", type=Path, help="the output folder (kept: a second call resumes)")
    p.add_argument("--experiment", required=True, help="the matrix's experiment (a Gymnasium one)")
    p.add_argument("--matrix", type=Path, default=HERE / "systems.toml",
                   help="the experiments (default bench/python/systems.toml)")
    p.add_argument("--seeds", type=int, default=5, help="seeds 1..N [default: 5]")
    p.add_argument("--steps", type=int,
                   help="learning steps per run [default: the zoo's n_timesteps, capped: BUDGET_CAP]")
    args = p.parse_args()
    if args.seeds < 1:
        p.error("--seeds must be at least 1")
    experiments = {e["name"]: e for e in read_matrix(args.matrix)}
    if args.experiment not in experiments:
        p.error(f"--experiment: unknown {args.experiment!r}; the matrix has {sorted(experiments)}")
    run(args.out, experiments[args.experiment], args.seeds, args.steps)
    return 0


if __name__ == "__main__":
    sys.exit(main())
