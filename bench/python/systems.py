#!/usr/bin/env python3
"""The systems a lab brings, learned: every experiment of a matrix file (default
bench/python/systems.toml) × its learners × SEEDS seeds, in lockstep against the
experiment's Python driver; one table of success rates, simulated seconds of interaction
to success, wall times and the agent's compute per sample, the learning curves, and
beside them the published figures of the field and (with --sb3) Stable-Baselines3's SAC
run here on Gymnasium's Pendulum-v1 with the same seeds (bench/python/sb3_pendulum.py).

    python3 bench/python/systems.py OUT                      # everything, 5 seeds
    python3 bench/python/systems.py OUT --only furuta-balance --seeds 2
    python3 bench/python/systems.py OUT --sb3                # and the Pendulum-v1 comparison

Resumable: a learner's seeds already in OUT/<experiment>/<learner>/wall.csv are kept
and the next seed starts where they stop (an interrupted seed is run again from its
start; --sb3's finished runs are kept the same way). Writes OUT/table.md (the whole
report), OUT/table.csv and OUT/<experiment>.png (median greedy return over the seeds
against simulated seconds of learning, the band from the worst to the best seed). Needs
iceoryx2 0.10.0, mcap and matplotlib (and what each driver imports: gymnasium for the
adapter); --sb3 needs stable-baselines3.
"""

import argparse
import csv
import os
import re
import shutil
import statistics
import subprocess
import sys
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from seeds_report import seed_results  # noqa: E402

SEEDS_SH = ROOT / "examples" / "python_driver" / "seeds.sh"

# The field's published figures for the same kinds of task, quoted beside the table.
PUBLISHED = [
    ("PILCO (Deisenroth & Rasmussen, ICML 2011)", "cart-pole swing-up and balance",
     "17.5 s of interaction to success"),
    ("rl-baselines3-zoo, tuned SAC (its benchmark table)", "Gymnasium Pendulum-v1",
     "return −157 ± 89 after 20 000 steps"),
]


def slug(label: str) -> str:
    """A folder name for a learner's label."""
    return re.sub(r"[^a-z0-9]+", "-", label.lower()).strip("-")


def read_matrix(path: Path):
    """The experiments of a matrix file, checked: one-line errors name the file and key."""
    with open(path, "rb") as f:
        experiments = tomllib.load(f).get("experiment", [])
    keys, optional = {"name", "system", "task", "driver", "trials", "success", "learners"}, {"held_out"}
    for k, e in enumerate(experiments):
        where = f"{path}: experiment {k + 1} ({e.get('name', '?')})"
        missing, unknown = keys - e.keys(), e.keys() - keys - optional
        if missing or unknown:
            sys.exit(f"{where}: missing keys {sorted(missing)}, unknown keys {sorted(unknown)}; "
                     f"an experiment has {sorted(keys)} and optionally {sorted(optional)}")
        if type(e.get("held_out", False)) is not bool:
            sys.exit(f"{where}: held_out must be true or false, not {e['held_out']!r}")
        s = e["success"]
        if sorted(s) not in (["return_at_least"], ["hold", "upright"]):
            sys.exit(f"{where}: success must be {{ upright = A, hold = S }} or "
                     f"{{ return_at_least = R }}, not {s}")
        for learner in e["learners"]:
            if not {"flags", "label"} <= learner.keys() <= {"flags", "label", "trials"}:
                sys.exit(f"{where}: a learner is {{ label = \"…\", flags = [\"…\"] }} and "
                         f"optionally trials = N, not {learner}")
            t = learner.get("trials", e["trials"])
            if type(t) is not int or t < 1:
                sys.exit(f"{where}: trials must be a whole number >= 1, not {t!r}")
    return experiments


def seeds_done(folder: Path) -> int:
    """How many seeds of a learner's folder are complete (rows of its wall.csv)."""
    wall = folder / "wall.csv"
    if not wall.exists():
        return 0
    with open(wall) as f:
        return sum(1 for _ in csv.DictReader(f))


def learn(e, learner, folder: Path, seeds: int, env):
    """Runs the seeds of one experiment × learner not yet in `folder` (seeds.sh)."""
    done = seeds_done(folder)
    if done >= seeds:
        return
    # A seed interrupted part way leaves its folder; it is run again from its start.
    shutil.rmtree(folder / f"seed-{done + 1}", ignore_errors=True)
    print(f"{e['name']} × {learner['label']}: seeds {done + 1}..{seeds}", flush=True)
    trials = learner.get("trials", e["trials"])
    run = subprocess.run(
        [str(SEEDS_SH), str(folder), str(seeds - done), str(trials), e["task"], *e["driver"],
         "--", *learner["flags"]],
        cwd=ROOT, env={**env, "FIRST": str(done + 1)},
    )
    if run.returncode != 0:
        sys.exit(f"{e['name']} × {learner['label']}: a run failed (its error above); "
                 f"the seeds finished are kept in {folder}: call again to go on")


def judged(e, folder: Path):
    """The per-seed results of a learner's folder, by the experiment's success rule."""
    s = e["success"]
    return seed_results(folder, s.get("return_at_least"), s.get("upright"), s.get("hold", 1.5))


def median_or_none(values):
    return statistics.median(values) if values else None


def summary_row(e, learner, results):
    """One row of the table: success rate, seconds to success, final return, wall time,
    the agent's step."""
    firsts = [r["first_success_s"] for r in results if r["first_success_s"] is not None]
    return {
        "experiment": e["name"], "system": e["system"], "learner": learner["label"],
        "seeds": len(results), "succeed": sum(r["succeeds"] for r in results),
        "sim_s_to_success": median_or_none(firsts), "ever_succeeded": len(firsts),
        "final_return": median_or_none([r["final"] for r in results]),
        "wall_s": median_or_none([r["wall_s"] for r in results]),
        "agent_ms_median": median_or_none([r["agent_ms"][0] for r in results if r["agent_ms"]]),
        "agent_ms_p99": median_or_none([r["agent_ms"][1] for r in results if r["agent_ms"]]),
    }


def plot(e, curves, out: Path):
    """The experiment's learning curves: per learner the median greedy return over seeds
    at each evaluation against its median simulated seconds, the band min..max."""
    fig, ax = plt.subplots(figsize=(7, 4))
    for label, results in curves:
        n = min(len(r["curve"]) for r in results)
        t = [statistics.median(r["curve"][k][0] for r in results) for k in range(n)]
        ys = [[r["curve"][k][1] for r in results] for k in range(n)]
        ax.plot(t, [statistics.median(y) for y in ys], "o-", markersize=3, label=f"{label} ({len(results)} seeds)")
        ax.fill_between(t, [min(y) for y in ys], [max(y) for y in ys], alpha=0.2)
    ax.set_xlabel("simulated seconds of learning")
    ax.set_ylabel("greedy return")
    ax.set_title(e["system"])
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / f"{e['name']}.png", dpi=110)
    plt.close(fig)


def fmt(v, spec):
    return "—" if v is None else format(v, spec)


def report(rows, out: Path, sb3: Path | None) -> str:
    """The Markdown report: the table, the published figures, the SB3 comparison."""
    lines = [
        "| system | learner | seeds succeeding | simulated s to first success (median of those that did) "
        "| greedy return at the end (median) | wall time per run (median) "
        "| agent's step per sample, median / 99 % (medians of the seeds) |",
        "|---|---|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['system']} | {r['learner']} | {r['succeed']} of {r['seeds']} "
            f"| {fmt(r['sim_s_to_success'], '.0f')} ({r['ever_succeeded']} ever) "
            f"| {fmt(r['final_return'], '.2f')} | {fmt(r['wall_s'], '.1f')} s "
            f"| {fmt(r['agent_ms_median'], '.3f')} / {fmt(r['agent_ms_p99'], '.3f')} ms |"
        )
    lines += ["", "Published figures for the same kinds of task:", "",
              "| source | task | figure |", "|---|---|---|"]
    lines += [f"| {a} | {b} | {c} |" for a, b, c in PUBLISHED]
    if sb3 is not None:
        lines += ["", "Gymnasium Pendulum-v1, the rig's learners and Stable-Baselines3's SAC "
                  "(bench/python/sb3_pendulum.py, the same seeds):", "",
                  (sb3 / "summary.md").read_text().strip()]
    with open(out / "table.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]) if rows else ["experiment"])
        w.writeheader()
        w.writerows(rows)
    return "\n".join(lines) + "\n"


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out", type=Path, help="the output folder (kept: a second call resumes)")
    p.add_argument("--matrix", type=Path, default=Path(__file__).resolve().parent / "systems.toml",
                   help="the experiments (default bench/python/systems.toml)")
    p.add_argument("--seeds", type=int, default=5, help="seeds per experiment × learner (1..N) [default: 5]")
    p.add_argument("--only", default="", help="comma-separated experiment names to run (default all)")
    p.add_argument("--trials", type=int, help="trials per run instead of each experiment's and learner's own (a short look)")
    p.add_argument("--sb3", action="store_true", help="also run bench/python/sb3_pendulum.py, 20 000 steps")
    p.add_argument("--rig", type=Path, default=ROOT / "target" / "release" / "rig",
                   help="the rig binary [default: the release build]")
    p.add_argument("--python", default=sys.executable, help="the interpreter for the drivers")
    args = p.parse_args()
    if args.seeds < 1:
        p.error("--seeds must be at least 1")
    if not args.rig.exists():
        p.error(f"{args.rig}: no such rig binary (cargo build --release -p rig)")
    experiments = read_matrix(args.matrix)
    names = {e["name"] for e in experiments}
    only = [n for n in args.only.split(",") if n]
    if unknown := [n for n in only if n not in names]:
        p.error(f"--only: unknown experiments {unknown}; the matrix has {sorted(names)}")
    args.out.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "PYTHON": args.python, "RIG": str(args.rig.resolve())}
    rows = []
    for e in experiments:
        if only and e["name"] not in only:
            continue
        if args.trials is not None:
            e = {**e, "trials": args.trials,
                 "learners": [{**l, "trials": args.trials} for l in e["learners"]]}
        curves = []
        for learner in e["learners"]:
            folder = args.out / e["name"] / slug(learner["label"])
            learn(e, learner, folder, args.seeds, env)
            results = judged(e, folder)[: args.seeds]
            rows.append(summary_row(e, learner, results))
            curves.append((learner["label"], results))
        plot(e, curves, args.out)
    sb3 = None
    if args.sb3:
        sb3 = args.out / "pendulum-v1"
        run = subprocess.run([args.python, str(ROOT / "bench" / "python" / "sb3_pendulum.py"), str(sb3),
                              "--seeds", str(args.seeds), "--steps", "20000", "--rig", str(args.rig.resolve()),
                              "--python", args.python], cwd=ROOT)
        if run.returncode != 0:
            sys.exit(f"--sb3: the Pendulum-v1 comparison failed (its error above); "
                     f"its finished runs are kept in {sb3}: call again to go on")
    text = report(rows, args.out, sb3)
    (args.out / "table.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
