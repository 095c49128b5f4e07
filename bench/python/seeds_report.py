#!/usr/bin/env python3
"""The per-seed table of an experiment written by examples/python_driver/seeds.sh: for
each seed, the greedy return at the last evaluation, whether it succeeds, the simulated
seconds of learning until the first evaluation that succeeds, the mean return of its
last 100 learning trials (with exploration, from the learning trials' starts) and the
run's wall time, and the agent's step per sample (from receiving the estimate to
publishing the action, the recording's `/timing/agent/action`: the learner's compute,
and what the machine's other work added to it).

    python3 bench/python/seeds_report.py OUT --return-at-least 90
    python3 bench/python/seeds_report.py OUT --upright 0.3 --hold 1.5

An evaluation succeeds
  --return-at-least R   if its greedy return (the mean over the task's start states) is
                        at least R;
  --upright A --hold S  if every greedy trial of it (one per start state, read from the
                        run's recording, run.mcap) runs its full length and its last S
                        seconds keep every angle state within A rad of 0 (upright).
Prints a Markdown table and a line "K of N seeds succeed at the last evaluation".
Needs mcap (the official reader).
"""

import argparse
import csv
import json
import math
import statistics
import sys
from pathlib import Path

FLAG_GREEDY = 4


def wrap(a: float) -> float:
    """Angle to [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def task_of(run_dir: Path):
    """(sampling time, trial seconds, indices of the angle states) from config.toml."""
    import tomllib

    with open(run_dir / "config.toml", "rb") as f:
        task = tomllib.load(f)["task"]
    angles = [i for i, s in enumerate(task["state"]) if s.get("angle")]
    return task["sampling_time"], task["trial_seconds"], angles


def read_recording(mcap_path: Path, greedy: bool = True, agent: bool = True):
    """From a run's recording: evaluation (the learning trial it follows) -> [[measurement
    message per step] per greedy trial] (if `greedy`), and the agent's step of every
    sample in ns (if `agent`: from receiving the estimate to publishing the action,
    `/timing/agent/action`)."""
    from mcap.reader import make_reader

    evals, steps = {}, []
    topics = (["/timing/agent/action"] if agent else []) + (["/plant/measurement"] if greedy else [])
    with open(mcap_path, "rb") as f:
        for _, channel, msg in make_reader(f).iter_messages(topics=topics):
            m = json.loads(msg.data)
            if channel.topic == "/timing/agent/action":
                steps.append(m["t_publish_ns"] - m["t_received_ns"])
            elif m["flags"] & FLAG_GREEDY:
                trials = evals.setdefault(m["trial"], [])
                if m["step"] == 0 or not trials:
                    trials.append([])
                trials[-1].append(m)
    return evals, steps


def greedy_measurements(mcap_path: Path):
    """The greedy trials' measurement messages of `read_recording`, alone."""
    return read_recording(mcap_path, agent=False)[0]


def percentile(sorted_values, q: float):
    """The nearest-rank `q` percentile (0 < q <= 100) of a sorted list."""
    return sorted_values[max(0, math.ceil(q / 100 * len(sorted_values)) - 1)]


def states(measurement) -> list:
    """The measured state `[y_0, y_1, ...]` of one measurement message."""
    return [measurement[f"y_{i}"] for i in range(sum(k.startswith("y_") for k in measurement))]


def greedy_trials(measurements):
    """evaluation -> [[state per step] per greedy trial], of `read_recording`'s first part."""
    return {e: [[states(m) for m in trial] for trial in trials] for e, trials in measurements.items()}


def upright_at_end(trial, ts, length, angles, tol, hold) -> bool:
    """Whether `trial` runs `length` seconds and its last `hold` seconds keep every angle
    within `tol` of 0."""
    samples = round(length / ts) + 1
    tail = round(hold / ts) + 1
    return len(trial) >= samples and all(
        abs(wrap(x[i])) < tol for x in trial[-tail:] for i in angles
    )


def meets(success, ts, length, angles, trials):
    """(the mean return, whether a success rule holds) of one greedy evaluation, its
    trials `[(states, return)]` one per start state: `success` is an experiment's rule,
    {"return_at_least": R} or {"upright": A, "hold": S} (bench/python/systems.toml), for a
    task of sampling time `ts`, trials of `length` seconds and angle states `angles`."""
    mean = sum(r for _, r in trials) / len(trials)
    if "return_at_least" in success:
        return mean, mean >= success["return_at_least"]
    return mean, all(
        upright_at_end(s, ts, length, angles, success["upright"], success["hold"]) for s, _ in trials
    )


def upright_times(trial, ts, angles, tol):
    """(the first time [s] every angle is within `tol` of 0, or None; the share of the
    trial's samples where they are)."""
    up = [all(abs(wrap(x[i])) < tol for i in angles) for x in trial]
    first = next((k * ts for k, u in enumerate(up) if u), None)
    return first, sum(up) / len(up)


def evaluations(run_dir: Path):
    """[(trial, simulated seconds of learning so far, greedy return)] of a run."""
    with open(run_dir / "returns.csv") as f:
        return [
            (int(r["trial"]), float(r["sim_time_s"]), float(r["greedy_return"]))
            for r in csv.DictReader(f)
            if r["greedy_return"]
        ]


def last_learning_mean(run_dir: Path, count: int = 100) -> float:
    """The mean return of the run's last `count` learning trials."""
    with open(run_dir / "returns.csv") as f:
        returns = [float(r["return"]) for r in csv.DictReader(f)]
    return statistics.mean(returns[-count:])


def to_success(evals):
    """(first, holds) of a run's evaluations `[(interaction so far, succeeds)]` in order:
    the interaction until the first evaluation that succeeds, and until the first one
    from which every later evaluation succeeds too (it meets the criterion and holds it
    to the end of the run); None for one that never comes."""
    first = next((t for t, good in evals if good), None)
    holds = None
    for t, good in reversed(evals):
        if not good:
            break
        holds = t
    return first, holds


def median_to_success(values):
    """The median over seeds of `to_success`'s figures, a seed that never got there
    counting as later than any that did: None if the median seed never did."""
    if not values:
        return None
    ranked = sorted(values, key=lambda v: (v is None, v or 0))
    n = len(ranked)
    middle = ranked[(n - 1) // 2 : n // 2 + 1]
    return None if None in middle else sum(middle) / len(middle)


def seed_results(out: Path, return_at_least=None, upright=None, hold=1.5):
    """Per seed of experiment folder `out` (seeds.sh's OUT), in seed order: a dict of
    `seed`, `trials`, `final` (the greedy return at the last evaluation), `succeeds`
    (there), `first_success_s` (simulated seconds of learning until the first evaluation
    that succeeds, or None), `holds_s` (until the first evaluation from which every later
    one succeeds, or None), `first_success_samples` and `holds_samples` (the same in
    samples of learning), `learning_mean` (the last 100 learning trials), `wall_s`,
    `agent_ms` (the agent's step per sample, median and 99th percentile in ms, or None
    if the recording has none), `curve` ([(simulated s, greedy return)] of every
    evaluation) and `notes` (with `upright`: when each last greedy trial is upright).
    Success as `main` says: give one of `return_at_least` and `upright`."""
    with open(out / "wall.csv") as f:
        walls = {int(r["seed"]): float(r["wall_s"]) for r in csv.DictReader(f)}
    results = []
    for seed in sorted(walls):
        run = out / f"seed-{seed}"
        evals = evaluations(run)
        if not evals:
            sys.exit(f"{run}: no greedy evaluation in returns.csv (learn more trials than eval_every)")
        notes = []
        ts = task_of(run)[0]
        measurements, steps = read_recording(run / "run.mcap", greedy=upright is not None)
        steps.sort()
        if upright is None:
            good = [e[2] >= return_at_least for e in evals]
        else:
            _, length, angles = task_of(run)
            greedy = greedy_trials(measurements)
            good = [
                all(upright_at_end(t, ts, length, angles, upright, hold) for t in greedy[e[0]])
                for e in evals
            ]
            for k, trial in enumerate(greedy[evals[-1][0]]):
                at, share = upright_times(trial, ts, angles, upright)
                notes.append(
                    f"seed {seed}, last greedy trial from start state {k}: "
                    + ("never upright" if at is None else f"first upright at {at:.2f} s, upright {100 * share:.0f} % of it")
                )
        first, holds = to_success([(e[1], g) for e, g in zip(evals, good)])
        samples = lambda t: None if t is None else round(t / ts)  # noqa: E731
        results.append({
            "seed": seed,
            "ts": ts,
            "trials": evals[-1][0],
            "final": evals[-1][2],
            "succeeds": good[-1],
            "first_success_s": first,
            "holds_s": holds,
            "first_success_samples": samples(first),
            "holds_samples": samples(holds),
            "learning_mean": last_learning_mean(run),
            "wall_s": walls[seed],
            "agent_ms": (percentile(steps, 50) / 1e6, percentile(steps, 99) / 1e6) if steps else None,
            "curve": [(e[1], e[2]) for e in evals],
            "notes": notes,
        })
    return results


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out", type=Path, help="the experiment's folder (seeds.sh's OUT)")
    p.add_argument("--return-at-least", type=float, metavar="R", help="success: greedy return >= R")
    p.add_argument("--upright", type=float, metavar="A", help="success: angles within A rad of upright")
    p.add_argument("--hold", type=float, default=1.5, metavar="S", help="for --upright: the last S seconds [default: 1.5]")
    args = p.parse_args()
    if (args.return_at_least is None) == (args.upright is None):
        p.error("give one of --return-at-least and --upright")
    results = seed_results(args.out, args.return_at_least, args.upright, args.hold)
    print(
        "| seed | trials | greedy return at the last evaluation | succeeds | simulated s to first success "
        "| simulated s to success held to the end | mean return, last 100 learning trials | wall time "
        "| agent's step, median / 99 % |"
    )
    print("|---:|---:|---:|---|---:|---:|---:|---:|---:|")
    for r in results:
        first, holds = r["first_success_s"], r["holds_s"]
        step = "—" if r["agent_ms"] is None else "{:.3f} / {:.3f} ms".format(*r["agent_ms"])
        print(
            f"| {r['seed']} | {r['trials']} | {r['final']:.2f} | {'yes' if r['succeeds'] else 'no'} "
            f"| {'never' if first is None else f'{first:.0f}'} | {'never' if holds is None else f'{holds:.0f}'} "
            f"| {r['learning_mean']:.2f} | {r['wall_s']:.1f} s "
            f"| {step} |"
        )
    notes = [n for r in results for n in r["notes"]]
    if notes:
        print(f"\nUpright: every angle within {args.upright} rad of 0.")
        print("\n".join(f"- {n}" for n in notes))
    finals = [r["final"] for r in results]
    won = sum(r["succeeds"] for r in results)
    print(f"\n{won} of {len(results)} seeds succeed at the last evaluation; "
          f"greedy return there: median {statistics.median(finals):.2f}, min {min(finals):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
