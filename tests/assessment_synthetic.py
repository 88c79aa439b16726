"""Synthetic runs for the assessment tests: a time-history table in the format of
``ttbpipe simulate`` (docs/vehicle.md section 6) with chosen histories, and its summary."""

from __future__ import annotations

import numpy as np
import pandas as pd

SIDES = ("left", "right")
POINTS = ("front", "centre", "rear")


def synthetic_run(columns=None, *, duration_s=4.0, dt=1e-3, speed_kmh=300.0,
                  wheelsets=("car1_ws1", "car1_ws2"), p0=70e3, cars=1, extra_summary=None):
    """(table, summary): every wheel at its static load p0 (N) with no lateral force, car bodies
    at rest, then ``columns`` {name: array or function of t} replacing or adding histories.
    The summary's raw indices are the table's maxima (as a run's, over its output steps)."""
    n = int(round(duration_s / dt))
    t = dt * np.arange(n)
    v = speed_kmh / 3.6
    cols = {"time_s": t, "x_lead_m": 100.0 + v * t}
    for ws in wheelsets:
        for side in SIDES:
            cols[f"{ws}_{side}_P_N"] = np.full(n, p0)
            cols[f"{ws}_{side}_Q_N"] = np.zeros(n)
            cols[f"{ws}_{side}_in_contact"] = np.ones(n, dtype=np.int8)
    for c in range(1, cars + 1):
        for p in POINTS:
            for a in ("az", "ay"):
                cols[f"car{c}_body_{p}_{a}_m_s2"] = np.zeros(n)
    for name, value in (columns or {}).items():
        cols[name] = np.asarray(value(t) if callable(value) else value, dtype=float)
    for ws in wheelsets:
        if f"{ws}_H_N" not in (columns or {}):
            cols[f"{ws}_H_N"] = cols[f"{ws}_left_Q_N"] + cols[f"{ws}_right_Q_N"]
        for side in SIDES:
            p, q = cols[f"{ws}_{side}_P_N"], cols[f"{ws}_{side}_Q_N"]
            cols[f"{ws}_{side}_QP"] = np.where(p > 0, np.abs(q) / np.where(p > 0, p, 1.0), 0.0)
            cols[f"{ws}_{side}_unloading"] = (p0 - p) / p0
    table = pd.DataFrame(cols)
    wheel = [f"{ws}_{s}" for ws in wheelsets for s in SIDES]
    az = [c for c in table.columns if c.endswith("_az_m_s2")]
    ay = [c for c in table.columns if c.endswith("_ay_m_s2")]
    summary = {
        "speed_kmh": speed_kmh,
        "static_wheel_load_N": {ws: [p0, p0] for ws in wheelsets},
        "max_derailment_coefficient": float(max(table[f"{w}_QP"].max() for w in wheel)),
        "max_wheel_unloading_ratio": float(max(table[f"{w}_unloading"].max() for w in wheel)),
        "max_lateral_wheelset_force_N": float(max(table[f"{ws}_H_N"].abs().max()
                                                  for ws in wheelsets)),
        "max_wheel_vertical_force_N": float(max(table[f"{w}_P_N"].max() for w in wheel)),
        "max_carbody_vertical_acc_m_s2": float(table[az].abs().max().max()),
        "max_carbody_lateral_acc_m_s2": float(table[ay].abs().max().max()),
    }
    summary.update(extra_summary or {})
    return table, summary


def fitted_amplitudes(t, y, freqs):
    """Least-squares amplitudes of sinusoids at ``freqs`` (with a constant) in y(t)."""
    basis = [np.ones_like(t)]
    for f in freqs:
        basis += [np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t)]
    coef, *_ = np.linalg.lstsq(np.column_stack(basis), y, rcond=None)
    return [float(np.hypot(coef[1 + 2 * k], coef[2 + 2 * k])) for k in range(len(freqs))]
