"""The numbers a campaign reports: success rate with its Wilson score interval, the task-time
distribution of the successful runs, failure causes with their seeds, and success by
perturbation size. Pure functions of the run records (no Ray, no Drake)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

#: Two-sided 95 % normal quantile (Φ⁻¹(0.975)).
Z95 = 1.959963984540054


def wilson_interval(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion (Wilson 1927).

    centre = (p̂ + z²/2n) / (1 + z²/n), half-width = z/(1 + z²/n) · √(p̂(1-p̂)/n + z²/4n²).
    Unlike p̂ ± z·√(p̂(1-p̂)/n) it stays inside [0, 1] and is not empty at 0 or n successes,
    which is where a good system's campaigns land. ``n = 0`` gives (0, 1): nothing known.
    """
    if n < 0 or not 0 <= successes <= n:
        raise ValueError(f"need 0 <= successes <= n, got {successes}/{n}")
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    z2 = z * z
    denom = 1.0 + z2 / n
    centre = (p + z2 / (2 * n)) / denom
    half = z / denom * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n))
    # it holds p̂; at 0 or n successes the rounding of centre -+ half can miss it by 1e-16
    # (a plot's error bar then has a negative length)
    return max(0.0, min(p, centre - half)), min(1.0, max(p, centre + half))


@dataclass(frozen=True)
class Distribution:
    """Mean, median, 90th percentile (linear interpolation), min and max of some values."""

    n: int
    mean: float | None
    median: float | None
    p90: float | None
    min: float | None
    max: float | None

    @staticmethod
    def of(values: Sequence[float]) -> Distribution:
        xs = sorted(float(v) for v in values)
        if not xs:
            return Distribution(0, None, None, None, None, None)
        return Distribution(
            len(xs), sum(xs) / len(xs), percentile(xs, 50), percentile(xs, 90), xs[0], xs[-1]
        )

    def to_json(self) -> dict:
        return {k: (v if v is None or k == "n" else round(v, 3)) for k, v in vars(self).items()}


def percentile(sorted_values: Sequence[float], q: float) -> float:
    """The ``q``-th percentile of sorted values, interpolated linearly between order
    statistics (numpy's default method)."""
    if not sorted_values:
        raise ValueError("percentile of no values")
    pos = (len(sorted_values) - 1) * q / 100.0
    lo = math.floor(pos)
    hi = min(lo + 1, len(sorted_values) - 1)
    return sorted_values[lo] + (sorted_values[hi] - sorted_values[lo]) * (pos - lo)


@dataclass(frozen=True)
class Cause:
    """One reason runs did not succeed, its status and the seeds that hit it."""

    status: str
    cause: str
    seeds: tuple[int, ...]

    def to_json(self) -> dict:
        return {
            "status": self.status,
            "cause": self.cause,
            "count": len(self.seeds),
            "seeds": list(self.seeds),
        }


def group_causes(runs: Sequence[tuple[int, str, str | None]]) -> list[Cause]:
    """Group the unsuccessful ``(seed, status, cause)`` runs by (status, cause), most
    frequent first (ties by first seed); seeds ascending."""
    groups: dict[tuple[str, str], list[int]] = {}
    for seed, status, cause in runs:
        if status == "success":
            continue
        groups.setdefault((status, cause or "(no cause given)"), []).append(seed)
    out = [Cause(s, c, tuple(sorted(seeds))) for (s, c), seeds in groups.items()]
    return sorted(out, key=lambda g: (-len(g.seeds), g.seeds[0]))


@dataclass(frozen=True)
class Bin:
    """Runs whose perturbation size lies in [lo, hi] and how many succeeded."""

    lo: float
    hi: float
    n: int
    successes: int

    @property
    def rate(self) -> float:
        return self.successes / self.n if self.n else 0.0

    def to_json(self) -> dict:
        lo, hi = wilson_interval(self.successes, self.n)
        return {
            "lo": round(self.lo, 4),
            "hi": round(self.hi, 4),
            "n": self.n,
            "successes": self.successes,
            "rate": round(self.rate, 4),
            "wilson_95": [round(lo, 4), round(hi, 4)],
        }


def success_by_size(runs: Sequence[tuple[float, bool]], bins: int = 5) -> list[Bin]:
    """Success counts in ``bins`` equal-width bins of perturbation size (empty bins are
    left out; one bin when every size is the same, e.g. all 0 without perturbations)."""
    if not runs:
        return []
    sizes = [s for s, _ in runs]
    lo, hi = min(sizes), max(sizes)
    if hi <= lo:
        return [Bin(lo, hi, len(runs), sum(ok for _, ok in runs))]
    width = (hi - lo) / bins
    counts = [[0, 0] for _ in range(bins)]
    for size, ok in runs:
        i = min(int((size - lo) / width), bins - 1)
        counts[i][0] += 1
        counts[i][1] += int(ok)
    return [Bin(lo + i * width, lo + (i + 1) * width, n, k) for i, (n, k) in enumerate(counts) if n]
