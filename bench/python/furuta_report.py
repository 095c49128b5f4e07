#!/usr/bin/env python3
"""Plots and tabulates the Furuta pendulum experiments (examples/furuta/experiment.sh,
benchmark.sh): the greedy learning curves of each learner (mean, min and max over its
runs) in one figure, the time response of one run's last greedy trial, and a verdict per
seed, read from each run's recording (rigkit.seeds, rigkit.recording).

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

import importlib.util
import statistics
import sys
from pathlib import Path

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: furuta_report.py needs the rig's Python package rigkit: pip install ./python")

from rigkit.script import fail, need  # noqa: E402

need("furuta_report.py", modules=["mcap", "matplotlib"])

from rigkit import plots, recording, returns, seeds  # noqa: E402
from rigkit.angle import wrap  # noqa: E402

import matplotlib.pyplot as plt  # noqa: E402 - after rigkit.plots has chosen Agg

UPRIGHT = 0.3  # "upright": |alpha| below this [rad]


def held_at_end(trial: seeds.Trial, task: seeds.TaskTimes) -> float:
    """How long [s] the greedy `trial` (states per step) ends within UPRIGHT of upright,
    0 if it ends before the task's full length."""
    tail = 0
    for x in reversed(trial):
        if abs(wrap(x[1])) >= UPRIGHT:
            break
        tail += 1
    full = len(trial) >= round(task.length / task.ts) + 1
    return (tail - 1) * task.ts if full and tail else 0.0


def measurements(run: Path) -> list[recording.Message]:
    """The run's `/plant/measurement` messages."""
    return recording.read(run / "run.mcap", [recording.MEASUREMENT]).of(recording.MEASUREMENT)


def verdict(run: Path):
    """(the last evaluation's trial, its greedy return, [held_at_end per start state],
    whether the seed is upright at the end, (how many, of the evaluations in the last
    quarter of the run, are upright at the end, how many there are))."""
    task = seeds.task_of(run)
    evals = returns.evaluations(returns.read(run / "returns.csv"))
    last, ret = evals[-1].trial, evals[-1].greedy
    greedy = seeds.greedy_states(measurements(run))
    hold = max(1.5, task.length / 3.0)

    def upright(e):
        return all(seeds.upright_at_end(t, task, UPRIGHT, hold) for t in greedy[e])

    late = [e.trial for e in evals if e.trial > 0.75 * last]
    held = [held_at_end(t, task) for t in greedy[last]]
    return last, ret, held, upright(last), (sum(upright(e) for e in late), len(late))


def greedy_curves(runs_csv: Path):
    """trial -> [greedy return of each run]."""
    by_trial = {}
    for r in returns.evaluations(returns.read(runs_csv)):
        by_trial.setdefault(r.trial, []).append(r.greedy)
    return dict(sorted(by_trial.items()))


def plot_response(out: Path, name: str, run: Path):
    """OUT/response-NAME.png/.svg: the last greedy trial (from the last start state) of `run`."""
    ts = seeds.task_of(run).ts
    msgs = recording.greedy_trials(measurements(run))
    trial = msgs[max(msgs)][-1]
    t = [m["step"] * ts for m in trial]
    x = list(zip(*(recording.vector(m, "y_") for m in trial)))
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


def report(name: str, d: Path) -> dict:
    """Prints the learner's per-seed table; returns its last greedy returns per seed."""
    walls = seeds.walls(d)
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


def main() -> int:
    if len(sys.argv) < 3 or "--help" in sys.argv or "-h" in sys.argv or any("=" not in a for a in sys.argv[2:]):
        print((__doc__ or "").strip(), file=sys.stderr)
        return 2
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plots.figure()
    for name, d in (a.split("=", 1) for a in sys.argv[2:]):
        d = Path(d)
        try:
            curves = greedy_curves(d / "runs.csv")
            trials = list(curves)
            plots.band(ax, trials, list(curves.values()), f"{name} (mean of {len(curves[trials[-1]])} runs)")
            finals = report(name, d)
            plot_response(out, name, d / f"seed-{max(finals, key=finals.get)}")
        except (OSError, recording.RecordingError, returns.ReturnsError) as e:
            fail("furuta_report.py", str(e))
    plots.finish(fig, ax, "trial", "greedy return", f"{out.name}: learning against the Python driver (lockstep)",
                 out / "curves", ("png", "svg"), legend="lower right")
    return 0


if __name__ == "__main__":
    sys.exit(main())
