"""A coupled run as the profiles read it: histories by wheel, wheelset, car and span.

The time-history table of ``ttbpipe simulate`` (docs/vehicle.md section 6, docs/structure.md
section 6; :mod:`ttbpipe.simulation.outputs`) has ``time_s`` and ``x_lead_m``, then per wheel
``carC_wsJ_{left,right}_{P_N,Q_N,in_contact,QP,unloading}``, per wheelset ``carC_wsJ_H_N``, per
car ``carC_body_{front,centre,rear}_{az,ay}_m_s2`` and the structure monitors by name
(``girder_spanS_mid_z_acc_m_s2``, ...). P is the vertical and Q the lateral force of the rail on
the wheel (+ left), H = Q_left + Q_right. The summary (the provenance's ``summary``) holds the raw
indices by their registry names (:mod:`ttbpipe.response_indices`), the train speed
``speed_kmh``, the static wheel loads ``static_wheel_load_N`` {wheelset: [left, right]} and
each wheelset's x relative to the leading one, ``wheelset_offset_m`` (needed on curves:
:mod:`.track`).

:class:`RunData` parses these once: the profiles then index arrays, not column names. The
column patterns below are the table's documented format; nothing here recomputes the run.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Mapping

import numpy as np
import pandas as pd

from .processing import sample_interval
from .track import TANGENT, has_curves, layout_of, radius_along

SIDES = ("left", "right")
_BODY = re.compile(r"^car(\d+)_body_(front|centre|rear)_(az|ay)_m_s2$")
_GIRDER = re.compile(r"^girder_span(\d+)_mid_z_(acc_m_s2|disp_mm)$")


@dataclass
class RunData:
    """The histories and facts of one run the profiles need (SI units)."""

    table: pd.DataFrame
    summary: Mapping[str, Any]
    config: Mapping[str, Any] | None = None
    wheelsets: list[str] = field(init=False)
    _carbody: dict = field(init=False, default_factory=dict, repr=False)
    _filtered: dict = field(init=False, default_factory=dict, repr=False)

    def __post_init__(self):
        if "time_s" not in self.table.columns:
            raise ValueError("the history table has no time_s column (not a ttbpipe simulate "
                             "result?)")
        loads = self.summary.get("static_wheel_load_N")
        if not isinstance(loads, Mapping) or not loads:
            raise ValueError("the summary has no static_wheel_load_N {wheelset: [left, right]} "
                             "(a coupled run's summary carries it)")
        self.wheelsets = list(loads)
        missing = [f"{ws}_{s}_{q}" for ws in self.wheelsets for s in SIDES for q in ("P_N", "Q_N")
                   if f"{ws}_{s}_{q}" not in self.table.columns]
        if missing:
            raise ValueError(f"the history table lacks wheel force columns {missing[:4]}"
                             f"{' ...' if len(missing) > 4 else ''}")
        if "speed_kmh" not in self.summary:
            raise ValueError("the summary has no speed_kmh")

    # -- facts of the run ---------------------------------------------------------------
    @cached_property
    def dt_s(self) -> float:
        """Output interval of the histories."""
        return sample_interval(self.table["time_s"].to_numpy(float))

    @property
    def speed_m_s(self) -> float:
        return float(self.summary["speed_kmh"]) / 3.6

    @property
    def speed_kmh(self) -> float:
        return float(self.summary["speed_kmh"])

    @cached_property
    def direction(self) -> int:
        """+1 when the train runs towards +x, -1 towards -x (from ``x_lead_m``; +1 without it)."""
        if "x_lead_m" not in self.table.columns:
            return 1
        x = self.table["x_lead_m"].to_numpy(float)
        return -1 if x[-1] < x[0] else 1

    @cached_property
    def x_m(self) -> np.ndarray:
        """Position axis of the histories: the leading wheelset's chainage along its direction of
        travel (m; ``direction`` x ``x_lead_m``, increasing for a train running either way), else
        V t. Every wheel is at a constant offset from it, so windows along it are windows along
        the track for every wheel."""
        if "x_lead_m" in self.table.columns:
            return self.direction * self.table["x_lead_m"].to_numpy(float)
        return self.speed_m_s * self.table["time_s"].to_numpy(float)

    @cached_property
    def static_wheel_load_N(self) -> np.ndarray:
        """(n_wheelsets, 2) static wheel loads P0 = Q0 (left, right) of the static equilibrium."""
        return np.array([self.summary["static_wheel_load_N"][ws] for ws in self.wheelsets],
                        dtype=float)

    @cached_property
    def has_curves(self) -> bool:
        """Whether the run's case (``config``) lays the track in curves (``simulation.layout``)."""
        return has_curves(self.config)

    @cached_property
    def wheel_offset_m(self) -> np.ndarray:
        """(n_wheels,) x of each wheel relative to ``x_lead_m`` (the summary's
        ``wheelset_offset_m``; both wheels of a wheelset alike)."""
        offsets = self.summary.get("wheelset_offset_m")
        if not isinstance(offsets, Mapping) or any(ws not in offsets for ws in self.wheelsets):
            raise ValueError(
                "the run's case has curves (simulation.layout), but its summary has no "
                "wheelset_offset_m {wheelset: x offset from x_lead_m} for every wheelset, so "
                "the track under each wheel is unknown: rerun it with this version of ttbpipe "
                "simulate, which records the offsets")
        return np.repeat([float(offsets[ws]) for ws in self.wheelsets], len(SIDES))

    def wheel_radius_m(self, lead_travel_m: np.ndarray) -> np.ndarray:
        """(len(lead_travel_m), n_wheels) curve radius under each wheel (``inf`` on tangent
        track) when the leading wheelset is at ``lead_travel_m`` of :attr:`x_m`
        (:func:`.track.radius_along` at x = direction x travel + the wheel's offset)."""
        lead = np.asarray(lead_travel_m, dtype=float)
        if not self.has_curves:
            return np.full((lead.size, len(self.wheel_labels)), TANGENT)
        lead_x = self.direction * lead
        return radius_along(layout_of(self.config), lead_x[:, None] + self.wheel_offset_m[None, :])

    def raw(self, name: str) -> float:
        """A raw index of the summary by its registry name (NaN when the run has none)."""
        value = self.summary.get(name)
        return float(value) if isinstance(value, (int, float)) else float("nan")

    # -- histories ----------------------------------------------------------------------
    @cached_property
    def column_names(self) -> list[str]:
        """The table's column names as a list, for the profiles' pattern matches (iterating a
        pandas ``Index`` of strings costs ten times more than its list)."""
        return self.table.columns.tolist()

    def read_columns(self, names: list[str]) -> np.ndarray:
        """(n, len(names)) the table's columns ``names`` as floats, column-major."""
        # by position in one take (half the time of reading column by column), into the
        # column-major layout DataFrame.to_numpy gives, so that reductions along the rows
        # sum in the same order
        positions = self.table.columns.get_indexer(names)
        if np.any(positions < 0):
            raise KeyError(f"the history table has no column {names[int(np.argmin(positions))]}")
        out = np.empty((len(self.table), len(names)), order="F")
        out[:] = self.table.iloc[:, positions].to_numpy(float)
        return out

    @cached_property
    def wheel_labels(self) -> list[str]:
        """'carC_wsJ_left', ... in the column order of :attr:`P_N`."""
        return [f"{ws}_{s}" for ws in self.wheelsets for s in SIDES]

    @cached_property
    def P_N(self) -> np.ndarray:
        """(n, n_wheels) vertical wheel-rail forces, wheels as :attr:`wheel_labels`."""
        return self.read_columns([f"{w}_P_N" for w in self.wheel_labels])

    @cached_property
    def Q_N(self) -> np.ndarray:
        """(n, n_wheels) lateral wheel-rail forces (+ left)."""
        return self.read_columns([f"{w}_Q_N" for w in self.wheel_labels])

    @cached_property
    def in_contact(self) -> np.ndarray:
        """(n, n_wheels) bool: the wheel is on the rail (all True for tables without the flag)."""
        names = [f"{w}_in_contact" for w in self.wheel_labels]
        if all(n in self.table.columns for n in names):
            return self.read_columns(names) > 0.5
        return np.ones(self.P_N.shape, dtype=bool)

    @cached_property
    def wheel_static_N(self) -> np.ndarray:
        """(n_wheels,) static loads in the order of :attr:`wheel_labels`."""
        return self.static_wheel_load_N.reshape(-1)

    @cached_property
    def wheel_side_sign(self) -> np.ndarray:
        """(n_wheels,) +1 for right wheels, -1 for left: sign x Q is positive when the rail pushes
        the wheel's flange away from its rail (flange-climbing sense; Q is + left)."""
        return np.tile([-1.0, 1.0], len(self.wheelsets))

    @cached_property
    def H_N(self) -> np.ndarray:
        """(n, n_wheelsets) lateral wheelset forces H = Q_left + Q_right (sum Y)."""
        names = [f"{ws}_H_N" for ws in self.wheelsets]
        if all(n in self.table.columns for n in names):
            return self.read_columns(names)
        q = self.Q_N
        return q[:, 0::2] + q[:, 1::2]

    def filtered(self, filt, quantity: str) -> np.ndarray:
        """The wheel-force history ``quantity`` ('P_N', 'Q_N' or 'H_N') through ``filt`` (a
        :class:`~.processing.Butterworth`), filtered once per run: EN 14363 and GB/T 5599 filter
        the same forces with the same low-pass. Read-only (slice or copy it)."""
        key = (filt, quantity)
        if key not in self._filtered:
            out = filt.apply(getattr(self, quantity), self.dt_s)
            out.flags.writeable = False
            self._filtered[key] = out
        return self._filtered[key]

    @cached_property
    def carbody_columns(self) -> dict[tuple[int, str, str], str]:
        """{(car, point, 'az' | 'ay'): column} of the car-body floor accelerations."""
        out = {}
        for c in self.column_names:
            m = _BODY.match(c)
            if m:
                out[(int(m.group(1)), m.group(2), m.group(3))] = c
        return dict(sorted(out.items()))

    def carbody(self, axis: str) -> tuple[list[str], np.ndarray]:
        """(labels 'carC_point', (n, k) accelerations) along 'az' (vertical) or 'ay' (lateral);
        read once per axis (several profiles ask), like the other histories."""
        if axis not in self._carbody:
            keys = [k for k in self.carbody_columns if k[2] == axis]
            if not keys:
                raise ValueError(f"the history table has no car-body {axis} columns "
                                 "(carC_body_<point>_{az,ay}_m_s2)")
            labels = [f"car{c}_{p}" for c, p, _ in keys]
            columns = [self.carbody_columns[k] for k in keys]
            self._carbody[axis] = (labels, self.read_columns(columns))
        labels, values = self._carbody[axis]
        return list(labels), values

    def girder(self, quantity: str) -> dict[int, np.ndarray]:
        """{span (1-based): midspan vertical history at the girder's shear centre} for 'acc_m_s2'
        or 'disp_mm'."""
        out = {}
        for c in self.column_names:
            m = _GIRDER.match(c)
            if m and m.group(2) == quantity:
                out[int(m.group(1))] = self.table[c].to_numpy(float)
        return dict(sorted(out.items()))

    def deck_acceleration(self) -> dict[int, list[np.ndarray]]:
        """{span (1-based): midspan vertical deck accelerations}: under each rail at the deck
        surface where the run recorded it, else at the shear centre
        (:func:`ttbpipe.structure.monitors.deck_columns`)."""
        from ..structure.monitors import deck_columns

        return {s: [self.table[c].to_numpy(float) for c in cols]
                for s, cols in deck_columns(self.column_names, "z").items()}
