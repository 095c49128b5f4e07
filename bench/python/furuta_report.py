#!/usr/bin/env python3
"""Plots the Furuta pendulum experiment (examples/furuta/experiment.sh): the greedy
learning curves of each learner (mean, min and max over its runs) in one figure, and the
time response of the last greedy trial of one run, from its recording.

    python3 bench/python/furuta_report.py OUT LEARNER=DIR [LEARNER=DIR ...]
    python3 bench/python/furuta_report.py docs/results/furuta mlac=out/furuta-mlac vgbp=out/furuta-vgbp

Writes OUT/curves.png, OUT/curves.svg, OUT/response-<LEARNER>.png/.svg (the run with the
best last greedy return; with several start states, the greedy trial from the last) and
prints a Markdown table (final greedy returns, best, wall time) and, per run, how its last
greedy trial ends: a run *swings up and balances* if that trial runs its full length and
its last max(1.5 s, a third of the trial) are all within 0.3 rad of upright. Needs
matplotlib and mcap (the official reader).
"""

import csv
import json
import math
import statistics
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from mcap.reader import make_reader  # noqa: E402

FLAG_GREEDY = 4
TS = 0.02  # the task's sampling time [s]
UPRIGHT = 0.3  # "upright": |alpha| below this [rad]


def wrap(a: float) -> float:
    """Angle to [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def trial_seconds(run_dir: Path) -> float:
    """The task's trial length, from the run's resolved configuration."""
    for line in open(run_dir / "config.toml"):
        if line.startswith("trial_seconds"):
            return float(line.split("=", 1)[1])
    raise ValueError(f"{run_dir}/config.toml: no trial_seconds")


def balance_summary(run_dir: Path):
    """(time within UPRIGHT of upright at the end of the last greedy trial [s], that
    trial's first time within UPRIGHT or None, the share of it within UPRIGHT, whether it
    swings up and balances)."""
    t, x, _ = last_greedy_trial(run_dir / "run.mcap")
    length = trial_seconds(run_dir)
    up = [abs(wrap(a)) < UPRIGHT for a in x[1]]
    tail = 0
    for u in reversed(up):
        if not u:
            break
        tail += 1
    full = t[-1] >= length - 1e-9
    held = (tail - 1) * TS if full and tail else 0.0
    first = next((ti for ti, u in zip(t, up) if u), None)
    need = max(1.5, length / 3.0)
    return held, first, sum(up[1:]) / (len(up) - 1), full and held >= need - 1e-9


def greedy_curves(runs_csv: Path):
    """trial -> [greedy return of each run]."""
    by_trial = {}
    with open(runs_csv) as f:
        for row in csv.DictReader(f):
            if row["greedy_return"]:
                by_trial.setdefault(int(row["trial"]), []).append(float(row["greedy_return"]))
    return dict(sorted(by_trial.items()))


def last_greedy_trial(mcap_path: Path):
    """(t, x, u) of the last greedy trial's measurements in a recording."""
    trials = {}
    with open(mcap_path, "rb") as f:
        for _, _, msg in make_reader(f).iter_messages(topics=["/plant/measurement"]):
            m = json.loads(msg.data)
            if m["flags"] & FLAG_GREEDY:
                if m["step"] == 0:
                    trials[m["trial"]] = []
                trials.setdefault(m["trial"], []).append(m)
    msgs = trials[max(trials)]
    t = [m["step"] * TS for m in msgs]
    x = [[m[f"y_{i}"] for m in msgs] for i in range(4)]
    u = [m["u_applied_0"] for m in msgs]
    return t, x, u


def main():
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    learners = [a.split("=", 1) for a in sys.argv[2:]]
    fig, ax = plt.subplots(figsize=(7, 4))
    print("| learner | runs | greedy return at the last trial: mean [min, max] | best mean | wall time per run |")
    print("|---|---:|---|---:|---|")
    for name, d in learners:
        d = Path(d)
        curves = greedy_curves(d / "runs.csv")
        trials = list(curves)
        mean = [statistics.mean(v) for v in curves.values()]
        ax.plot(trials, mean, label=f"{name} (mean of {len(next(iter(curves.values())))} runs)")
        ax.fill_between(trials, [min(v) for v in curves.values()], [max(v) for v in curves.values()], alpha=0.2)
        with open(d / "wall.csv") as f:
            walls = [float(r["wall_s"]) for r in csv.DictReader(f)]
        last = curves[trials[-1]]
        print(
            f"| {name} | {len(last)} | {statistics.mean(last):.0f} [{min(last):.0f}, {max(last):.0f}] "
            f"| {max(mean):.0f} (trial {trials[mean.index(max(mean))]}) "
            f"| {statistics.median(walls):.1f} s median ({min(walls):.1f}–{max(walls):.1f}) |"
        )
        best_run = max(range(len(last)), key=lambda k: last[k])
        seed = d / f"seed-{best_run + 1}"
        t, x, u = last_greedy_trial(seed / "run.mcap")
        rfig, rax = plt.subplots(3, 1, figsize=(7, 6), sharex=True)
        rax[0].plot(t, x[0], label="arm θ")
        rax[0].plot(t, x[1], label="pendulum α (0 upright)")
        rax[0].set_ylabel("rad")
        rax[0].legend(loc="best")
        rax[1].plot(t, x[2], label="θ̇")
        rax[1].plot(t, x[3], label="α̇")
        rax[1].set_ylabel("rad/s")
        rax[1].legend(loc="best")
        rax[2].step(t, u, where="post")
        rax[2].set_ylabel("V (applied)")
        rax[2].set_xlabel("time [s]")
        rax[0].set_title(f"{name}: last greedy trial of {seed.name}")
        rfig.tight_layout()
        for ext in ("png", "svg"):
            rfig.savefig(out / f"response-{name}.{ext}")
    for name, d in learners:
        runs = sorted(Path(d).glob("seed-*"), key=lambda p: int(p.name[5:]))
        ok = 0
        for run in runs:
            held, first, share, balanced = balance_summary(run)
            ok += balanced
            print(
                f"{name} {run.name}: "
                + (f"never within {UPRIGHT} rad of upright" if first is None else
                   f"first within {UPRIGHT} rad of upright at {first:.2f} s, {100 * share:.0f} % of the trial, "
                   f"the last {held:.2f} s{': swings up and balances' if balanced else ''}")
            )
        print(f"{name}: {ok} of {len(runs)} runs swing up and balance")
    ax.set_xlabel("trial")
    ax.set_ylabel("greedy return")
    ax.set_title(f"{out.name}: learning against the Python driver (lockstep)")
    ax.legend(loc="lower right")
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(out / f"curves.{ext}")


if __name__ == "__main__":
    main()
