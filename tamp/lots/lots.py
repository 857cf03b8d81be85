"""The locally observable transition system (LOTS, Zhou et al. Def. 3) over object counts.

A LOTS state is ``s = s^A_s^B``: counts of every task-related class in W^A and in W^B. The
controller reasons on the W^B part only (Lemma 1): under Assumption 1 the W^B counts never
exceed the final counts ``n'`` of one round of the task, so
``|S^B| = ∏_i (n'_i + 1)`` whatever a person does (dis_1, dis_2) — W^A may grow, W^B does not.

States are tuples of counts in the order of ``classes`` (a dict lookup on a tuple is what makes
a table hit cheap).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field

from tamp.lots.automaton import Letter

Counts = tuple[int, ...]


@dataclass(frozen=True)
class Lots:
    """The W^B side of the LOTS: classes, proposition → class, and the final W^B counts.

    ``final`` is ``s^B_final`` of the planned round; ``goals`` every W^B state that ends a
    round of *some* accepting way of the task (a task with alternatives, ``F p | F q``, has
    one per alternative; ``final`` is always among them). Lemma 1's box is bounded by
    ``bound``, their componentwise maximum (``final`` itself when there are no alternatives).
    """

    classes: tuple[str, ...]
    prop_class: Mapping[str, int]  # proposition -> class index
    final: Counts  # s^B_final: n'_i per class (one round of the planned way)
    goals: tuple[Counts, ...] = ()  # every round's end, final first (default: final only)
    bound: Counts = field(init=False)  # componentwise max of goals: Lemma 1's n'
    goal_set: frozenset[Counts] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        goals = (self.final,) + tuple(g for g in self.goals if g != self.final)
        object.__setattr__(self, "goals", goals)
        object.__setattr__(self, "goal_set", frozenset(goals))
        bound = tuple(max(g[i] for g in goals) for i in range(len(self.final)))
        object.__setattr__(self, "bound", bound)

    def vector(self, counts: Mapping[str, int]) -> Counts:
        """Counts of the task classes only (other objects are not task-related: ignored)."""
        return tuple(int(counts.get(c, 0)) for c in self.classes)

    def named(self, b: Iterable[int]) -> dict[str, int]:
        return dict(zip(self.classes, b, strict=True))

    def num_wb_states(self) -> int:
        """Lemma 1: ``|S^B| = ∏_i (n'_i + 1)`` (12 for Zhou et al.'s Example 1), n' = bound."""
        return math.prod(n + 1 for n in self.bound)

    def wb_states(self) -> Iterator[Counts]:
        """Every W^B state of Lemma 1's set, in lexicographic order."""
        return itertools.product(*(range(n + 1) for n in self.bound))

    def in_box(self, b: Counts) -> bool:
        return all(x <= n for x, n in zip(b, self.bound, strict=True))

    def is_goal(self, b: Counts) -> bool:
        """Does W^B state ``b`` end a round of some accepting way?"""
        return b in self.goal_set

    def needs(self, i: int, b: Counts) -> bool:
        """Could the rest of some round (from W^B state ``b``) deliver class ``i`` again?"""
        return any(g[i] > b[i] for g in self.goals)

    def surplus(self, b: Counts) -> int | None:
        """Index of a class with more objects in W^B than one round needs, if any."""
        for i, (x, n) in enumerate(zip(b, self.bound, strict=True)):
            if x > n:
                return i
        return None

    def deliver(self, b: Counts, letter: Letter) -> Counts | None:
        """``δ_t(s^B, a(σ))``: W^B after executing the letter; None when it leaves the box."""
        if not letter:
            return b
        (p,) = letter
        i = self.prop_class[p]
        if b[i] >= self.bound[i]:
            return None
        return b[:i] + (b[i] + 1,) + b[i + 1 :]

    def remove(self, b: Counts, i: int) -> Counts | None:
        """W^B with one object of class ``i`` taken out (waste basket or a person)."""
        if b[i] == 0:
            return None
        return b[:i] + (b[i] - 1,) + b[i + 1 :]

    def format(self, b: Iterable[int]) -> str:
        """Paper notation ``hammer^1 screw^2 …``."""
        return " ".join(f"{c}^{n}" for c, n in zip(self.classes, b, strict=True))
