"""Pluggable edge weights for the RG search (§IV-B2: distance, time, success rate).

Achieving a goal means: drive from where the robot is to the object, pick it, carry it to
the goal area, place it. Every model here is affine in the metres driven,
``cost = per_metre · (approach + carry) + per_goal``, which keeps the A* heuristic
admissible for all of them:

* ``distance`` — metres driven (per_metre = 1).
* ``time`` — seconds: metres / base speed + two MoveTo, one Pick, one Place duration.
* ``success`` — −log of the probability that every action succeeds: Pick and Place rates
  per action, the MoveTo rate per metre driven (a longer drive is likelier to fail).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from tamp.world.actions import Domain
from tamp.world.geometry import Point

COST_MODELS = ("distance", "time", "success")

Metric = Callable[[Point, Point], float]


def planar(a: Point, b: Point) -> float:
    """Default metric: straight-line distance on the floor."""
    return a.planar_distance(b)


@dataclass(frozen=True)
class CostModel:
    """``per_metre · metres + per_goal`` for each achieved goal."""

    name: str
    per_metre: float
    per_goal: float
    metric: Metric = planar

    @staticmethod
    def of(name: str, domain: Domain, metric: Metric = planar) -> CostModel:
        def dur(t: str) -> float:
            return domain.templates[t].duration if t in domain.templates else 0.0

        def nlog(t: str) -> float:
            sr = domain.templates[t].success_rate if t in domain.templates else 1.0
            return -math.log(sr)

        if name == "distance":
            return CostModel(name, 1.0, 0.0, metric)
        if name == "time":
            per_goal = 2 * dur("MoveTo") + dur("Pick") + dur("Place")
            return CostModel(name, 1.0 / domain.base_speed, per_goal, metric)
        if name == "success":
            return CostModel(name, nlog("MoveTo"), nlog("Pick") + nlog("Place"), metric)
        raise ValueError(f"unknown cost model {name!r} (known: {', '.join(COST_MODELS)})")
