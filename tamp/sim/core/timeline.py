"""A run's timeline: what ran when, in sim time, drawn the same way for every workcell.

`spans` reads a run's JSON document (`RunResult.to_json`, what ``tamp simulate CELL
--json`` prints and a campaign keeps per seed) and returns one `Span` per thing that
ran: the skills of the executor (``actions``: one row per skill, e.g. ``Pick``), the
scripted person's actions (``person_actions``) and a refinement program's behaviors
(``timeline``: one row per robot section). `draw_timeline` draws them as horizontal bars
over sim time with matplotlib (no Drake), coloured by how each ended.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

#: Bar colour per outcome (None: still running when the run ended).
COLORS = {
    "SUCCESS": "#55a868",
    "HALTED": "#4c72b0",
    "FAILURE": "#c44e52",
    "CANCELLED": "#aaaaaa",
    None: "#dd8452",
}


@dataclass(frozen=True)
class Span:
    """``label`` ran on row ``lane`` from ``start`` to ``end`` (None: to the run's end)."""

    lane: str
    label: str
    start: float
    end: float | None
    status: str | None = "SUCCESS"


def spans(doc: Mapping[str, Any]) -> list[Span]:
    """Every span of the run document ``doc``, in its order (module docstring)."""
    out: list[Span] = []
    for a in doc.get("actions") or ():
        name = str(a["action"])
        out.append(Span(name.split("(")[0], name, a["start"], a.get("end"), a.get("status")))
    for p in doc.get("person_actions") or ():
        if p.get("start") is None:
            continue
        what = p.get("object") or p.get("event", "")
        out.append(Span("person", str(what), p["start"], p.get("end"), "SUCCESS"))
    for b in doc.get("timeline") or ():
        if b.get("start") is None:
            continue
        robot, _, behavior = str(b["event"]).partition(".")
        lane = f"{robot} {b.get('section', '')}".strip()
        status = "SUCCESS" if b.get("end") is not None else None
        out.append(Span(lane, behavior or robot, b["start"], b.get("end"), status))
    return out


def draw_timeline(doc: Mapping[str, Any], path: str | Path) -> Path:
    """Draw the run ``doc``'s spans as a Gantt chart at ``path`` (SVG, PNG or PDF by its
    suffix): one row per lane, a bar per span, the run's verdict in the title."""
    import matplotlib.patches
    from matplotlib.figure import Figure  # no pyplot: a notebook's inline backend stays on

    items = spans(doc)
    lanes: list[str] = []
    for s in items:
        if s.lane not in lanes:
            lanes.append(s.lane)
    sim_time = float(doc.get("sim_time") or 0.0)
    end = max([sim_time, *(s.end or s.start for s in items)]) or 1.0
    fig = Figure(figsize=(10, 1.2 + 0.45 * max(len(lanes), 1)))
    ax = fig.subplots()
    for s in items:
        stop = s.end if s.end is not None else end
        y = lanes.index(s.lane)
        ax.barh(
            y,
            max(stop - s.start, end * 0.002),
            left=s.start,
            height=0.6,
            color=COLORS.get(s.status, "grey"),
            edgecolor="black",
            linewidth=0.5,
        )
        if stop - s.start > end * 0.04:
            ax.text(
                s.start + (stop - s.start) / 2, y, s.label, ha="center", va="center", fontsize=6
            )
    ax.set_yticks(range(len(lanes)), lanes, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlim(0, end * 1.02)
    ax.set_xlabel("sim time (s)")
    ax.set_title(_title(doc), fontsize=9, loc="left")
    handles = [
        matplotlib.patches.Patch(color=c, label=str(k).lower() if k else "running")
        for k, c in COLORS.items()
        if any(s.status == k for s in items)
    ]
    if handles:
        ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.tight_layout()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)
    return out


def _title(doc: Mapping[str, Any]) -> str:
    parts: Sequence[str] = (
        f"{doc.get('workcell', '')} {Path(str(doc.get('scenario', ''))).name}".strip(),
        f"seed {doc.get('seed')}",
        str(doc.get("status", "")),
    )
    return ", ".join(p for p in parts if p)
