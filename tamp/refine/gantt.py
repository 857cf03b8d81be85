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
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(phases), 1, figsize=(9, 1.6 + 1.4 * len(phases)), squeeze=False)
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
    plt.close(fig)
    return str(out)
