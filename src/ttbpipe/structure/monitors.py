"""Monitor points: named linear combinations of structural DOFs recorded during a run.

Each monitor (rail, slab, girder or pier point) is compiled into rows (dof, coefficient) per
direction through the same shape functions as the structure (Hermite for bending, linear for roll,
the Craig-Bampton basis for the girder), so a numba loop records it with a sparse dot product.
Column names carry units: ``<name>_<dir>_disp_mm``, ``_vel_m_s``, ``_acc_m_s2`` for z and y;
``<name>_roll_disp_mrad``, ``_vel_rad_s``, ``_acc_rad_s2`` for roll.
"""

from __future__ import annotations

import functools
import re
from collections import namedtuple
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from ..jit import kernel
from .rail_mesh import NODE_DOFS, rail_mesh
from .girder import span_slope_row
from .plan import plan_eccentricity_m
from .shape_functions import hermite_shape

QUANTITIES = {"displacement": 0, "velocity": 1, "acceleration": 2}
_SUFFIX = {("z", 0): ("disp_mm", 1e3), ("z", 1): ("vel_m_s", 1.0), ("z", 2): ("acc_m_s2", 1.0),
           ("y", 0): ("disp_mm", 1e3), ("y", 1): ("vel_m_s", 1.0), ("y", 2): ("acc_m_s2", 1.0),
           ("roll", 0): ("disp_mrad", 1e3), ("roll", 1): ("vel_rad_s", 1.0),
           ("roll", 2): ("acc_rad_s2", 1.0),
           ("slope", 0): ("mrad", 1e3), ("slope", 1): ("rad_s", 1.0),
           ("slope", 2): ("rad_s2", 1.0)}


@dataclass
class MonitorSet:
    """Compiled monitors: CSR rows over DOFs, quantity codes, column names and unit scales."""

    names: list
    ptr: np.ndarray
    dof: np.ndarray
    coef: np.ndarray
    qty: np.ndarray
    scale: np.ndarray

    @property
    def n(self) -> int:
        return len(self.names)

    def recorder(self) -> "MonitorRecorder":
        """A :class:`MonitorRecorder` of these monitors."""
        return MonitorRecorder(self.ptr, self.dof, self.coef, self.qty, self.scale,
                               np.zeros(self.n), np.zeros(self.n))


#: Monitors as a time loop records them: the compiled rows (ptr, dof, coef, qty), the unit
#: scale of each column, the values of the current step current[monitor] (scaled) and the
#: largest |value| over every step, peak[monitor] (scaled). Shared by the coupled
#: train-track-bridge loop and the structure's moving-load loop, which decimate ``current``
#: into their histories with an anti-alias filter (ttbpipe.decimation).
MonitorRecorder = namedtuple("MonitorRecorder", ["ptr", "dof", "coef", "qty", "scale", "current",
                                                 "peak"])


def no_monitors() -> MonitorRecorder:
    """A recorder without monitors (rigid track)."""
    i0, f0 = np.zeros(0, np.int64), np.zeros(0)
    return MonitorRecorder(np.zeros(1, np.int64), i0, f0, i0, f0, f0, np.zeros(0))


@kernel(creates_arrays=False)
def record_monitors(rec, disp, vel, acc):
    """Evaluate every monitor at this step: sum_j coef_j q[dof_j] with q = disp, vel or acc
    (qty 0, 1, 2), times its unit scale, into ``rec.current``; update ``rec.peak``. Returns the
    largest |unscaled| displacement monitor value (NaN if one is NaN), for the loops' blow-up
    checks."""
    largest = 0.0
    for m in range(rec.qty.shape[0]):
        s = 0.0
        for j in range(rec.ptr[m], rec.ptr[m + 1]):
            d = rec.dof[j]
            if rec.qty[m] == 0:
                s += rec.coef[j] * disp[d]
            elif rec.qty[m] == 1:
                s += rec.coef[j] * vel[d]
            else:
                s += rec.coef[j] * acc[d]
        if rec.qty[m] == 0 and not abs(s) <= largest:
            largest = abs(s)
        s *= rec.scale[m]
        if abs(s) > rec.peak[m]:
            rec.peak[m] = abs(s)
        rec.current[m] = s
    return largest


def _beam_rows(dof_a: int, dof_b: int, L: float, xi: float) -> dict[str, tuple]:
    N = hermite_shape(xi, L)
    return {"z": ([dof_a, dof_a + 1, dof_b, dof_b + 1], N),
            "y": ([dof_a + 2, dof_a + 3, dof_b + 2, dof_b + 3], N),
            "roll": ([dof_a + 4, dof_b + 4], np.array([1 - xi, xi]))}


def point_rows(model, spec: Mapping[str, Any]) -> dict[str, tuple]:
    """{direction: (dofs, coefs)} of one monitor spec (see docs/structure.md, "Monitors")."""
    kind = spec.get("kind")
    name = spec.get("name", "?")
    lay = model.layout
    if kind == "rail":
        if model.packed.n_rails == 0:
            raise ValueError(f"monitor {name}: the structure has no rails")
        x = float(spec["x_m"])
        rail = int(spec.get("rail", 0))
        n_rails = int(model.packed.n_rails)
        if not 0 <= rail < n_rails or not lay.rail_x[0] <= x <= lay.rail_x[-1]:
            raise ValueError(f"monitor {name}: rail {rail} at x={x} m is outside the rails "
                             f"[{lay.rail_x[0]}, {lay.rail_x[-1]}] m or rail is not in "
                             f"0..{n_rails - 1}")
        mesh = rail_mesh(model.packed, 0.0)
        h = mesh.dx
        e = min(int(x / h), lay.rail_x.size - 2)
        a = int(mesh.dof0[rail]) + NODE_DOFS * e
        return _beam_rows(a, a + NODE_DOFS, h, (x - lay.rail_x[e]) / h)
    if kind == "slab":
        x = float(spec["x_m"])
        track = int(spec.get("track", 0))
        se = model.slab_elements
        on = (se[:, 0] <= x) & (x <= se[:, 1]) if se.size else np.zeros(0, bool)
        if model.slab_element_track is not None and se.size:
            on &= model.slab_element_track == track
        inside = np.flatnonzero(on)
        if len(inside) == 0:
            raise ValueError(f"monitor {name}: no slab of track {track} at x={x} m")
        j = int(inside[0])
        a = int(model.slab_element_node0[j])
        L = se[j, 1] - se[j, 0]
        return _beam_rows(a, a + 5, L, (x - se[j, 0]) / L)
    if kind == "girder":
        s = int(spec.get("span", 0))
        if not 0 <= s < len(model.spans):
            raise ValueError(f"monitor {name}: span {s} outside 0..{len(model.spans) - 1}")
        red = model.spans[s]
        x = float(spec["x_m"]) if "x_m" in spec else red.start_m + float(
            spec.get("position", 0.5)) * red.length_m
        if not red.start_m <= x <= red.start_m + red.length_m:
            raise ValueError(f"monitor {name}: x={x} m is not on span {s}")
        rz, ry, rr = red.rows_at(x)
        idx = np.arange(model.dof_info["span_dof0"][s], model.dof_info["span_dof0"][s] + red.n)
        # a point of the cross-section off the shear centre, as the bearings (z + e roll) and
        # the CA mortar (y - h roll) see the girder: e to the left (rail 0's side), h upwards
        e = float(spec.get("lateral_offset_m", 0.0))
        h = (float(model.config["girder"]["deck_height_m"]) if spec.get("deck_surface")
             else float(spec.get("height_m", 0.0)))
        # slope: dz/dx of the girder axis (the end rotation at the supports, EN 1991-2 6.5.4)
        return {"z": (idx, rz + e * rr), "y": (idx, ry - h * rr), "roll": (idx, rr),
                "slope": (idx, span_slope_row(red, x))}
    if kind == "pier":
        p = int(spec.get("pier", 0))
        if not 0 <= p < model.dof_info["n_piers"]:
            raise ValueError(f"monitor {name}: pier {p} outside 0..{model.dof_info['n_piers'] - 1}")
        d = model.dof_info["pier_top_dof0"][p]        # top: y, z, roll
        return {"y": ([d], np.ones(1)), "z": ([d + 1], np.ones(1)), "roll": ([d + 2], np.ones(1))}
    raise ValueError(f"monitor {name}: kind {kind!r}; expected rail | slab | girder | pier")


def compile_monitors(model, specs: Sequence[Mapping[str, Any]]) -> MonitorSet:
    """Compile monitor specs into a :class:`MonitorSet`."""
    names, ptr, dof, coef, qty, scale = [], [0], [], [], [], []
    seen = set()
    for spec in specs:
        name = spec.get("name")
        if not name or name in seen:
            raise ValueError(f"monitor {spec}: every monitor needs a unique 'name'")
        seen.add(name)
        rows = point_rows(model, spec)
        for direction in spec.get("directions", ["z"]):
            if direction not in rows:
                raise ValueError(f"monitor {name}: direction {direction!r}; expected one of "
                                 f"{sorted(rows)}")
            for q in spec.get("quantities", ["displacement", "acceleration"]):
                if q not in QUANTITIES:
                    raise ValueError(f"monitor {name}: quantity {q!r}; expected one of "
                                     f"{list(QUANTITIES)}")
                code = QUANTITIES[q]
                suffix, sc = _SUFFIX[(direction, code)]
                d, c = rows[direction]
                names.append(f"{name}_{direction}_{suffix}")
                dof.extend(np.asarray(d, dtype=np.int64)); coef.extend(np.asarray(c, float))
                ptr.append(len(dof)); qty.append(code); scale.append(sc)
    return MonitorSet(names, np.array(ptr, np.int64), np.array(dof, np.int64),
                      np.array(coef, float), np.array(qty, np.int64), np.array(scale, float))


_DECK_COLUMN = re.compile(r"^deck_(?:track\d+_)?(left|right)_span(\d+)_mid_([zy])_"
                          r"(acc_m_s2|disp_mm)$")
_GIRDER_COLUMN = re.compile(r"^girder_span(\d+)_mid_([zy])_(acc_m_s2|disp_mm)$")


def deck_columns(columns, axis: str, quantity: str = "acc_m_s2") -> dict[int, list[str]]:
    """{span (1-based): history columns of the deck at midspan} for ``axis`` z | y.

    The deck-surface monitors under the rails (:func:`default_monitors`; under every track's
    rails on a double-track deck) where the run has them, else the girder's shear centre (runs
    with their own monitor lists).
    """
    # a run's table is asked several times (its indices, then each standard), by a few hundred
    # names: matched once per set of names (a DataFrame's Index as a list first: iterating the
    # Index itself is ten times slower)
    names = columns.tolist() if hasattr(columns, "tolist") else list(columns)
    found = _deck_columns(tuple(names), axis, quantity)
    return {span: list(cols) for span, cols in found}


@functools.lru_cache(maxsize=16)
def _deck_columns(columns: tuple[str, ...], axis: str, quantity: str):
    deck: dict[int, list[str]] = {}
    girder: dict[int, list[str]] = {}
    for c in columns:
        m = _DECK_COLUMN.match(c)
        if m and m.group(3) == axis and m.group(4) == quantity:
            deck.setdefault(int(m.group(2)), []).append(c)
        m = _GIRDER_COLUMN.match(c)
        if m and m.group(2) == axis and m.group(3) == quantity:
            girder.setdefault(int(m.group(1)), []).append(c)
    return tuple((span, tuple(cols)) for span, cols in sorted((deck or girder).items()))


def deck_monitor_name(side: str, span: int, track: int | None = None) -> str:
    """Name of the default deck monitor under rail ``side`` (left | right) of 1-based ``span``
    (of 1-based ``track`` on a double-track deck: ``deck_track2_left_span1_mid``)."""
    return f"deck_{side}_span{span}_mid" if track is None else \
        f"deck_track{track}_{side}_span{span}_mid"


def default_monitors(model) -> list[dict]:
    """At every span's midspan: the left rail, the slab, the girder's shear centre and the deck
    surface under each rail, at the track's offset ``girder.track_offset_m`` (vertical under
    both, lateral under the left: the deck surface's lateral motion is the same under both)
    and, with ``girder.deck_width_m``, at both deck edges (vertical); every pier. On a span
    under a curve the deck monitors under the rails follow the track's centre line at mid-span
    (its offset from the straight girder's axis, :func:`_mid_span_plan_offset`).

    On a double-track deck the rail, slab and deck monitors are per track, named with the
    1-based track: ``rail_track1_left_span1_mid`` (both rails of every track),
    ``slab_track2_span1_mid``, ``deck_track1_right_span1_mid`` (under each rail of every
    track, at its offset ``girder.track_offsets_m``); the girder, deck-edge and pier monitors
    are the structure's, named as on a single track."""
    if model.n_tracks > 1:
        return _double_track_monitors(model)
    out = []
    half_gauge = 0.5 * float(model.config["fastener"]["rail_centre_distance_m"])
    track = float(model.layout.track_offsets_m[0])
    deck_width = model.config["girder"].get("deck_width_m")
    for s, red in enumerate(model.spans):
        x = red.start_m + 0.5 * red.length_m
        e_mid = track + _mid_span_plan_offset(model, red)
        if model.packed.n_rails:
            out.append({"name": f"rail_left_span{s + 1}_mid", "kind": "rail", "rail": 0,
                        "x_m": x, "directions": ["z", "y"]})
        if model.slab_elements.size and np.any((model.slab_elements[:, 0] <= x)
                                               & (x <= model.slab_elements[:, 1])):
            out.append({"name": f"slab_span{s + 1}_mid", "kind": "slab", "x_m": x,
                        "directions": ["z", "y"]})
        out.append({"name": f"girder_span{s + 1}_mid", "kind": "girder", "span": s,
                    "position": 0.5, "directions": ["z", "y"]})
        for side, e, directions in (("left", e_mid + half_gauge, ["z", "y"]),
                                    ("right", e_mid - half_gauge, ["z"])):
            out.append({"name": deck_monitor_name(side, s + 1), "kind": "girder", "span": s,
                        "position": 0.5, "deck_surface": True, "lateral_offset_m": e,
                        "directions": directions})
        if deck_width is not None:
            for side, e in (("left", 0.5 * deck_width), ("right", -0.5 * deck_width)):
                out.append({"name": f"deck_edge_{side}_span{s + 1}_mid", "kind": "girder",
                            "span": s, "position": 0.5, "deck_surface": True,
                            "lateral_offset_m": e, "directions": ["z"]})
    out += _pier_monitors(model)
    return out


def _mid_span_plan_offset(model, red) -> float:
    """Offset (m, + left) of a track's centre line from the straight girder's axis at the
    span's mid-point under a curve in plan (:mod:`ttbpipe.structure.plan`); 0.0 off curves."""
    return float(plan_eccentricity_m(model.plan, red.start_m, red.length_m,
                                     red.start_m + 0.5 * red.length_m,
                                     model.config["girder"]["placement_on_curves"]))


def _pier_monitors(model) -> list[dict]:
    return [{"name": f"pier{p + 1}", "kind": "pier", "pier": p, "directions": ["z", "y"]}
            for p in range(model.dof_info["n_piers"])]


def _double_track_monitors(model) -> list[dict]:
    """:func:`default_monitors` of a double-track deck (its docstring)."""
    out = []
    half_gauge = 0.5 * float(model.config["fastener"]["rail_centre_distance_m"])
    deck_width = model.config["girder"].get("deck_width_m")
    se = model.slab_elements
    for s, red in enumerate(model.spans):
        x = red.start_m + 0.5 * red.length_m
        out.append({"name": f"girder_span{s + 1}_mid", "kind": "girder", "span": s,
                    "position": 0.5, "directions": ["z", "y"]})
        e_plan = _mid_span_plan_offset(model, red)
        for t, e_track in enumerate(model.layout.track_offsets_m):
            e_track = e_track + e_plan
            tag = f"track{t + 1}"
            for side, rail in (("left", 2 * t), ("right", 2 * t + 1)):
                if model.packed.n_rails:
                    out.append({"name": f"rail_{tag}_{side}_span{s + 1}_mid", "kind": "rail",
                                "rail": rail, "x_m": x, "directions": ["z", "y"]})
            if se.size and np.any((se[:, 0] <= x) & (x <= se[:, 1])
                                  & (model.slab_element_track == t)):
                out.append({"name": f"slab_{tag}_span{s + 1}_mid", "kind": "slab", "x_m": x,
                            "track": t, "directions": ["z", "y"]})
            for side, e, directions in (("left", e_track + half_gauge, ["z", "y"]),
                                        ("right", e_track - half_gauge, ["z"])):
                out.append({"name": deck_monitor_name(side, s + 1, t + 1), "kind": "girder",
                            "span": s, "position": 0.5, "deck_surface": True,
                            "lateral_offset_m": e, "directions": directions})
        if deck_width is not None:
            for side, e in (("left", 0.5 * deck_width), ("right", -0.5 * deck_width)):
                out.append({"name": f"deck_edge_{side}_span{s + 1}_mid", "kind": "girder",
                            "span": s, "position": 0.5, "deck_surface": True,
                            "lateral_offset_m": e, "directions": ["z"]})
    return out + _pier_monitors(model)
