"""Learning curves drawn the one way the bench scripts draw them: per learner a line
through the centre (mean or median) of its runs at each point, and the band from the
worst run to the best. matplotlib, without a display (Agg).

    fig, ax = figure()
    band(ax, trials, [returns of each run at each trial], "MLAC/LLR (5 runs)")
    finish(fig, ax, "trial", "greedy return", "the title", out / "curves", ("png", "svg"))
"""

from __future__ import annotations

import statistics
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Literal

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402


def figure() -> tuple[Figure, Axes]:
    """A figure of one plot, 7 by 4 inches."""
    fig, ax = plt.subplots(figsize=(7, 4))
    return fig, ax


def band(
    ax: Axes,
    x: Sequence[float],
    values: Sequence[Sequence[float]],
    label: str,
    centre: Callable[[Sequence[float]], float] = statistics.mean,
    **line: Any,
) -> None:
    """At each `x[k]`, the `centre` of `values[k]` (one value per run) as a line with
    `label` (and matplotlib's `line` keywords), and the band from its least to its most."""
    ax.plot(x, [centre(v) for v in values], label=label, **line)
    ax.fill_between(x, [min(v) for v in values], [max(v) for v in values], alpha=0.2)


def finish(
    fig: Figure, ax: Axes, xlabel: str, ylabel: str, title: str, stem: Path,
    formats: Sequence[str] = ("png",), legend: Literal["best", "lower right"] = "best",
    dpi: float | None = None,
) -> None:
    """Labels, legend and title; saved as `stem`.FORMAT for each format, then closed."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(loc=legend)
    fig.tight_layout()
    for ext in formats:
        if dpi is None:
            fig.savefig(stem.with_name(f"{stem.name}.{ext}"))
        else:
            fig.savefig(stem.with_name(f"{stem.name}.{ext}"), dpi=dpi)
    plt.close(fig)
