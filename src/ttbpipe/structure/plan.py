"""A curved track on straight spans: the track's eccentricity on the girders from the curve in plan.

Simply supported girders are straight between their bearings; on a curve the track follows the
curve across them, so its centre line departs from the girder's axis by the curve's offset from
the span's chord, ``d(x) = y(x) - [y_a + (y_b - y_a) (x - x_a) / L]`` (y: the centre line's
lateral offset, :func:`ttbpipe.vehicle.curving.centreline_offset`; a, b: the span's bearings).
On a circular arc of radius R this is the parabola ``-x' (L - x') / (2 R)`` (x' from the span's
start; + left, a left-hand curve bows to the right of its chord), whose largest value is the
versine ``f = L^2 / (8 R)``: 3.2 cm for a 32 m span on R = 4000 m, 13 cm on R = 1000 m.

Where the girder's axis lies relative to the chord is ``girder.placement_on_curves``:

* ``split_versine`` (default): the axis is moved towards the outside of the curve by half the
  mid-span offset, so that the track runs f/2 inside the axis over the bearings and f/2 outside
  it at mid-span. This halves the largest eccentricity a straight girder must carry (f/2
  instead of f), and a uniform load's torque on the span nearly cancels (its resultant is
  q f L / 6 instead of 2 q f L / 3): of all straight axes it makes the largest eccentricity
  smallest, and its effect on the girder is the smaller of the two.
* ``chord``: the axis on the chord between the track's centre line over the two bearings.

Either is added to the track's own offset (``girder.track_offset_m`` / ``track_offsets_m``) at
every CA quadrature point of the span (:func:`ttbpipe.structure.assembly._ca_deck_rows`), and at
the deck monitors under the rails. Spans without curvature get no term at all, so a layout whose
curves stay off the bridge builds the structure of tangent track bit for bit.
"""

from __future__ import annotations

import numpy as np

#: Where a straight girder's axis lies under a curved track (module docstring).
PLACEMENTS = ("split_versine", "chord")


def span_is_curved(plan: tuple[np.ndarray, np.ndarray] | None, start_m: float,
                   length_m: float) -> bool:
    """Whether the curvature (piecewise linear between the ``plan`` knots) is nonzero anywhere
    on the span."""
    if plan is None:
        return False
    xs, ks = plan
    end_m = start_m + length_m
    inside = ks[(xs > start_m) & (xs < end_m)]
    return bool(np.any(np.interp([start_m, end_m], xs, ks) != 0.0) or np.any(inside != 0.0))


def plan_eccentricity_m(plan: tuple[np.ndarray, np.ndarray] | None, start_m: float,
                        length_m: float, x, placement: str = PLACEMENTS[0]) -> np.ndarray:
    """Lateral offset (m, + left) of the track's centre line from the axis of the straight
    girder spanning ``start_m`` .. ``start_m + length_m``, at chainage ``x`` on it, for the
    curvature knots ``plan`` (:func:`ttbpipe.vehicle.curving.plan_knots`) and the girder's
    ``placement`` (:data:`PLACEMENTS`, module docstring). Exactly 0 on a span without
    curvature."""
    if placement not in PLACEMENTS:
        raise ValueError(f"structure.girder.placement_on_curves {placement!r}; expected one of "
                         f"{', '.join(PLACEMENTS)}")
    x = np.asarray(x, dtype=float)
    if not span_is_curved(plan, start_m, length_m):
        return np.zeros(x.shape)
    from ..vehicle.curving import centreline_offset

    xs, ks = plan
    y_a, y_b = centreline_offset(xs, ks, np.array([start_m, start_m + length_m]))

    def off_chord(at):
        return centreline_offset(xs, ks, at) - y_a - (y_b - y_a) * (at - start_m) / length_m

    offset = off_chord(x)
    if placement == "split_versine":
        offset = offset - 0.5 * off_chord(np.asarray(start_m + 0.5 * length_m))
    return offset
