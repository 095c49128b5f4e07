#!/usr/bin/env python3
"""The thesis's learners through the rig against Stable-Baselines3's SAC, on the same
Gymnasium Pendulum-v1: environment steps and wall time until the greedy return first
reaches a common level, per seed, and the learning curves in one plot.

    python3 bench/python/sb3_pendulum.py OUT [--seeds 3] [--steps 40000] [--level -300] [--rig R]

Both sides are evaluated alike: the greedy (deterministic) policy, one 200-step episode
from each of the task's four start states (examples/gymnasium/pendulum-v1.toml), the
mean, every 2000 environment steps of learning (the rig's `eval_every` of 10 trials of
200 steps). The rig's learners (MLAC/LLR, SAC/LLR, the presets by rules) learn through
examples/gymnasium/adapter.py, one `rig run --plant external` per seed; SB3's SAC
(default hyperparameters, CPU) learns on the environment with its own random starts, as
users run it. Steps count learning steps only; wall time is the whole run's, evaluations
included, on the machine this runs on.

Writes OUT/curves.csv (learner, seed, steps, wall_s, greedy_return), OUT/curves.png/.svg,
OUT/summary.md. Each learner's seed is appended to curves.csv as it finishes, and a second
call keeps those already there (a call interrupted part way goes on where it stopped);
a folder holding runs of another length is refused. Needs stable-baselines3 (with
torch), gymnasium, iceoryx2 0.10.0, matplotlib, and the release build of the rig.
"""

import argparse
import csv
import importlib.util
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: sb3_pendulum.py needs the rig's Python package rigkit: pip install ./python")

from rigkit.script import fail, interrupt_on_sigterm, need, rig_binary, rig_option  # noqa: E402

need("sb3_pendulum.py", modules=["gymnasium", "iceoryx2", "matplotlib"])

import gymnasium  # noqa: E402

from rigkit import plots, processes, returns  # noqa: E402
from rigkit.adapter import load  # noqa: E402
from rigkit.task import Task  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
pendulum_v1 = load(str(ROOT / "examples" / "gymnasium" / "pendulum_v1.py"))

TASK = ROOT / "examples" / "gymnasium" / "pendulum-v1.toml"
EVAL_EVERY = 2000  # environment steps
EPISODE = 200


def greedy_return(env, act, starts) -> float:
    """The mean return of one deterministic episode from each start state."""
    total = 0.0
    for x0 in starts:
        env.reset(seed=0)
        pendulum_v1.place(env, x0)
        obs = env.unwrapped._get_obs()
        for _ in range(EPISODE):
            obs, r, _, _, _ = env.step(act(obs))
            total += float(r)
    return total / len(starts)


def sb3_sac(seed: int, steps: int, starts):
    """SB3 SAC on Pendulum-v1: [(steps, wall_s, greedy_return)] every EVAL_EVERY steps."""
    from stable_baselines3 import SAC
    from stable_baselines3.common.callbacks import BaseCallback

    curve = []
    t0 = time.monotonic()
    eval_env = gymnasium.make("Pendulum-v1")

    class Evaluate(BaseCallback):
        def _on_step(self) -> bool:
            if self.num_timesteps % EVAL_EVERY == 0:
                act = lambda obs: self.model.predict(obs, deterministic=True)[0]  # noqa: E731
                curve.append((self.num_timesteps, time.monotonic() - t0, greedy_return(eval_env, act, starts)))
            return True

    model = SAC("MlpPolicy", gymnasium.make("Pendulum-v1"), seed=seed, device="cpu", verbose=0)
    model.learn(total_timesteps=steps, callback=Evaluate())
    return curve


def rig_learner(rig: Path, algo: str, seed: int, steps: int, out: Path, python: str):
    """A learner of the rig through the adapter: [(steps, wall_s, greedy_return)]."""
    driver_id = f"bench-gym-{algo}-{seed}"
    adapter = processes.start(
        [python, str(ROOT / "examples/gymnasium/adapter.py"), "--mapping",
         str(ROOT / "examples/gymnasium/pendulum_v1.py"), "--driver-id", driver_id, "--seed", str(seed)],
        stderr=subprocess.DEVNULL,
    )
    run_dir = out / f"rig-{algo}-{seed}"
    # A run interrupted part way left its folder; it is run again from its start.
    shutil.rmtree(run_dir, ignore_errors=True)
    try:
        t0 = time.monotonic()
        status = processes.call(
            [str(rig), "run", "--plant", "external", "--driver", driver_id, "--task", str(TASK),
             "--algo", algo, "--approx", "llr", "--seed", str(seed), "--trials", str(steps // EPISODE),
             "--eval-every", str(EVAL_EVERY // EPISODE), "--quiet", "--out", str(run_dir)],
        )
        wall = time.monotonic() - t0
        if status != 0:
            fail("sb3_pendulum.py", f"rig run {algo} seed {seed} failed (its error above); "
                 f"the finished runs are kept in {out}: call again to go on", 1)
    finally:
        processes.stop(adapter)
    # The run's wall time, spread over its trials (the rig stamps no per-trial time).
    return [(r.trial * EPISODE, wall * r.trial / (steps // EPISODE), r.greedy)
            for r in returns.evaluations(returns.read(run_dir / "returns.csv")) if r.greedy is not None]


def first_reaching(curve, level):
    """(steps, wall_s) of the first evaluation at or above `level`, or None."""
    return next(((s, w) for s, w, g in curve if g >= level), None)


HEADER = ["learner", "seed", "steps", "wall_s", "greedy_return"]


def kept_curves(path: Path, steps: int):
    """The finished runs of an earlier call, {(learner, seed): curve}; exits in one line
    if they learned for another number of steps."""
    curves = {}
    if not path.exists():
        return curves
    with open(path) as f:
        for r in csv.DictReader(f):
            curve = curves.setdefault((r["learner"], int(r["seed"])), [])
            curve.append((int(r["steps"]), float(r["wall_s"]), float(r["greedy_return"])))
    if other := sorted({c[-1][0] for c in curves.values()} - {steps}):
        fail("sb3_pendulum.py", f"{path}: holds runs of {other[0]} steps, not --steps {steps}: "
             "use another folder or the same --steps")
    return curves


def append(path: Path, learner: str, seed: int, curve):
    """One finished run's evaluations, appended to curves.csv (its header if new)."""
    new = not path.exists()
    with open(path, "a", newline="") as f:
        w = csv.writer(f)
        if new:
            w.writerow(HEADER)
        for s, t, g in curve:
            w.writerow([learner, seed, s, f"{t:.3f}", g])


def main():
    interrupt_on_sigterm()
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out", help="the output folder (kept: a second call resumes)")
    p.add_argument("--seeds", type=int, default=3, help="seeds 1..N per learner [default: 3]")
    p.add_argument("--steps", type=int, default=40000,
                   help=f"learning steps per run, a multiple of {EVAL_EVERY} [default: 40000]")
    p.add_argument("--level", type=float, default=-300.0,
                   help="the common greedy-return level [default: -300]")
    rig_option(p, ROOT / "target" / "release" / "rig")
    p.add_argument("--python", default=sys.executable, help="the interpreter for the adapter")
    args = p.parse_args()
    args.rig = rig_binary("sb3_pendulum.py", args.rig)
    if args.seeds < 1:
        p.error("--seeds must be at least 1")
    if args.steps < EVAL_EVERY or args.steps % EVAL_EVERY:
        p.error(f"--steps must be a positive multiple of {EVAL_EVERY} (one evaluation each)")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    starts = Task.read(str(TASK)).starts
    table = out / "curves.csv"
    kept = kept_curves(table, args.steps)
    curves = {}
    for seed in range(1, args.seeds + 1):
        runs = [(f"rig {a.upper()}/LLR", lambda a=a: rig_learner(args.rig, a, seed, args.steps, out, args.python))
                for a in ("mlac", "sac")]
        runs.append(("SB3 SAC", lambda: sb3_sac(seed, args.steps, starts)))
        for learner, learn in runs:
            if (learner, seed) in kept:
                curves[(learner, seed)] = kept[(learner, seed)]
                print(f"{learner} seed {seed}: kept from {table}", flush=True)
                continue
            curves[(learner, seed)] = learn()
            append(table, learner, seed, curves[(learner, seed)])
            print(f"{learner} seed {seed}: {curves[(learner, seed)][-1]}", flush=True)
    summarize(curves, args, out)
    plot(curves, out)


def summarize(curves, args, out: Path):
    lines = [
        f"Level {args.level:g} (greedy return, mean over the four start states); {args.seeds} seeds, "
        f"{args.steps} learning steps each.",
        "",
        "| learner | seeds reaching the level | steps to reach it (median) | wall time to reach it (median) | final greedy return (median) | wall time per run (median) |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for learner in dict.fromkeys(k[0] for k in curves):
        runs = [c for (name, _), c in curves.items() if name == learner]
        reached = [first_reaching(c, args.level) for c in runs]
        hit = [r for r in reached if r is not None]
        med = lambda v, spec, unit="": format(statistics.median(v), spec) + unit if v else "—"  # noqa: E731
        lines.append(
            f"| {learner} | {len(hit)} of {len(runs)} | {med([s for s, _ in hit], '.0f')} "
            f"| {med([w for _, w in hit], '.1f', ' s')} | {med([c[-1][2] for c in runs], '.1f')} "
            f"| {med([c[-1][1] for c in runs], '.1f', ' s')} |"
        )
    text = "\n".join(lines) + "\n"
    (out / "summary.md").write_text(text)
    print(text)


def plot(curves, out: Path):
    fig, ax = plots.figure()
    for learner in dict.fromkeys(k[0] for k in curves):
        runs = [c for (name, _), c in curves.items() if name == learner]
        steps = [s for s, _, _ in runs[0]]
        values = [[c[i][2] for c in runs if i < len(c)] for i in range(len(steps))]
        plots.band(ax, steps, values, f"{learner} (mean of {len(runs)})")
    plots.finish(fig, ax, "environment steps of learning", "greedy return (4 start states)",
                 "Pendulum-v1: the rig's learners and Stable-Baselines3 SAC", out / "curves", ("png", "svg"),
                 legend="lower right")


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:
        fail("sb3_pendulum.py", "stopped (Ctrl-C or SIGTERM), its runs with it; the finished runs are kept: "
             "call again to go on", 130)
