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
import importlib.util
import os
import re
import shutil
import statistics
import sys
import tomllib
from pathlib import Path

if importlib.util.find_spec("rigkit") is None:
    sys.exit("error: systems.py needs the rig's Python package rigkit: pip install ./python")

from rigkit.script import fail, interrupt_on_sigterm, need, rig_binary, rig_option  # noqa: E402

need("systems.py", modules=["iceoryx2", "mcap", "matplotlib"])

from rigkit import plots, processes  # noqa: E402
from rigkit.recording import RecordingError  # noqa: E402
from rigkit.returns import ReturnsError  # noqa: E402
from rigkit.seeds import Seed, seed_results  # noqa: E402

import interaction  # noqa: E402  (beside this script)

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
WHO = "systems.py"

SEEDS_SH = ROOT / "examples" / "python_driver" / "seeds.sh"

def slug(label: str) -> str:
    """A folder name for a learner's label."""
    return re.sub(r"[^a-z0-9]+", "-", label.lower()).strip("-")


def read_matrix(path: Path):
    """The experiments of a matrix file, checked: one-line errors name the file and key."""
    try:
        with open(path, "rb") as f:
            experiments = tomllib.load(f).get("experiment", [])
    except (OSError, tomllib.TOMLDecodeError) as err:
        fail(WHO, f"{path}: {err}")
    keys, optional = {"name", "system", "task", "driver", "trials", "success", "learners"}, {"held_out"}
    for k, e in enumerate(experiments):
        where = f"{path}: experiment {k + 1} ({e.get('name', '?')})"
        missing, unknown = keys - e.keys(), e.keys() - keys - optional
        if missing or unknown:
            fail(WHO, f"{where}: missing keys {sorted(missing)}, unknown keys {sorted(unknown)}; "
                 f"an experiment has {sorted(keys)} and optionally {sorted(optional)}")
        if type(e.get("held_out", False)) is not bool:
            fail(WHO, f"{where}: held_out must be true or false, not {e['held_out']!r}")
        s = e["success"]
        if sorted(s) not in (["return_at_least"], ["hold", "upright"]):
            fail(WHO, f"{where}: success must be {{ upright = A, hold = S }} or "
                 f"{{ return_at_least = R }}, not {s}")
        for learner in e["learners"]:
            if not {"flags", "label"} <= learner.keys() <= {"flags", "label", "trials"}:
                fail(WHO, f"{where}: a learner is {{ label = \"…\", flags = [\"…\"] }} and "
                     f"optionally trials = N, not {learner}")
            t = learner.get("trials", e["trials"])
            if type(t) is not int or t < 1:
                fail(WHO, f"{where}: trials must be a whole number >= 1, not {t!r}")
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
    # In a process group of its own: stopped (Ctrl-C, SIGTERM, an error here), the script,
    # its driver and its run stop with it.
    status = processes.call(
        [str(SEEDS_SH), str(folder), str(seeds - done), str(trials), e["task"], *e["driver"],
         "--", *learner["flags"]],
        cwd=ROOT, env={**env, "FIRST": str(done + 1)},
    )
    if status != 0:
        fail(WHO, f"{e['name']} × {learner['label']}: a run failed (its error above); "
             f"the seeds finished are kept in {folder}: call again to go on", 1)


def judged(e, folder: Path) -> list[Seed]:
    """The per-seed results of a learner's folder, by the experiment's success rule."""
    s = e["success"]
    try:
        return seed_results(folder, s.get("return_at_least"), s.get("upright"), s.get("hold", 1.5))
    except (OSError, RecordingError, ReturnsError) as err:
        fail(WHO, str(err))


def plot(e, curves, out: Path):
    """The experiment's learning curves: per learner the median greedy return over seeds
    at each evaluation against its median simulated seconds, the band min..max."""
    fig, ax = plots.figure()
    for label, results in curves:
        n = min(len(r.curve) for r in results)
        t = [statistics.median(r.curve[k][0] for r in results) for k in range(n)]
        ys = [[r.curve[k][1] for r in results] for k in range(n)]
        plots.band(ax, t, ys, f"{label} ({len(results)} seeds)", statistics.median, marker="o", markersize=3)
    plots.finish(fig, ax, "simulated seconds of learning", "greedy return", e["system"], out / e["name"], dpi=110)


def sac(e, args, rows, run: bool):
    """SB3's SAC on a Gymnasium experiment: its seeds run (if `run` and --sb3; sb3_sac.py,
    finished seeds kept) and its row added to `rows` where OUT/<experiment>/sb3-sac holds
    any."""
    folder = args.out / e["name"] / "sb3-sac"
    gym = e["driver"][:1] == ["examples/gymnasium/adapter.py"]
    if run and args.sb3 and gym:
        status = processes.call([args.python, str(HERE / "sb3_sac.py"), str(folder), "--experiment", e["name"],
                                 "--matrix", str(args.matrix), "--seeds", str(args.seeds)], cwd=ROOT)
        if status != 0:
            fail(WHO, f"--sb3: SAC on {e['name']} failed (its error above); "
                 f"its finished seeds are kept in {folder}: call again to go on", 1)
    if (folder / "curves.csv").exists():
        rows.append(interaction.sac_row(e, interaction.read_sac(folder / "curves.csv"), args.seeds))


def main():
    interrupt_on_sigterm()
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
    rig_option(p, ROOT / "target" / "release" / "rig")
    p.add_argument("--python", default=sys.executable, help="the interpreter for the drivers")
    args = p.parse_args()
    args.rig = rig_binary(WHO, args.rig)
    if args.seeds < 1:
        p.error("--seeds must be at least 1")
    experiments = read_matrix(args.matrix)
    names = {e["name"] for e in experiments}
    labels = {l["label"] for e in experiments for l in e["learners"]}
    only = [n for n in args.only.split(",") if n]
    if unknown := [n for n in only if n not in names]:
        p.error(f"--only: unknown experiments {unknown}; the matrix has {sorted(names)}")
    chosen = [n for n in args.learners.split(",") if n]
    if unknown := [n for n in chosen if n not in labels]:
        p.error(f"--learners: unknown learners {unknown}; the matrix has {sorted(labels)}")
    selected = [] if args.report_only else [e for e in experiments if not only or e["name"] in only]
    if any("adapter.py" in " ".join(e["driver"]) for e in selected):
        need(WHO, modules=["gymnasium"])
    if args.sb3 and selected:
        need(WHO, modules=["gymnasium", "stable_baselines3"])
    args.out.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "PYTHON": args.python, "RIG": str(args.rig.resolve())}
    rows = []
    # Runs what --only and --learners choose; reports every experiment × learner with a
    # seed in OUT.
    for e in experiments:
        if args.trials is not None:
            e = {**e, "trials": args.trials,
                 "learners": [{**l, "trials": args.trials} for l in e["learners"]]}
        run = any(e["name"] == s["name"] for s in selected)
        curves = []
        for learner in e["learners"]:
            folder = args.out / e["name"] / slug(learner["label"])
            if run and (not chosen or learner["label"] in chosen):
                learn(e, learner, folder, args.seeds, env)
            if seeds_done(folder):
                results = judged(e, folder)[: args.seeds]
                rows.append(interaction.rig_row(e, learner["label"], results))
                curves.append((learner["label"], results))
        if curves:
            plot(e, curves, args.out)
        sac(e, args, rows, run=run)
    text = interaction.report(rows, args.out)
    interaction.plot(rows, args.out)
    (args.out / "table.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        fail(WHO, "stopped (Ctrl-C or SIGTERM), its runs with it; the seeds finished are kept: call again to go on", 130)
