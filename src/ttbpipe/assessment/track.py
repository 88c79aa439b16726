"""The track under each wheel: the curve radius along a run, and limits that hold over a range of
radii.

Some running-safety limits hold on part of the network only: EN 14363's (Y/Q)lim = 0.8 for
R >= 250 m [M], GB/T 5599-2019's derailment coefficient 0.8 on tangent track and R > 400 m [V]
(docs/reference/standards.md). A run on a layout with curves (``simulation.layout``,
:mod:`ttbpipe.vehicle.curving`) takes each wheel over tangent track, clothoids and arcs, so a
profile evaluates such an index per wheel over the part of the run where that wheel is in the
limit's range (:class:`RadiusRange`), as a test evaluates each track section against the limit
of its zone. The rest of the run is reported beside it, and assessed only against a limit the
user supplies for it (the profiles' ``*_small_radius`` options): the standards' values there are
not in docs/reference/standards.md, and ttbpipe does not invent them.

Where a wheel is: the run's table gives the leading wheelset's x (``x_lead_m``) and the summary
each wheelset's constant offset from it (``wheelset_offset_m``, written by ``ttbpipe simulate``),
so a wheel's chainage is ``x_lead_m + offset`` in the layout's x, whichever way the train runs.
The radius there is ``1 / |kappa|`` of the layout's piecewise-linear curvature (arcs at R,
clothoids from infinity down to R), infinite on tangent track.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from .base import governing
from .processing import percentile_where

TANGENT = math.inf


def radius_along(layout: Mapping[str, Any] | None, x_m: np.ndarray) -> np.ndarray:
    """Curve radius (m, positive; ``inf`` on tangent track) at the chainages ``x_m`` of a
    ``simulation.layout`` section (any shape)."""
    from ..vehicle.curving import layout_knots

    x = np.asarray(x_m, dtype=float)
    knots_x, kappa, _ = layout_knots(layout)
    curvature = np.abs(np.interp(x.ravel(), knots_x, kappa)).reshape(x.shape)
    with np.errstate(divide="ignore"):
        return np.where(curvature > 0.0, 1.0 / np.where(curvature > 0.0, curvature, 1.0), TANGENT)


@dataclass(frozen=True)
class RadiusRange:
    """The radii a limit holds for: tangent track and R >= ``min_radius_m`` (``inclusive``) or
    R > ``min_radius_m``."""

    min_radius_m: float
    inclusive: bool = True

    def contains(self, radius_m: np.ndarray) -> np.ndarray:
        r = np.asarray(radius_m, dtype=float)
        return r >= self.min_radius_m if self.inclusive else r > self.min_radius_m

    def describe(self) -> str:
        return f"tangent track and R {'>=' if self.inclusive else '>'} {self.min_radius_m:g} m"

    def describe_outside(self) -> str:
        return f"R {'<' if self.inclusive else '<='} {self.min_radius_m:g} m"


def layout_of(config: Mapping[str, Any] | None) -> Mapping[str, Any] | None:
    """The ``simulation.layout`` of a run's case (None without one)."""
    return ((config or {}).get("simulation") or {}).get("layout")


def has_curves(config: Mapping[str, Any] | None) -> bool:
    """Whether a run's case lays its track in curves."""
    return bool((layout_of(config) or {}).get("curves"))


@dataclass(frozen=True)
class RadiusSplit:
    """A per-wheel statistic over the part of a run inside a limit's radius range and over the
    rest (NaN for a wheel without such a part), and the smallest radius met outside."""

    inside: np.ndarray
    outside: np.ndarray
    smallest_radius_outside_m: float

    @property
    def all_inside(self) -> bool:
        return not np.isfinite(self.outside).any()


def split_by_radius(radius_m: np.ndarray, values: np.ndarray, radius_range: RadiusRange,
                    percent: float) -> RadiusSplit:
    """The ``percent`` percentile of ``values`` (n, n_wheels) per wheel where the wheel's radius
    ``radius_m`` (n, n_wheels) is in ``radius_range`` and where it is not."""
    inside = radius_range.contains(radius_m)
    smallest = float(np.min(radius_m[~inside])) if (~inside).any() else TANGENT
    return RadiusSplit(percentile_where(values, inside, percent),
                       percentile_where(values, ~inside, percent), smallest)


def governing_by_radius(split: RadiusSplit, limit: np.ndarray | float,
                        small_radius_limit: float | None, labels: list[str],
                        radius_range: RadiusRange) -> tuple[int, float, float, str]:
    """(wheel, value, limit, note) of the largest utilisation over the wheels' parts: inside the
    range against ``limit``; outside against ``small_radius_limit`` when one is given, else not
    assessed (the note gives the largest value there). A run with no part inside the range and
    no ``small_radius_limit`` gives its largest value outside with a NaN limit."""
    n = len(labels)
    limits_inside = np.broadcast_to(np.asarray(limit, dtype=float), (n,))
    outside = (f"{radius_range.describe_outside()} (down to R = "
               f"{split.smallest_radius_outside_m:.0f} m)")
    if split.all_inside:
        i, v, lim = governing(split.inside, limits_inside, labels)
        return i, v, lim, ""
    j = int(np.nanargmax(split.outside))
    largest_out = f"{float(split.outside[j]):.4g} ({labels[j]})"
    if small_radius_limit is not None:
        values = np.concatenate([split.inside, split.outside])
        limits = np.concatenate([limits_inside, np.full(n, float(small_radius_limit))])
        keep = np.isfinite(values)
        idx = np.flatnonzero(keep)
        k, v, lim = governing(values[keep], limits[keep], [labels[m % n] for m in idx])
        part = "outside" if idx[k] >= n else "inside"
        note = (f"{radius_range.describe()}: against the limit; {outside}: against the "
                f"small-radius limit {float(small_radius_limit):g} (option); governing part: "
                f"{'the small radii' if part == 'outside' else 'the range'}")
        return int(idx[k] % n), v, lim, note
    if not np.isfinite(split.inside).any():
        note = (f"no part of the run is on {radius_range.describe()}, where the limit holds: the "
                f"value is the largest on {outside}, not assessed (give the small-radius limit "
                f"as an option to assess it)")
        return j, float(split.outside[j]), float("nan"), note
    i, v, lim = governing(split.inside, limits_inside, labels)
    note = (f"evaluated where the wheel is on {radius_range.describe()} (the limit's range); on "
            f"{outside} the largest value is {largest_out}, not assessed (give the small-radius "
            f"limit as an option to assess it)")
    return i, v, lim, note
