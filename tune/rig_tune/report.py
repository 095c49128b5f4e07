"""OUT/report.md: the study's trials, the parameters that mattered, and the check of the
best configuration against the preset, with Optuna's plots and the check's curves."""

from __future__ import annotations

import argparse
import os
import warnings
from collections.abc import Callable
from pathlib import Path
from statistics import fmean, stdev
from typing import Any

os.environ.setdefault("MPLBACKEND", "Agg")

import matplotlib.pyplot as plt  # noqa: E402
import optuna  # noqa: E402
from optuna.trial import TrialState  # noqa: E402

from .check import Arm, verdict  # noqa: E402


def write(args: argparse.Namespace, study: optuna.Study, url: str, arms: list[Arm], eval_every: int) -> Path:
    """Writes the report and its plots; returns the report's path."""
    plots = args.out / "plots"
    plots.mkdir(parents=True, exist_ok=True)
    lines = [f"# Study {study.study_name}", ""] + summary(args, study, url) + [""]
    lines += checked(args, arms, plots, eval_every)
    lines += importances(study, plots)
    lines += optuna_plots(study, plots)
    lines += trials_table(study)
    path: Path = args.out / "report.md"
    path.write_text("\n".join(lines) + "\n")
    return path


def summary(args: argparse.Namespace, study: optuna.Study, url: str) -> list[str]:
    trials = study.get_trials(deepcopy=False)
    count = {s: sum(t.state == s for t in trials) for s in TrialState}
    best = study.best_trial
    shown = url.split("@")[-1] if url.startswith("postgresql") else url
    return [
        f"- storage: `{shown}`; sampler {args.sampler}, pruner {args.pruner}",
        f"- trials: {count[TrialState.COMPLETE]} complete, {count[TrialState.PRUNED]} pruned, "
        f"{count[TrialState.FAIL]} failed",
        f"- objective (maximised): the mean over seeds 1..{args.seeds} of each run's mean greedy "
        f"return over its last {args.last} evaluations",
        f"- best: trial {best.number}, {best.value:.1f}; its configuration is `best.toml` "
        "(`rig learn --config best.toml`)",
        "",
        "| key | best |",
        "|---|---|",
    ] + [f"| `{k}` | {v:.6g} |" if isinstance(v, float) else f"| `{k}` | {v} |" for k, v in best.params.items()]


def checked(args: argparse.Namespace, arms: list[Arm], plots: Path, eval_every: int) -> list[str]:
    if not arms:
        return ["## Check", "", "No check was run (`--check-seeds 0`).", ""]
    finals = {a.label: a.finals(args.last) for a in arms}
    rows = ["| configuration | mean | sd | min | max | per seed |", "|---|---|---|---|---|---|"]
    for a in arms:
        f = finals[a.label]
        sd = stdev(f) if len(f) > 1 else 0.0
        rows.append(f"| {a.label} | {fmean(f):.1f} | {sd:.1f} | {min(f):.1f} | {max(f):.1f} | "
                    + ", ".join(f"{v:.1f}" for v in f) + " |")
    curves(arms, plots / "check.png", eval_every)
    seeds = ", ".join(str(s) for s in arms[0].greedy)
    return ["## Check on fresh seeds", "",
            f"Final greedy return (mean of the last {args.last} evaluations) of the best configuration "
            f"and of the preset, each learned with seeds {seeds}:", ""] + rows + [
        "", verdict(finals["best"], finals["preset"]), "", "![greedy returns on the check's seeds](plots/check.png)", ""]


def curves(arms: list[Arm], path: Path, eval_every: int) -> None:
    """The check's greedy curves: mean over seeds, and the range."""
    fig, ax = plt.subplots(figsize=(7, 4))
    for a in arms:
        runs = list(a.greedy.values())
        n = min(len(g) for g in runs)
        x = [eval_every * (i + 1) for i in range(n)]
        ax.plot(x, [fmean(g[i] for g in runs) for i in range(n)], label=f"{a.label} (mean)")
        ax.fill_between(x, [min(g[i] for g in runs) for i in range(n)],
                        [max(g[i] for g in runs) for i in range(n)], alpha=0.2)
    ax.set_xlabel("trial")
    ax.set_ylabel("greedy return")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def importances(study: optuna.Study, plots: Path) -> list[str]:
    """fANOVA importances of the parameters over the complete trials."""
    try:
        values = optuna.importance.get_param_importances(study)
    except (RuntimeError, ValueError) as e:
        return ["## Parameter importances", "", f"Not computed: {e}", ""]
    rows = ["| key | importance |", "|---|---|"] + [f"| `{k}` | {v:.3f} |" for k, v in values.items()]
    saved = save(optuna.visualization.matplotlib.plot_param_importances, study, plots / "importances.png")
    return ["## Parameter importances", ""] + rows + ["", saved, ""]


def optuna_plots(study: optuna.Study, plots: Path) -> list[str]:
    return ["## The study", "",
            save(optuna.visualization.matplotlib.plot_optimization_history, study, plots / "history.png"),
            "", save(optuna.visualization.matplotlib.plot_intermediate_values, study, plots / "intermediate.png"), ""]


def save(plot: Callable[[optuna.Study], Any], study: optuna.Study, path: Path) -> str:
    """One of Optuna's matplotlib plots as a PNG, and its Markdown image line."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        try:
            ax = plot(study)
        except (RuntimeError, ValueError) as e:
            return f"({path.stem}: not drawn: {e})"
    fig = ax.figure if hasattr(ax, "figure") else ax.flat[0].figure
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return f"![{path.stem}](plots/{path.name})"


def trials_table(study: optuna.Study) -> list[str]:
    trials = study.get_trials(deepcopy=False)
    keys = sorted({k for t in trials for k in t.params})
    head = "| trial | state | value | minutes | " + " | ".join(f"`{k}`" for k in keys) + " |"
    rows = [head, "|" + "---|" * (4 + len(keys))]
    for t in trials:
        value = f"{t.value:.1f}" if t.value is not None else ""
        minutes = f"{t.duration.total_seconds() / 60:.1f}" if t.duration else ""
        params = [f"{t.params[k]:.4g}" if isinstance(t.params.get(k), float) else str(t.params.get(k, ""))
                  for k in keys]
        rows.append(f"| {t.number} | {t.state.name.lower()} | {value} | {minutes} | " + " | ".join(params) + " |")
    return ["## Trials", ""] + rows
