#!/usr/bin/env python3
"""The per-seed table of an experiment written by examples/python_driver/seeds.sh: for
each seed, the greedy return at the last evaluation, whether it succeeds, the simulated
seconds of learning until the first evaluation that succeeds and until the first one
from which every later one succeeds too (success held to the end), the mean return of its
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
Prints a Markdown table, every evaluation's verdict per seed (and how many of each seed's
last ten succeed), and a line "K of N seeds succeed at the last evaluation".
Needs mcap (the official reader); the judging is rigkit.seeds.
"""

import argparse
import importlib.util
import statistics
import sys
from pathlib import Path

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: seeds_report.py needs the rig's Python package rigkit: pip install ./python")

from rigkit.script import fail, need  # noqa: E402

need("seeds_report.py", modules=["mcap"])

from rigkit.recording import RecordingError  # noqa: E402
from rigkit.returns import ReturnsError  # noqa: E402
from rigkit.seeds import last_successes, seed_results, verdict_line  # noqa: E402


def seconds(s: float | None) -> str:
    """Simulated seconds to success: 'never', to 0.01 s below 10 s, else whole."""
    return "never" if s is None else f"{s:.{2 if s < 10 else 0}f}"


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out", type=Path, help="the experiment's folder (seeds.sh's OUT)")
    p.add_argument("--return-at-least", type=float, metavar="R", help="success: greedy return >= R")
    p.add_argument("--upright", type=float, metavar="A", help="success: angles within A rad of upright")
    p.add_argument("--hold", type=float, default=1.5, metavar="S", help="for --upright: the last S seconds [default: 1.5]")
    args = p.parse_args()
    if (args.return_at_least is None) == (args.upright is None):
        p.error("give one of --return-at-least and --upright")
    try:
        results = seed_results(args.out, args.return_at_least, args.upright, args.hold)
    except (OSError, RecordingError, ReturnsError) as e:
        fail("seeds_report.py", str(e))
    print(
        "| seed | trials | greedy return at the last evaluation | succeeds | simulated s to first success "
        "| simulated s to success held to the end | mean return, last 100 learning trials | wall time "
        "| agent's step, median / 99 % |"
    )
    print("|---:|---:|---:|---|---:|---:|---:|---:|---:|")
    for r in results:
        first, holds = r.first_success_s, r.holds_s
        step = "—" if r.agent_ms is None else "{:.3f} / {:.3f} ms".format(*r.agent_ms)
        print(
            f"| {r.seed} | {r.trials} | {r.final:.2f} | {'yes' if r.succeeds else 'no'} "
            f"| {seconds(first)} | {seconds(holds)} "
            f"| {r.learning_mean:.2f} | {r.wall_s:.1f} s | {step} |"
        )
    print("\nEvery evaluation in order (1 succeeds, . misses), and of each seed's last ten:")
    ok = total = 0
    for r in results:
        won, of = last_successes(r.verdicts)
        ok, total = ok + won, total + of
        print(f"- seed {r.seed}: {verdict_line(r.verdicts)} — {won} of {of}")
    print(f"- the last ten of every seed: {ok} of {total}")
    notes = [n for r in results for n in r.notes]
    if notes:
        print(f"\nUpright: every angle within {args.upright} rad of 0.")
        print("\n".join(f"- {n}" for n in notes))
    finals = [r.final for r in results]
    won = sum(r.succeeds for r in results)
    print(f"\n{won} of {len(results)} seeds succeed at the last evaluation; "
          f"greedy return there: median {statistics.median(finals):.2f}, min {min(finals):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
