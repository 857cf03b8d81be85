"""A campaign's two figures, each as PNG and SVG (matplotlib, Agg backend, no display):
the task-time histogram of the successful runs, and success rate by perturbation size with
Wilson 95 % error bars."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from tamp.campaign.stats import Bin, wilson_interval


def _figure():
    """A figure and its axes, without pyplot (a notebook's inline backend stays on)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(5.5, 3.5))
    return fig, fig.subplots()


def _finish(fig, ax, labels: tuple[str, str, str], out: Path, stem: str) -> list[str]:
    """Label the axes and title, write ``out/stem.png`` and ``.svg``."""
    xlabel, ylabel, title = labels
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for ext in ("png", "svg"):
        p = out / f"{stem}.{ext}"
        fig.savefig(p, dpi=120 if ext == "png" else None, bbox_inches="tight")
        paths.append(str(p))
    return paths


def task_time_histogram(times: Sequence[float], out: Path, title: str) -> list[str]:
    """Histogram of task times (sim s) of the successful runs; returns the files written."""
    fig, ax = _figure()
    if times:
        ax.hist(times, bins=min(20, max(5, len(times) // 2)), color="#4878a8", edgecolor="white")
    else:
        ax.text(0.5, 0.5, "no successful run", ha="center", va="center", transform=ax.transAxes)
    return _finish(fig, ax, ("task time (sim s)", "runs", title), out, "task_time")


def success_by_perturbation(bins: Sequence[Bin], out: Path, title: str) -> list[str]:
    """Success rate per perturbation-size bin with Wilson 95 % intervals."""
    fig, ax = _figure()
    for b in bins:
        lo, hi = wilson_interval(b.successes, b.n)
        x = (b.lo + b.hi) / 2
        ax.errorbar(
            x, b.rate, yerr=[[b.rate - lo], [hi - b.rate]], fmt="o", color="#4878a8", capsize=3
        )
        ax.annotate(
            f"{b.successes}/{b.n}",
            (x, b.rate),
            textcoords="offset points",
            xytext=(6, -12),
            fontsize=8,
        )
    ax.set_ylim(-0.02, 1.05)
    labels = ("perturbation size", "success rate", title)
    return _finish(fig, ax, labels, out, "success_by_perturbation")
