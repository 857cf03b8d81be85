"""What one execution measured (Fig. 1(b), Fig. 11): when each behavior started and when
its event fired, and the task time. The refinement steps read durations from it."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class BehaviorRecord:
    """Behavior ``robot.behavior`` ran from ``start`` (None: never started); its event fired
    at ``end`` (None: never, within the run). ``gating``: False for an absorbed behavior (a
    marker)."""

    robot: str
    behavior: str
    section: str
    start: float | None
    end: float | None
    gating: bool = True

    @property
    def event(self) -> str:
        return f"{self.robot}.{self.behavior}"

    @property
    def duration(self) -> float | None:
        return None if self.end is None or self.start is None else self.end - self.start

    def to_json(self) -> dict:
        return {
            "event": self.event,
            "section": self.section,
            "start": None if self.start is None else round(self.start, 3),
            "end": None if self.end is None else round(self.end, 3),
            "gating": self.gating,
        }


@dataclass(frozen=True)
class Timeline:
    """All behavior records of one run, and the task time (the last event)."""

    records: tuple[BehaviorRecord, ...]
    rates: dict[str, float] = field(default_factory=dict)  # robot -> final command rate

    @property
    def task_time(self) -> float:
        ends = [r.end for r in self.records if r.end is not None]
        return max(ends, default=0.0)

    @property
    def finished(self) -> bool:
        return all(r.end is not None for r in self.records)

    def record(self, event: str) -> BehaviorRecord:
        for r in self.records:
            if r.event == event:
                return r
        raise KeyError(event)

    def durations(self) -> dict[str, float]:
        """Event id -> measured duration, for the behaviors whose event fired."""
        return {r.event: r.duration for r in self.records if r.duration is not None}

    def order(self) -> list[str]:
        """Events in the order they fired (ties: program order)."""
        fired = [(r.end, i, r.event) for i, r in enumerate(self.records) if r.end is not None]
        return [e for _, _, e in sorted(fired)]

    def to_json(self) -> dict:
        return {
            "task_time": round(self.task_time, 3),
            "behaviors": [r.to_json() for r in self.records],
            "rates": dict(self.rates),
        }
