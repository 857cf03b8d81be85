"""Choosing l_free, "any free space that does not affect task execution" (§V-D2).

The rule (deterministic):

1. A candidate area A is *valid* when
   - it is not the area being freed and not an area already reserved by the tree (the
     target of another pending recovery placement);
   - it overlaps no goal area (the areas of C_goal) and no reserved area;
   - no object except the held one lies within ``A.radius + radius`` of A's centre, i.e.
     the disc does not overlap any object's current place.
2. Among the demonstration's free areas that are valid, take the one nearest to the robot
   (planar distance; ties broken by the order the areas were given).
3. In a recovery that needs the hand free first (the robot holds an object while the area
   it must place it in is blocked), the held object's area is chosen first, then one per
   blocker, each by rule 2 with the earlier choices reserved.
4. When none is left, search rings around the workspace: centre = mean of every known area
   and object position; first ring radius = largest distance from the centre to any of
   them + 2·radius, then growing by 2·radius; 16 candidates per ring (every 22.5°, starting
   on +x). On the first ring that has valid candidates, take the one nearest to the robot
   (ties: smaller angle). It is named ``free_auto<k>``. At most 8 rings are searched.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

from tamp.world.geometry import Area, Point
from tamp.world.state import WorldState

RING_CANDIDATES = 16
MAX_RINGS = 8


def is_valid(
    area: Area,
    state: WorldState,
    *,
    avoid: Iterable[Area],
    excluded: set[str],
    radius: float,
) -> bool:
    """Rule 1: ``area`` does not affect the task in ``state``."""
    if area.name in excluded:
        return False
    for other in avoid:
        if other.name != area.name and area.overlaps(other):
            return False
    for uid, obj in state.objects.items():
        if uid == state.held:
            continue
        if area.pos.planar_distance(obj.pos) < area.radius + radius - 1e-9:
            return False
    return True


def choose_free_area(
    state: WorldState,
    *,
    candidates: Sequence[str],
    goal_areas: Iterable[str],
    freeing: str | None = None,
    reserved: Iterable[str] = (),
    radius: float | None = None,
    auto_index: int = 1,
) -> Area | None:
    """Pick l_free by the module's rule; returns None only when even the rings are full.

    ``candidates`` are area names known to ``state`` (the demonstration's free areas, in
    file order); ``radius`` defaults to the largest goal-area radius.
    """
    goals = [state.area(g) for g in goal_areas if g in state.areas]
    reserved = set(reserved)
    excluded = set(reserved)
    if freeing is not None:
        excluded.add(freeing)
    avoid = goals + [state.area(r) for r in reserved if r in state.areas]
    if freeing is not None and freeing in state.areas:
        avoid.append(state.area(freeing))
    if radius is None:
        radius = max((a.radius for a in goals), default=0.15)
    robot = state.robot.pos

    best: tuple[float, int, Area] | None = None
    for k, name in enumerate(candidates):
        if name not in state.areas:
            continue
        area = state.area(name)
        if not is_valid(area, state, avoid=avoid, excluded=excluded, radius=radius):
            continue
        key = (robot.planar_distance(area.pos), k, area)
        if best is None or key[:2] < best[:2]:
            best = key
    if best is not None:
        return best[2]
    return ring_search(state, avoid=avoid, excluded=excluded, radius=radius, index=auto_index)


def ring_search(
    state: WorldState,
    *,
    avoid: list[Area],
    excluded: set[str],
    radius: float,
    index: int = 1,
) -> Area | None:
    """Rule 3: candidates on rings around the workspace."""
    points = [a.pos for a in state.areas.values()] + [o.pos for o in state.objects.values()]
    if not points:
        points = [state.robot.pos]
    cx = sum(p.x for p in points) / len(points)
    cy = sum(p.y for p in points) / len(points)
    centre = Point(cx, cy)
    r0 = max(centre.planar_distance(p) for p in points) + 2.0 * radius
    avoid = avoid + list(state.areas.values())
    robot = state.robot.pos
    name = f"free_auto{index}"
    while name in state.areas:
        index += 1
        name = f"free_auto{index}"
    for ring in range(MAX_RINGS):
        r = r0 + ring * 2.0 * radius
        found: list[tuple[float, int, Area]] = []
        for j in range(RING_CANDIDATES):
            angle = 2.0 * math.pi * j / RING_CANDIDATES
            pos = Point(cx + r * math.cos(angle), cy + r * math.sin(angle), 0.0)
            area = Area(name, pos, radius)
            if is_valid(area, state, avoid=avoid, excluded=excluded, radius=radius):
                found.append((robot.planar_distance(pos), j, area))
        if found:
            return min(found, key=lambda t: (t[0], t[1]))[2]
    return None
