#!/usr/bin/env python3
"""The systems a lab brings, learned: every experiment of a matrix file (default
bench/python/systems.toml) × its learners × SEEDS seeds, in lockstep against the
experiment's Python driver; one table per kind of system — those the default learner's
rules were chosen on, and the held-out ones (`held_out = true`), out of sample — of
success rates, interaction until the greedy policy first meets the experiment's success
rule and until it holds it to the end of the run (simulated seconds and samples, the
median over the seeds), the final greedy return, wall times and the agent's step per
sample (median and 99th percentile); the learning curves; one plot of the interaction to
success per system (interaction.py); and beside them the field's published figures and,
on the Gymnasium experiments, Stable-Baselines3's SAC with rl-baselines3-zoo's tuned
hyperparameters, run here with the same seeds and judged by the same rule (sb3_sac.py).

    python3 bench/python/systems.py OUT                      # everything, 5 seeds
    python3 bench/python/systems.py OUT --only furuta-balance --seeds 2
    python3 bench/python/systems.py OUT --sb3                # and SAC on the Gymnasium ones

Resumable: a learner's seeds already in OUT/<experiment>/<learner>/wall.csv are kept
and the next seed starts where they stop (an interrupted seed is run again from its
start); SAC's finished seeds in OUT/<experiment>/sb3-sac/curves.csv are kept the same way,
and reported whenever they are there. Writes OUT/table.md (the whole report),
OUT/table.csv, OUT/interaction.png and OUT/<experiment>.png (median greedy return over
the seeds against simulated seconds of learning, the band from the worst to the best
seed). Needs iceoryx2 0.10.0, mcap and matplotlib (and what each driver imports:
gymnasium for the adapter); --sb3 needs stable-baselines3.
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

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(HERE))
import interaction  # noqa: E402
from seeds_report import seed_results  # noqa: E402

SEEDS_SH = ROOT / "examples" / "python_driver" / "seeds.sh"

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


def sac(e, args, rows, run: bool):
    """SB3's SAC on a Gymnasium experiment: its seeds run (if `run` and --sb3; sb3_sac.py,
    finished seeds kept) and its row added to `rows` where OUT/<experiment>/sb3-sac holds
    any."""
    folder = args.out / e["name"] / "sb3-sac"
    gym = e["driver"][:1] == ["examples/gymnasium/adapter.py"]
    if run and args.sb3 and gym:
        run = subprocess.run([args.python, str(HERE / "sb3_sac.py"), str(folder), "--experiment", e["name"],
                              "--matrix", str(args.matrix), "--seeds", str(args.seeds)], cwd=ROOT)
        if run.returncode != 0:
            sys.exit(f"--sb3: SAC on {e['name']} failed (its error above); "
                     f"its finished seeds are kept in {folder}: call again to go on")
    if (folder / "curves.csv").exists():
        rows.append(interaction.sac_row(e, interaction.read_sac(folder / "curves.csv"), args.seeds))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out", type=Path, help="the output folder (kept: a second call resumes)")
    p.add_argument("--matrix", type=Path, default=Path(__file__).resolve().parent / "systems.toml",
                   help="the experiments (default bench/python/systems.toml)")
    p.add_argument("--seeds", type=int, default=5, help="seeds per experiment × learner (1..N) [default: 5]")
    p.add_argument("--only", default="", help="comma-separated experiment names to run (default all)")
    p.add_argument("--learners", default="",
                   help="comma-separated learner labels to run, e.g. default (default all)")
    p.add_argument("--report-only", action="store_true",
                   help="run nothing: the report of what OUT holds (while other calls run seeds into it)")
    p.add_argument("--trials", type=int, help="trials per run instead of each experiment's and learner's own (a short look)")
    p.add_argument("--sb3", action="store_true",
                   help="also run Stable-Baselines3's SAC on the Gymnasium experiments (bench/python/sb3_sac.py)")
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
    labels = {l["label"] for e in experiments for l in e["learners"]}
    only = [n for n in args.only.split(",") if n]
    if unknown := [n for n in only if n not in names]:
        p.error(f"--only: unknown experiments {unknown}; the matrix has {sorted(names)}")
    chosen = [n for n in args.learners.split(",") if n]
    if unknown := [n for n in chosen if n not in labels]:
        p.error(f"--learners: unknown learners {unknown}; the matrix has {sorted(labels)}")
    args.out.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "PYTHON": args.python, "RIG": str(args.rig.resolve())}
    rows = []
    # Runs what --only and --learners choose; reports every experiment × learner with a
    # seed in OUT.
    for e in experiments:
        selected = not args.report_only and (not only or e["name"] in only)
        if args.trials is not None:
            e = {**e, "trials": args.trials,
                 "learners": [{**l, "trials": args.trials} for l in e["learners"]]}
        curves = []
        for learner in e["learners"]:
            folder = args.out / e["name"] / slug(learner["label"])
            if selected and (not chosen or learner["label"] in chosen):
                learn(e, learner, folder, args.seeds, env)
            if seeds_done(folder):
                results = judged(e, folder)[: args.seeds]
                rows.append(interaction.rig_row(e, learner["label"], results))
                curves.append((learner["label"], results))
        if curves:
            plot(e, curves, args.out)
        sac(e, args, rows, run=selected)
    text = interaction.report(rows, args.out)
    interaction.plot(rows, args.out)
    (args.out / "table.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
