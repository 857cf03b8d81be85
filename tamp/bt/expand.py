"""ExpandTree (SMP-MRO Alg. 3): grow a failed condition into RF(c, PF(RS(con…, action)…)).

- GetAllActTemplatesFor (l. 2): every template with an effect that unifies with the failed
  condition (``ActionTemplate.bindings_achieving``); unlike PA-BT all of them are kept, as
  children of a PriorityFallback ordered by a priority function (default: the template's
  success rate), so the priority of actions stays variable (§IV-C3).
- GetActionValuesFromCondition (l. 10): parameters the condition does not bind are filled
  from the state: an unbound *object* is the held object (IsHandFree() is achieved by
  Place(held, l_free)); an unbound *area* is a free area chosen by `free_area`.
- Eager expansion (l. 14-15): preconditions that do not hold in the current state are
  expanded at once, recursively.
- GetRecoveryTreeForCondition (l. 4): when no template achieves the condition. IsAreaFree(l)
  is recovered by inserting IsObjectAt(b, l_free_b) before it, for each blocking object b,
  and expanding those like any other condition (see `recovery`).
- Conflict (l. 20-21): the new subtree conflicts when one of its actions has an effect that
  contradicts (``Predicate.contradicts``) a condition an earlier part of the tree relies on:
  the guard of a left sibling in an enclosing ReactiveSequence (those are re-checked every
  tick; a Sequence-with-memory's finished children and Fallback guards are not relied on).
  IncreasePriority moves the subtree one place left; at the front of its ReactiveSequence
  it moves above its parent into the next enclosing ReactiveSequence, leaving a bare guard
  Condition behind so the parent still checks it. A *mutual* conflict (the sibling it must
  pass also undoes the subtree's guard) cannot be fixed by reordering: ExpansionError.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from tamp.bt.nodes import (
    ActionNode,
    Condition,
    Node,
    PriorityFallback,
    ReactiveFallback,
    ReactiveSequence,
    actions_in,
    guard_of,
)
from tamp.world.actions import Action, ActionTemplate, Domain
from tamp.world.geometry import Area
from tamp.world.predicates import IsAreaFree, IsObjectAt, Predicate
from tamp.world.state import WorldState

MAX_DEPTH = 12
MAX_MOVES = 64

#: priority(action, state) -> float; higher is tried first in the PriorityFallback.
PriorityFn = Callable[[Action, WorldState], float]


def success_rate_priority(action: Action, state: WorldState) -> float:
    return action.template.success_rate


class ExpansionError(Exception):
    """The tree cannot grow to achieve a condition (the executor stops with this reason)."""


@dataclass(frozen=True)
class Conflict:
    """The subtree's ``action`` undoes ``relied_on``, the guard of ``sibling``."""

    action: Action
    effect: Predicate
    relied_on: Predicate
    sibling: Node

    def __str__(self) -> str:
        return f"{self.action} makes {self.effect} true, which undoes {self.relied_on}"


# -- pure tree queries ----------------------------------------------------------------------
def find_conflict(sub: Node, scope: Node | None = None) -> Conflict | None:
    """The first relied-on condition (left of ``sub`` in an enclosing RS, inside ``scope``
    when given) that an action of ``sub`` undoes."""
    effects = [(a, e) for a in actions_in(sub) for e in a.eff]
    if not effects:
        return None
    child = sub
    node = sub.parent
    while node is not None:
        if isinstance(node, ReactiveSequence):
            for sibling in node.children[: node.index_of(child)]:
                g = guard_of(sibling)
                if g is None:
                    continue
                for a, e in effects:
                    if e.contradicts(g) or g.contradicts(e):
                        return Conflict(a, e, g, sibling)
        if node is scope:
            break
        child = node
        node = node.parent
    return None


def _undoes(node: Node, pred: Predicate | None) -> Action | None:
    if pred is None:
        return None
    for a in actions_in(node):
        for e in a.eff:
            if e.contradicts(pred) or pred.contradicts(e):
                return a
    return None


def _owner(leaf: Node) -> str:
    """The action whose precondition ``leaf`` is (for the growth log)."""
    if leaf.parent is not None:
        last = leaf.parent.children[-1]
        if isinstance(last, ActionNode):
            return str(last.action)
    return "recovery"


class TreeGrowth:
    """Alg. 3 as methods of the executor (`PaBtExecutor` inherits them).

    The methods edit the executor's tree between ticks and use its bookkeeping: the
    attributes and services annotated below, which `PaBtExecutor` provides. Keeping them
    here keeps this module free of any import of the executor.
    """

    # provided by PaBtExecutor
    domain: Domain
    state: WorldState | None
    ticking: bool
    priority: PriorityFn
    put_down_hint: dict[str, str]
    reserve_free_area: Callable[..., Area | None]
    count_expansion: Callable[[], None]
    count_conflict: Callable[[int], None]
    log_event: Callable[..., None]

    # -- GetAllActTemplatesFor + GetActionValuesFromCondition -----------------------------
    def achieving_actions(self, cond: Predicate, state: WorldState) -> list[Action]:
        """Every ground action whose effects make ``cond`` true (one per template binding)."""
        out: list[Action] = []
        seen: set[str] = set()
        for template in self.domain.templates.values():
            for binding in template.bindings_achieving(cond):
                action = self._complete(template, dict(binding), state)
                if action is not None and str(action) not in seen:
                    seen.add(str(action))
                    out.append(action)
        return out

    def _complete(
        self, template: ActionTemplate, binding: dict[str, str], state: WorldState
    ) -> Action | None:
        for name, kind in template.params:
            if name in binding:
                continue
            if kind == "object":
                if state.held is None:
                    return None
                binding[name] = state.held
        for name, _kind in template.params:
            if name in binding:
                continue
            held = state.held if state.held in binding.values() else None
            if held is not None and held in self.put_down_hint:
                binding[name] = self.put_down_hint.pop(held)
            else:
                area = self.reserve_free_area(self.state, freeing=None)
                if area is None:
                    return None
                binding[name] = area.name
        return self.domain.action(template.name, *(binding[p] for p in template.param_names))

    # -- ExpandTree ------------------------------------------------------------------------
    def expand(
        self,
        cond_node: Condition,
        *,
        why: str,
        depth: int = 0,
        scope: Node | None = None,
    ) -> Node:
        """Grow the tree at ``cond_node`` (a failed, attached Condition); returns the subtree.

        Conditions are evaluated on ``self.state`` (the state observed after the failing
        tick, plus any free area the growth step has just found). ``scope`` is the subtree
        of the outermost call: as in Alg. 3, where nested expansions work on T_seq before it
        joins T, a nested subtree resolves conflicts only inside it; the outermost subtree
        then resolves its conflicts with the rest of the tree.
        """
        if self.ticking:
            raise RuntimeError("the tree is edited only between ticks")
        if depth > MAX_DEPTH:
            raise ExpansionError(f"expansion of {cond_node.pred} nests deeper than {MAX_DEPTH}")
        parent = cond_node.parent
        if parent is None:
            raise ExpansionError(f"{cond_node.pred} is the root; it cannot be expanded in place")
        cond = cond_node.pred
        state = self.state
        assert state is not None
        actions = self.achieving_actions(cond, state)
        if not actions:
            return self.recovery(cond_node, why=why, depth=depth)
        self.count_expansion()
        pf = PriorityFallback()
        now = self.state  # achieving_actions may have added a free area to it
        assert now is not None
        for a in actions:
            rs = ReactiveSequence([Condition(c) for c in a.con] + [ActionNode(a)])
            pf.add(rs, self.priority(a, now))
        sub = ReactiveFallback([Condition(cond, expanded=True), pf])
        parent.replace(cond_node, sub)  # Alg. 3 l. 19
        self.log_event("expand", cond, why, " | ".join(str(a) for a in actions), sub)
        # Alg. 3 l. 14-15: preconditions that do not hold now are expanded at once.
        for leaf in [n for n in pf.walk() if type(n) is Condition]:
            now = self.state  # expanding a precondition may add a free area to it
            assert now is not None
            if leaf.parent is not None and not leaf.pred.holds(now):
                self.expand(
                    leaf,
                    why=f"precondition of {_owner(leaf)}",
                    depth=depth + 1,
                    scope=scope or sub,
                )
        self.resolve_conflicts(sub, scope)  # Alg. 3 l. 20-21
        return sub

    # -- GetRecoveryTreeForCondition -------------------------------------------------------
    def recovery(self, cond_node: Condition, *, why: str, depth: int = 0) -> Node:
        """Make ``cond`` true when no action template does (Alg. 3 l. 4).

        IsAreaFree(l): for every object b blocking l, a Condition IsObjectAt(b, l_free) is
        inserted *before* the failed condition and expanded like any other condition (it
        is the "tree added to check IsObjectAt(O_a, l_free) to satisfy IsAreaFree(l_1)" of
        §V-D2). The failed IsAreaFree(l) stays in place, unexpanded: it keeps guarding the
        action and, should a new blocker appear later, fails and grows a new recovery.
        (Using IsAreaFree(l) itself as the guard would let the recovery stop as soon as the
        blocker is *grasped*, since a held object is not in any area.) Returns the first
        recovery subtree.
        """
        cond = cond_node.pred
        if not isinstance(cond, IsAreaFree):
            raise ExpansionError(
                f"no action template achieves {cond} and no recovery is known for it"
            )
        state = self.state
        assert state is not None
        blockers = cond.blockers(state)
        if not blockers:
            raise ExpansionError(f"{cond} failed but no object blocks {cond.area}")
        parent = cond_node.parent
        assert parent is not None
        held = state.held
        if held is not None and held not in self.put_down_hint:
            # The robot must put down what it holds before it can pick a blocker: that
            # object gets the free area nearest to the robot, the blockers the next ones
            # (§V-D2: Place(O_1, l_free2) near l_1, then O_a to l_free1).
            area = self.reserve_free_area(self.state, freeing=cond.area)
            if area is not None:
                self.put_down_hint[held] = area.name
        stand_ins: list[Condition] = []
        for b in blockers:
            area = self.reserve_free_area(self.state, freeing=cond.area)
            if area is None:
                raise ExpansionError(f"no free area left to move {b} out of {cond.area}")
            node = Condition(IsObjectAt(b, area.name))
            parent.insert(parent.index_of(cond_node), node)
            stand_ins.append(node)
        self.log_event("recovery", cond, why, ", ".join(str(n.pred) for n in stand_ins))
        subs = [self.expand(n, why=f"recovery for {cond}", depth=depth + 1) for n in stand_ins]
        return subs[0]

    # -- Conflict + IncreasePriority -------------------------------------------------------
    def resolve_conflicts(self, sub: Node, scope: Node | None = None) -> int:
        """IncreasePriority until `find_conflict` is None (Alg. 3 l. 20-21); returns moves."""
        first = find_conflict(sub, scope)
        if first is None:
            return 0
        moves = 0
        conflict: Conflict | None = first
        while conflict is not None:
            if moves >= MAX_MOVES:
                raise ExpansionError(f"conflict not resolved after {MAX_MOVES} moves: {conflict}")
            parent = sub.parent
            assert parent is not None
            index = parent.index_of(sub)
            if isinstance(parent, ReactiveSequence) and index > 0:
                left = parent.children[index - 1]
                back = _undoes(left, guard_of(sub))
                if back is not None and guard_of(left) == conflict.relied_on:
                    raise ExpansionError(
                        f"unresolvable conflict: {conflict}, and {back} (which establishes "
                        f"{conflict.relied_on}) undoes {guard_of(sub)}; no execution order "
                        f"satisfies both"
                    )
                parent.remove(sub)
                parent.insert(index - 1, sub)
            else:
                self._move_above_parent(sub, conflict, scope)
            moves += 1
            conflict = find_conflict(sub, scope)
        parent = sub.parent
        where = ""
        if parent is not None:
            index = parent.index_of(sub)
            after = parent.children[index + 1] if index + 1 < len(parent.children) else None
            where = f", now child {index} of its {parent.describe()}"
            if after is not None:
                where += f", before {guard_of(after) or after.describe()}"
        self.log_event(
            "conflict",
            guard_of(sub),
            str(first),
            f"moved up {moves} place(s) in execution order{where}",
            sub,
        )
        self.count_conflict(moves)
        return moves

    def _move_above_parent(self, sub: Node, conflict: Conflict, scope: Node | None) -> None:
        """Take ``sub`` out of its ReactiveSequence and put it before that sequence's branch
        in the next enclosing ReactiveSequence, leaving its guard as a bare Condition."""
        branch = sub.parent
        target = branch.parent if branch is not None else None
        while target is not None and not isinstance(target, ReactiveSequence):
            if branch is scope:
                target = None
                break
            branch = target
            target = target.parent
        if target is None or branch is None:
            raise ExpansionError(f"unresolvable conflict: {conflict}; no enclosing sequence left")
        guard = guard_of(sub)
        parent = sub.parent
        assert parent is not None and guard is not None
        stand_in = Condition(guard)
        parent.replace(sub, stand_in)
        target.insert(target.index_of(branch), sub)
