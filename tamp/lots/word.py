"""The run's word: what happened in W^B, in order, read by the task automaton as it happens.

Zhou et al. judge a LOTS run by the letters it produces: the robot's action ``a_B^A(o_i)``
makes its proposition true (Def. 3), and a person's change of W^B (dis_1, dis_2, §III-B) is
seen by the camera as a new W^B state. `RunWord` records both, in order:

- a robot delivery for proposition ``p``: the letter ``{p}``;
- a robot removal from W^B (waste basket, or back to W^A with our return action): ∅;
- an observed W^B state: objects that appeared there since the last known state were
  delivered by someone, each as *some* proposition of its class (the attribution is not
  observable); objects that disappeared read ∅. Objects already in W^B at the start are no
  delivery at all.

It keeps the set of automaton states the word so far can lead to (over every attribution,
closed under ∅ letters, which only advance the automaton), each with one witness word, so
the controller never plans from a state the run cannot be in (which is how a replan could
take a block that started in W^B for a delivery that never happened), and a run is judged
on its word: accepted when some reachable state accepts the round's accepting cycle forever
(`accepting`). ``tamp.verification.lots.judge_word`` checks the witness against the formula.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from tamp.lots.automaton import EMPTY, Automaton, Letter
from tamp.lots.lots import Counts, Lots
from tamp.ltl.automata import accepts_lasso


@dataclass
class RunWord:
    """The word of a run so far (see module docstring); ``b`` is the last known W^B state."""

    aut: Automaton
    lots: Lots
    b: Counts
    #: automaton state -> one word from q_0 reaching it (∅-closed)
    states: dict[int, tuple[Letter, ...]] = field(default_factory=dict)
    #: what happened, in order, for the JSON and the text: (who, what) pairs
    events: list[tuple[str, str]] = field(default_factory=list)

    def __post_init__(self) -> None:
        if not self.states:
            self.states = self._closure({self.aut.initial: ()})

    # ------------------------------------------------------------------ reading letters
    def _closure(self, states: dict[int, tuple[Letter, ...]]) -> dict[int, tuple[Letter, ...]]:
        out = dict(states)
        stack = list(states)
        while stack:
            q = stack.pop()
            for nq in self.aut.successors(q, EMPTY):
                if nq not in out:
                    out[nq] = out[q] + (EMPTY,)
                    stack.append(nq)
        return out

    def _read(
        self, states: dict[int, tuple[Letter, ...]], letters: list[Letter]
    ) -> dict[int, tuple[Letter, ...]]:
        """One position: any of ``letters`` (one letter: a robot delivery)."""
        nxt: dict[int, tuple[Letter, ...]] = {}
        for q in sorted(states):
            for x in letters:
                for nq in self.aut.successors(q, x):
                    nxt.setdefault(nq, states[q] + (x,))
        return self._closure(nxt)

    def _letters_of(self, i: int) -> list[Letter]:
        return [frozenset({p}) for p, c in sorted(self.lots.prop_class.items()) if c == i]

    # ------------------------------------------------------------------ what happened
    def deliver(self, prop: str) -> None:
        """The robot placed an object in W^B for ``prop`` (after `observe` of W^B)."""
        i = self.lots.prop_class[prop]
        self.states = self._read(self.states, [frozenset({prop})])
        self.b = self.b[:i] + (self.b[i] + 1,) + self.b[i + 1 :]
        self.events.append(("robot", prop))

    def remove(self, i: int) -> None:
        """The robot took one object of class ``i`` out of W^B (letter ∅)."""
        self.b = self.b[:i] + (max(0, self.b[i] - 1),) + self.b[i + 1 :]
        self.events.append(("robot", f"remove {self.lots.classes[i]}"))

    def observe(self, b_obs: Counts) -> None:
        """The camera saw W^B in state ``b_obs``: what changed unseen enters the word."""
        if tuple(b_obs) == self.b:
            return
        self.states = self.peek(b_obs)
        self.events.append(("seen", f"W^B {self.lots.format(b_obs)}"))
        self.b = tuple(b_obs)

    def peek(self, b: Counts) -> dict[int, tuple[Letter, ...]]:
        """The states if W^B were now seen in state ``b`` (nothing is recorded)."""
        states = self.states
        for i, (old, new) in enumerate(zip(self.b, b, strict=True)):
            letters = self._letters_of(i)
            for _ in range(max(0, new - old)):
                if not letters:
                    break
                before = states
                states = self._read(states, letters)
                if states.keys() == before.keys():
                    break  # a fixed point: more of the same class changes nothing
        return states

    # ------------------------------------------------------------------ the verdict
    def accepting(self, cycle: list[Letter]) -> int | None:
        """A state the word can be in from which ``cycle^ω`` is accepted, or None."""
        for q in sorted(self.states):
            if accepts_lasso(self.aut.spot_aut, [], cycle, start=q)[0]:
                return q
        return None

    def witness(self, cycle: list[Letter]) -> tuple[tuple[Letter, ...], int]:
        """One word of the run (the accepted one, if any) and the state it reaches."""
        q = self.accepting(cycle)
        if q is None:
            q = min(self.states)
        return self.states[q], q

    def completes(
        self, states: dict[int, tuple[Letter, ...]], letters: list[Letter], cycle: list[Letter]
    ) -> bool:
        """From one of ``states``, do ``letters`` then ``cycle^ω`` get accepted?"""
        for x in letters:
            states = self._read(states, [x])
        return any(
            q in self.aut.live_accepting and accepts_lasso(self.aut.spot_aut, [], cycle, start=q)[0]
            for q in sorted(states)
        )

    def to_json(self) -> list[dict[str, str]]:
        return [{"by": who, "what": what} for who, what in self.events]
