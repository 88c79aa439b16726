"""Monitor points: named linear combinations of structural DOFs recorded during a run.

Each monitor (rail, slab, girder or pier point) is compiled into rows (dof, coefficient) per
direction through the same shape functions as the structure (Hermite for bending, linear for roll,
the Craig-Bampton basis for the girder), so a numba loop records it with a sparse dot product.
Column names carry units: ``<name>_<dir>_disp_mm``, ``_vel_m_s``, ``_acc_m_s2`` for z and y;
``<name>_roll_disp_mrad``, ``_vel_rad_s``, ``_acc_rad_s2`` for roll.
"""

from __future__ import annotations

from collections import namedtuple
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np
from numba import njit

from .rail_mesh import NODE_DOFS, rail_mesh
from .shape_functions import hermite_shape

QUANTITIES = {"displacement": 0, "velocity": 1, "acceleration": 2}
_SUFFIX = {("z", 0): ("disp_mm", 1e3), ("z", 1): ("vel_m_s", 1.0), ("z", 2): ("acc_m_s2", 1.0),
           ("y", 0): ("disp_mm", 1e3), ("y", 1): ("vel_m_s", 1.0), ("y", 2): ("acc_m_s2", 1.0),
           ("roll", 0): ("disp_mrad", 1e3), ("roll", 1): ("vel_rad_s", 1.0),
           ("roll", 2): ("acc_rad_s2", 1.0)}


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


@njit(cache=True)
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
