#!/usr/bin/env python3
"""Plots and tabulates the Furuta pendulum experiments (examples/furuta/experiment.sh,
benchmark.sh): the greedy learning curves of each learner (mean, min and max over its
runs) in one figure, the time response of one run's last greedy trial, and a verdict per
seed, read from each run's recording with seeds_report.py's reader.

    python3 bench/python/furuta_report.py OUT LEARNER=DIR [LEARNER=DIR ...]
    python3 bench/python/furuta_report.py docs/results/furuta/bal mlac-llr=out/bal-mlac

Writes OUT/curves.png, OUT/curves.svg, OUT/response-<LEARNER>.png/.svg (the run with the
best last greedy return; with several start states, the greedy trial from the last) and
prints a Markdown table per learner: for each seed its last greedy return, how long each
last greedy trial (one per start state) ends within 0.3 rad of upright, the verdict, how
many of the evaluations in the run's last quarter meet it, and the wall time. A seed is *upright at the end* if every greedy trial of its last
evaluation runs its full length and its last max(1.5 s, a third of the trial) keep the
pendulum within 0.3 rad of upright. Needs matplotlib and mcap (the official reader).
"""

import csv
import statistics
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from seeds_report import evaluations, greedy_measurements, states, task_of, upright_at_end, wrap  # noqa: E402

UPRIGHT = 0.3  # "upright": |alpha| below this [rad]


def held_at_end(trial, ts: float, length: float) -> float:
    """How long [s] the greedy `trial` (states per step) ends within UPRIGHT of upright,
    0 if it ends before its full `length`."""
    tail = 0
    for x in reversed(trial):
        if abs(wrap(x[1])) >= UPRIGHT:
            break
        tail += 1
    full = len(trial) >= round(length / ts) + 1
    return (tail - 1) * ts if full and tail else 0.0


def verdict(run: Path):
    """(the last evaluation's trial, its greedy return, [held_at_end per start state],
    whether the seed is upright at the end, (how many, of the evaluations in the last
    quarter of the run, are upright at the end, how many there are))."""
    ts, length, angles = task_of(run)
    evals = evaluations(run)
    last, _, ret = evals[-1]
    greedy = {
        e: [[states(m) for m in t] for t in trials]
        for e, trials in greedy_measurements(run / "run.mcap").items()
    }
    hold = max(1.5, length / 3.0)

    def upright(e):
        return all(upright_at_end(t, ts, length, angles, UPRIGHT, hold) for t in greedy[e])

    late = [e for e, _, _ in evals if e > 0.75 * last]
    held = [held_at_end(t, ts, length) for t in greedy[last]]
    return last, ret, held, upright(last), (sum(upright(e) for e in late), len(late))


def greedy_curves(runs_csv: Path):
    """trial -> [greedy return of each run]."""
    by_trial = {}
    with open(runs_csv) as f:
        for row in csv.DictReader(f):
            if row["greedy_return"]:
                by_trial.setdefault(int(row["trial"]), []).append(float(row["greedy_return"]))
    return dict(sorted(by_trial.items()))


def plot_response(out: Path, name: str, run: Path):
    """OUT/response-NAME.png/.svg: the last greedy trial (from the last start state) of `run`."""
    ts, _, _ = task_of(run)
    msgs = greedy_measurements(run / "run.mcap")
    trial = msgs[max(msgs)][-1]
    t = [m["step"] * ts for m in trial]
    x = list(zip(*(states(m) for m in trial)))
    fig, ax = plt.subplots(3, 1, figsize=(7, 6), sharex=True)
    ax[0].plot(t, x[0], label="arm θ")
    ax[0].plot(t, x[1], label="pendulum α (0 upright)")
    ax[0].set_ylabel("rad")
    ax[1].plot(t, x[2], label="θ̇")
    ax[1].plot(t, x[3], label="α̇")
    ax[1].set_ylabel("rad/s")
    for a in ax[:2]:
        a.legend(loc="best")
    ax[2].step(t, [m["u_applied_0"] for m in trial], where="post")
    ax[2].set_ylabel("V (applied)")
    ax[2].set_xlabel("time [s]")
    ax[0].set_title(f"{name}: last greedy trial of {run.name}")
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(out / f"response-{name}.{ext}")
    plt.close(fig)


def report(name: str, d: Path) -> list:
    """Prints the learner's per-seed table; returns its last greedy returns per seed."""
    with open(d / "wall.csv") as f:
        walls = {int(r["seed"]): float(r["wall_s"]) for r in csv.DictReader(f)}
    print(f"\n{name} ({d}):\n")
    print(
        "| seed | trials | greedy return at the last trial | within 0.3 rad of upright at the end, "
        "per start state | upright at the end | evaluations upright at the end, last quarter | wall time |"
    )
    print("|---:|---:|---:|---|---|---:|---:|")
    won, finals = 0, {}
    for seed in sorted(walls):
        last, ret, held, ok, (late_ok, late) = verdict(d / f"seed-{seed}")
        won += ok
        finals[seed] = ret
        ends = ", ".join(f"{h:.2f} s" for h in held)
        print(
            f"| {seed} | {last} | {ret:.0f} | {ends} | {'yes' if ok else 'no'} "
            f"| {late_ok} of {late} | {walls[seed]:.1f} s |"
        )
    print(
        f"\n{name}: {won} of {len(walls)} seeds upright at the end; last greedy return mean "
        f"{statistics.mean(finals.values()):.0f} [{min(finals.values()):.0f}, {max(finals.values()):.0f}], "
        f"wall time median {statistics.median(walls.values()):.1f} s"
    )
    return finals


def main():
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7, 4))
    for name, d in (a.split("=", 1) for a in sys.argv[2:]):
        d = Path(d)
        curves = greedy_curves(d / "runs.csv")
        trials = list(curves)
        ax.plot(trials, [statistics.mean(v) for v in curves.values()], label=f"{name} (mean of {len(curves[trials[-1]])} runs)")
        ax.fill_between(trials, [min(v) for v in curves.values()], [max(v) for v in curves.values()], alpha=0.2)
        finals = report(name, d)
        plot_response(out, name, d / f"seed-{max(finals, key=finals.get)}")
    ax.set_xlabel("trial")
    ax.set_ylabel("greedy return")
    ax.set_title(f"{out.name}: learning against the Python driver (lockstep)")
    ax.legend(loc="lower right")
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(out / f"curves.{ext}")


if __name__ == "__main__":
    main()
