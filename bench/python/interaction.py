"""The systems benchmark's headline: interaction until success, per system and learner —
the rig's learners (rigkit.seeds.seed_results) beside Stable-Baselines3's SAC
(sb3_sac.py's curves.csv) and the field's published figures — as one table (Markdown and
CSV rows) and one plot. Used by systems.py.

A seed's interaction to success is `rigkit.seeds.to_success`'s: the simulated seconds
(and samples) of learning until its greedy policy first meets the experiment's success
rule, and until it meets it at every later evaluation of the run; a row's figure is the
median over its seeds, a seed that never got there counting as later than any that did
(`rigkit.seeds.median_to_success`: none if the median seed never did).
"""

import csv
import statistics
from dataclasses import dataclass
from pathlib import Path

from rigkit.seeds import Seed, median_to_success, to_success

SAC_LABEL = "SB3 SAC (rl-zoo)"

# The field's published figures: (source, task, figure, interaction in samples or None,
# the experiments of the matrix it stands beside).
PUBLISHED = [
    ("PILCO (Deisenroth & Rasmussen, ICML 2011)",
     "cart-pole swing-up and balance (its own cart-pole: 0.5 kg cart and pole, 0.6 m, Ts 0.1 s)",
     "17.5 s of interaction to success (175 samples)", 175, ["cartpole-swing-balance"]),
    ("rl-baselines3-zoo, tuned SAC: hyperparams/sac.yml's budget, benchmark.md's result",
     "Gymnasium Pendulum-v1", "n_timesteps 20 000; return −157 ± 89 after them (random starts)",
     20_000, ["pendulum-v1"]),
    ("rl-baselines3-zoo, tuned SAC: hyperparams/sac.yml's budget, benchmark.md's result",
     "Gymnasium MountainCarContinuous-v0", "n_timesteps 50 000; return 94.7 ± 1.1 after them",
     50_000, ["mountain-car"]),
    ("rl-baselines3-zoo, tuned SAC: hyperparams/sac.yml's budget",
     "InvertedPendulumSwingupBulletEnv-v0 (no SAC entry for InvertedPendulum-v4/v5: the nearest)",
     "n_timesteps 300 000", 300_000, ["inverted-pendulum-v5"]),
]


def median(values):
    return statistics.median(values) if values else None


def rig_row(e, label, results: list[Seed]):
    """A row of the rig's learner `label` from its seeds' `seed_results`."""
    return {
        "experiment": e["name"], "system": e["system"], "held_out": bool(e.get("held_out")),
        "learner": label, "seeds": len(results), "succeed": sum(r.succeeds for r in results),
        "ever_succeeded": sum(r.first_success_s is not None for r in results),
        "first_success_s": median_to_success([r.first_success_s for r in results]),
        "first_success_samples": median_to_success([r.first_success_samples for r in results]),
        "holds_s": median_to_success([r.holds_s for r in results]),
        "holds_samples": median_to_success([r.holds_samples for r in results]),
        "run_samples": median([round(r.curve[-1][0] / r.ts) for r in results]),
        "final_return": median([r.final for r in results]),
        "wall_s": median([r.wall_s for r in results]),
        "agent_ms_median": median([r.agent_ms[0] for r in results if r.agent_ms]),
        "agent_ms_p99": median([r.agent_ms[1] for r in results if r.agent_ms]),
    }


@dataclass(frozen=True)
class Evaluation:
    """One greedy evaluation of SAC's learning: after `steps` learning steps (`sim_s`
    simulated seconds, `wall_s` of wall time), its greedy return and whether it met the
    experiment's success rule."""

    steps: int
    sim_s: float
    wall_s: float
    greedy_return: float
    success: bool


def read_sac(path: Path) -> dict[int, list[Evaluation]]:
    """sb3_sac.py's curves.csv: {seed: its evaluations in order}."""
    runs: dict[int, list[Evaluation]] = {}
    with open(path) as f:
        for r in csv.DictReader(f):
            runs.setdefault(int(r["seed"]), []).append(Evaluation(
                int(r["steps"]), float(r["sim_s"]), float(r["wall_s"]), float(r["greedy_return"]),
                r["success"] == "1"))
    return runs


def sac_row(e, runs: dict[int, list[Evaluation]], seeds: int):
    """The row of SB3's SAC from sb3_sac.py's runs of seeds 1..`seeds` (those there)."""
    curves = [runs[s] for s in range(1, seeds + 1) if s in runs]
    steps = [to_success([(c.steps, c.success) for c in curve]) for curve in curves]
    secs = [to_success([(c.sim_s, c.success) for c in curve]) for curve in curves]
    return {
        "experiment": e["name"], "system": e["system"], "held_out": bool(e.get("held_out")),
        "learner": SAC_LABEL, "seeds": len(curves), "succeed": sum(c[-1].success for c in curves),
        "ever_succeeded": sum(f is not None for f, _ in steps),
        "first_success_s": median_to_success([f for f, _ in secs]),
        "first_success_samples": median_to_success([f for f, _ in steps]),
        "holds_s": median_to_success([h for _, h in secs]),
        "holds_samples": median_to_success([h for _, h in steps]),
        "run_samples": median([c[-1].steps for c in curves]),
        "final_return": median([c[-1].greedy_return for c in curves]),
        "wall_s": median([c[-1].wall_s for c in curves]),
        "agent_ms_median": None, "agent_ms_p99": None,
    }


def fmt(v, spec):
    return "—" if v is None else format(v, spec)


def interaction(s, n):
    """'s s / n samples' of a median, or 'not reached'."""
    return "not reached" if s is None else f"{s:.{2 if s < 10 else 0}f} s / {n:.0f}"


def table(rows) -> list:
    """The Markdown table of `rows`."""
    lines = [
        "| system | learner | seeds succeeding at the end | ever | to first success: simulated s / samples "
        "(median) | to success held to the end: s / samples (median) | greedy return at the end (median) "
        "| wall time per run (median) | agent's step per sample, median / 99 % (medians of the seeds) |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        step = ("—" if r["agent_ms_median"] is None
                else f"{r['agent_ms_median']:.3f} / {r['agent_ms_p99']:.3f} ms")
        lines.append(
            f"| {r['system']} | {r['learner']} | {r['succeed']} of {r['seeds']} | {r['ever_succeeded']} "
            f"| {interaction(r['first_success_s'], r['first_success_samples'])} "
            f"| {interaction(r['holds_s'], r['holds_samples'])} "
            f"| {fmt(r['final_return'], '.2f')} | {fmt(r['wall_s'], '.1f')} s | {step} |"
        )
    return lines


def report(rows, out: Path) -> str:
    """The Markdown report (the systems the rules were chosen on, then the held-out ones,
    then the published figures); writes OUT/table.csv with every row."""
    inside = [r for r in rows if not r["held_out"]]
    held_out = [r for r in rows if r["held_out"]]
    lines = []
    if inside:
        lines += table(inside)
    if held_out:
        lines += ["", "Out of sample — systems not used to choose the default learner's rules:", ""]
        lines += table(held_out)
    lines += ["", "Published figures for the same kinds of task:", "",
              "| source | task | figure |", "|---|---|---|"]
    lines += [f"| {a} | {b} | {c} |" for a, b, c, _, _ in PUBLISHED]
    with open(out / "table.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]) if rows else ["experiment"])
        w.writeheader()
        w.writerows(rows)
    return "\n".join(lines) + "\n"


def plot(rows, out: Path, learners=("default", SAC_LABEL)):
    """OUT/interaction.png: per system, samples of interaction until the first success
    (filled) and until success held to the end (open) of `learners`, and the published
    figures; a median seed that never got there is drawn at its run's length as ×."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    systems = list(dict.fromkeys((r["experiment"], r["system"], r["held_out"]) for r in rows))
    if not systems:
        return
    fig, ax = plt.subplots(figsize=(10, 2.2 + 0.55 * len(systems)), layout="constrained")
    styles = {learners[0]: ("tab:blue", -0.15), learners[1]: ("tab:orange", 0.15)}
    labelled = set()

    def mark(x, y, label, **style):
        ax.scatter([x], [y], label=None if label in labelled else label, **style)
        labelled.add(label)

    for y, (name, _, _) in enumerate(systems):
        for r in (r for r in rows if r["experiment"] == name and r["learner"] in styles):
            colour, dy = styles[r["learner"]]
            for key, what in (("first_success_samples", "first success"), ("holds_samples", "held to the end")):
                if r[key] is None:
                    mark(r["run_samples"], y + dy, "median seed never: at its run's length",
                         marker="x", s=60, color=colour)
                else:
                    face = colour if what == "first success" else "none"
                    mark(r[key], y + dy, f"{r['learner']}: {what}", marker="o", s=60,
                         edgecolors=colour, facecolors=face)
        for _, _, _, samples, names in PUBLISHED:
            if name in names:
                mark(samples, y, "published (PILCO; rl-zoo's budget)", marker="*", s=140, color="tab:green")
    ax.set_yticks(range(len(systems)))
    ax.set_yticklabels([f"{s}{' (held out)' if h else ''}" for _, s, h in systems], fontsize=8)
    ax.set_ylim(len(systems) - 0.5, -0.5)
    ax.set_xscale("log")
    ax.set_xlabel("samples of interaction until success (median over seeds)")
    ax.grid(axis="x", which="major", alpha=0.3)
    fig.legend(fontsize=7, loc="outside lower center", ncol=3)
    fig.savefig(out / "interaction.png", dpi=110, bbox_inches="tight")
    plt.close(fig)
