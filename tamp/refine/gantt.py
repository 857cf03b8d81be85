"""Fig. 12-style timelines: one panel per phase, one row per robot section, a bar per
behavior from its start to its event (matplotlib, no Drake)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from tamp.refine.timeline import Timeline

COLORS = {"base": "#4c72b0", "arm": "#dd8452", "gripper": "#55a868"}


def draw_gantt(phases: Sequence[tuple[str, Timeline]], path: str | Path, title: str = "") -> str:
    """Write the timelines of ``phases`` (name, timeline) as one figure (SVG, PNG, PDF by
    the file's suffix); absorbed behaviors (completion markers) are hatched."""
    from matplotlib.figure import Figure  # no pyplot: a notebook's inline backend stays on

    fig = Figure(figsize=(9, 1.6 + 1.4 * len(phases)))
    axes = fig.subplots(len(phases), 1, squeeze=False)
    end = max((t.task_time for _, t in phases), default=1.0) * 1.05 or 1.0
    for ax, (name, timeline) in zip(axes[:, 0], phases, strict=True):
        rows: list[str] = []
        for r in timeline.records:
            row = f"{r.robot} {r.section}"
            if row not in rows:
                rows.append(row)
        for r in timeline.records:
            if r.start is None:
                continue
            stop = r.end if r.end is not None else timeline.task_time
            y = rows.index(f"{r.robot} {r.section}")
            ax.barh(
                y,
                stop - r.start,
                left=r.start,
                height=0.6,
                color=COLORS.get(r.section, "grey"),
                edgecolor="black",
                hatch=None if r.gating else "//",
            )
            ax.text(
                r.start + (stop - r.start) / 2, y, r.behavior, ha="center", va="center", fontsize=7
            )
        ax.set_yticks(range(len(rows)), rows, fontsize=8)
        ax.invert_yaxis()
        ax.set_xlim(0, end)
        ax.set_title(f"{name}: {timeline.task_time:.1f} s", fontsize=9, loc="left")
    axes[-1, 0].set_xlabel("time (s)")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out)
    return str(out)


#: the paper's Task 4 phases (s; Figueroa Heredia et al. 2018, Fig. 12), drawn beside ours
PAPER_TASK4 = {
    "original": 260.0,
    "parallelized": 203.0,
    "speed-adjusted": 192.0,
    "rate-refined": 93.0,
}


def draw_phases(
    phases: Sequence[tuple[str, float]],
    path: str | Path,
    title: str = "",
    paper: dict[str, float] | None = None,
    label: str = "ours (measured)",
) -> str:
    """Fig. 14-style bars: the task time of each phase (name, s), and beside each the
    paper's (``paper``, phase name -> s) when given; the reduction from the first phase is
    written on each bar."""
    from matplotlib.figure import Figure  # no pyplot: a notebook's inline backend stays on

    names = [n for n, _ in phases]
    times = [t for _, t in phases]
    fig = Figure(figsize=(7, 4))
    ax = fig.subplots()
    width = 0.38 if paper else 0.6
    xs = list(range(len(names)))
    ours = [x - width / 2 for x in xs] if paper else xs
    bars = ax.bar(ours, times, width, color="#4c72b0", label=label)
    for bar, t in zip(bars, times, strict=True):
        change = "" if t == times[0] or not times[0] else f"\n{t / times[0] - 1:+.0%}"
        ax.text(
            bar.get_x() + bar.get_width() / 2,
            t,
            f"{t:.0f} s{change}",
            ha="center",
            va="bottom",
            fontsize=8,
        )
    if paper:
        theirs = [paper.get(n, 0.0) for n in names]
        ax.bar([x + width / 2 for x in xs], theirs, width, color="#c0c0c0", label="paper")
        ax.legend(fontsize=8)
    ax.set_xticks(xs, names, fontsize=9)
    ax.set_ylabel("task time (s)")
    ax.set_ylim(0, max(times + (list(paper.values()) if paper else [])) * 1.2)
    if title:
        ax.set_title(title, fontsize=10)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out)
    return str(out)
