"""Results of a check: a verdict, its counterexample, and the error the gate raises.

A `Verdict` is what every checker returns; a `Report` groups the verdicts of one plan
(e.g. the chosen order *and* the whole reachability graph). `VerificationError` is an
`InfeasibleError`, so the CLIs turn it into exit status 1 with its counterexample.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from tamp.errors import InfeasibleError
from tamp.ltl.formula import short
from tamp.verification.words import Word

#: Characters of a formula or word that text output shows (JSON carries it whole): the
#: encoding of a plan of 5,000 goals is 10,000 conjuncts long.
FORMULA_SHOWN = 200
#: Violated conjuncts that text output lists.
VIOLATED_SHOWN = 8


@dataclass
class Counterexample:
    """Why a check failed.

    ``word`` is the violating behaviour: the checked trace, or a run of the checked system
    (``steps`` then describes each position: the system state or action behind it).
    ``position`` is the first position after which no accepting continuation exists (the
    end of the shortest bad prefix); ``None`` when every finite prefix can still be
    extended, i.e. only the infinite repetition of the cycle (or, for a finite trace, its
    end) fails. ``accepting_word`` agrees with ``word`` before ``position`` and is
    accepted: the comparison a user needs to see what should have happened instead.
    """

    word: Word
    reason: str
    position: int | None = None
    accepting_word: Word | None = None
    violated: list[str] = field(default_factory=list)
    steps: list[str] | None = None
    aps: list[str] = field(default_factory=list)

    def to_json(self) -> dict:
        out = {
            "reason": self.reason,
            "position": self.position,
            "violated": list(self.violated),
            "word": self.word.to_json(),
            "word_text": self.word.format(self.aps),
            "accepting_word": self.accepting_word.to_json() if self.accepting_word else None,
            "accepting_word_text": (
                self.accepting_word.format(self.aps) if self.accepting_word else None
            ),
        }
        if self.steps is not None:
            out["steps"] = list(self.steps)
        return out

    def text(self) -> str:
        lines = [f"counterexample: {self.reason}"]
        if self.violated:
            shown = self.violated[:VIOLATED_SHOWN]
            more = len(self.violated) - len(shown)
            lines.append(
                "  violated: " + "; ".join(shown) + (f"; … and {more} more" if more else "")
            )
        if self.steps is not None:
            n = len(self.word.prefix)
            shown = _steps_shown(len(self.steps), self.position)
            for i, s in enumerate(self.steps):
                if i not in shown:
                    if i - 1 in shown:
                        lines.append("  …")
                    continue
                mark = "  cycle " if i >= n else "  "
                letter = self.word.letter(i)
                props = ", ".join(sorted(letter & set(self.aps))) if self.aps else ""
                lines.append(f"{mark}[{i}] {s}" + (f"  {{{props}}}" if props or self.aps else ""))
        else:
            lines.append(f"  word:      {short(self.word.format(self.aps), FORMULA_SHOWN)}")
        if self.position is not None:
            lines.append(f"  no accepting continuation after position {self.position}")
        if self.accepting_word is not None:
            accepted = self.accepting_word.format(self.aps)
            lines.append(f"  accepted:  {short(accepted, FORMULA_SHOWN)}")
        return "\n".join(lines)


def _steps_shown(n: int, position: int | None, edge: int = 5) -> set[int]:
    """The steps text output lists: all of a short run; of a long one its start, the steps
    around the end of the bad prefix and its end (JSON carries every step)."""
    if n <= 4 * edge:
        return set(range(n))
    keep = set(range(edge)) | set(range(n - edge, n))
    if position is not None:
        keep |= set(range(max(0, position - edge), min(n, position + edge + 1)))
    return keep


@dataclass
class Verdict:
    """Outcome of one check of ``subject`` against ``formula``."""

    subject: str
    formula: str
    semantics: str  # "finite", "infinite" (lasso) or "all paths" (model checking)
    holds: bool
    states_explored: int
    counterexample: Counterexample | None = None
    #: False when the system was explored only up to a bound: then no violation among the
    #: explored states does not establish the property (status "unknown")
    complete: bool = True

    @property
    def status(self) -> str:
        """``holds``, ``violated`` (a real counterexample), or ``unknown`` (bounded, none found)."""
        if not self.holds:
            return "violated"
        return "holds" if self.complete else "unknown"

    def to_json(self) -> dict:
        return {
            "subject": self.subject,
            "formula": self.formula,
            "semantics": self.semantics,
            "status": self.status,
            "holds": self.status == "holds",
            "states_explored": self.states_explored,
            "counterexample": self.counterexample.to_json() if self.counterexample else None,
        }

    def text(self) -> str:
        word = {"holds": "holds", "violated": "VIOLATED", "unknown": "UNKNOWN (bounded)"}
        head = (
            f"{self.subject}: {word[self.status]} "
            f"({self.semantics}; {self.states_explored} states explored)\n"
            f"  formula: {short(self.formula, FORMULA_SHOWN)}"
        )
        if self.counterexample is None:
            return head
        return head + "\n" + self.counterexample.text()


@dataclass
class Report:
    """The verdicts of one plan; holds when all hold."""

    verdicts: list[Verdict]
    #: states of the one system all verdicts share (BT exploration); None: sum of verdicts
    explored: int | None = None
    #: checks that were skipped or bounded, in words
    notes: list[str] = field(default_factory=list)

    @property
    def status(self) -> str:
        """``violated`` if any verdict is, else ``unknown`` if any is, else ``holds``."""
        kinds = {v.status for v in self.verdicts}
        return "violated" if "violated" in kinds else "unknown" if "unknown" in kinds else "holds"

    @property
    def holds(self) -> bool:
        """Every property established (a bounded "no violation found" does not count)."""
        return self.status == "holds"

    @property
    def violated(self) -> bool:
        return self.status == "violated"

    @property
    def states_explored(self) -> int:
        if self.explored is not None:
            return self.explored
        return sum(v.states_explored for v in self.verdicts)

    @property
    def failed(self) -> list[Verdict]:
        return [v for v in self.verdicts if not v.holds]

    @property
    def counterexample(self) -> Counterexample | None:
        bad = self.failed
        return bad[0].counterexample if bad else None

    def to_json(self) -> dict:
        ce = self.counterexample
        return {
            "status": self.status,
            "holds": self.holds,
            "counterexample": ce.to_json() if ce else None,
            "states_explored": self.states_explored,
            "checks": [v.to_json() for v in self.verdicts],
            "notes": list(self.notes),
        }

    def text(self) -> str:
        return "\n".join([v.text() for v in self.verdicts] + [f"note: {n}" for n in self.notes])


class VerificationError(InfeasibleError):
    """A plan failed verification; carries the `Report` and its counterexample (exit 1)."""

    def __init__(self, report: Report | Verdict):
        if isinstance(report, Verdict):
            report = Report([report])
        self.report = report
        bad = report.failed
        first = bad[0] if bad else None
        summary = (
            f"verification failed: {first.subject} violates {short(first.formula, FORMULA_SHOWN)}"
            if first
            else "verification failed"
        )
        self.summary = summary
        super().__init__(
            summary + ("\n" + first.counterexample.text() if first and first.counterexample else "")
        )

    @property
    def counterexample(self) -> Counterexample | None:
        return self.report.counterexample
