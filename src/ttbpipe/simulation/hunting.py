"""Hunting in the time domain: the coupled loop's own vehicle on rigid straight track, disturbed.

A case of one or more cars on rigid, perfect track (``simulation.track: rigid``, no
irregularity) starts from its static state with a lateral offset of the leading wheelset
(:func:`disturbed_run`); the lead wheelset's lateral displacement is then followed at every
output step. Its exponential growth rate (:func:`growth_rate`: a straight line through the
logarithms of the oscillation's extrema) changes sign at the speed above which a small
disturbance no longer decays: the linear critical speed (a Hopf bifurcation of the centred
run), which :mod:`ttbpipe.vehicle.hunting` predicts from the eigenvalues.

For a strongly nonlinear contact (real profiles) the centred run can be stable while a large
oscillation persists (a subcritical bifurcation). :func:`ramp_down` finds the speed below
which every oscillation dies out (the nonlinear critical speed): it starts at a high speed
from a large disturbance and lowers the speed in steps, each run continuing from the last
state of the previous one (a stepwise version of the ramp-down of a continuous speed
reduction: Polach, "On non-linear methods of bogie stability assessment using computer
simulations", Proc. IMechE F 220, 2006). The loop runs at a constant speed, so the state is
carried over between runs (:func:`disturbed_run`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from .loop import integrate
from .setup import prepare

log = logging.getLogger(__name__)

def hunting_case(contact: Mapping[str, Any] | None, speed_kmh: float,
                 time_step_s: float = 1.0e-4, composition: tuple[str, ...] = ("trailer",),
                 train: Mapping[str, Any] | None = None, duration_s: float = 1.0) -> dict:
    """A case on rigid perfect track: ``composition`` cars with ``train.contact`` = ``contact``
    (further ``train`` keys in ``train``) at ``speed_kmh`` for ``duration_s``, output at every
    step."""
    train_cfg = dict(train or {})
    train_cfg["composition"] = list(composition)
    if contact:
        train_cfg["contact"] = dict(contact)
    return {"train": train_cfg,
            "simulation": {"track": "rigid", "speed_kmh": float(speed_kmh),
                           "duration_s": float(duration_s), "time_step_s": float(time_step_s),
                           "output_every": 1},
            "irregularity": {"source": "none"}}


@dataclass
class HuntingRun:
    """One run: output times, the wheelsets' lateral displacements (m) and the last state."""

    time: np.ndarray            # (n_out,)
    lateral: np.ndarray         # (n_out, n_ws)
    q_end: np.ndarray
    v_end: np.ndarray
    q_static: np.ndarray
    wall_s: float

    def amplitude(self, last_s: float = 1.0, wheelset: int = 0) -> float:
        """Largest |y| of a wheelset over the last ``last_s`` seconds (m)."""
        sel = self.time >= self.time[-1] - last_s
        return float(np.abs(self.lateral[sel, wheelset]).max())


def disturbed_run(case: Mapping[str, Any], duration_s: float, lateral_m: float = 0.0,
                  start: tuple[np.ndarray, np.ndarray] | None = None) -> HuntingRun:
    """Run ``case`` (:func:`hunting_case`) for ``duration_s`` from its static state with the
    leading wheelset moved laterally by ``lateral_m``, or from ``start`` = (q, v) (a previous
    run's final displacements and velocities: continuation at another speed). The wheelsets'
    spin angles start at zero (nothing depends on them; the loop does not count them as
    displacements)."""
    case = {**case, "simulation": {**case["simulation"], "duration_s": float(duration_s)}}
    setup = prepare(case)
    ws_y = setup.model.wheelset_dofs[:, 0]
    spin = setup.model.wheelset_dofs[:, 3]
    q_static = setup.q0.copy()
    if start is not None:
        q, v = np.array(start[0], dtype=float), np.array(start[1], dtype=float)
    else:
        q, v = setup.q0.copy(), setup.v0.copy()
        q[ws_y[0]] += lateral_m
    q[spin] = 0.0
    setup.q0, setup.v0 = q, v
    raw = integrate(setup)
    lateral = raw.q[:, ws_y] - q_static[ws_y]
    return HuntingRun(raw.time, lateral, raw.final.q.copy(), raw.final.v.copy(), q_static,
                      raw.wall_s)


def growth_rate(time: np.ndarray, signal: np.ndarray, t_start: float) -> tuple[float, float]:
    """Exponential growth rate (1/s, negative: decay) and frequency (Hz) of an oscillation
    from ``t_start`` on: the extrema of the signal (sign changes of its difference, refined by
    a parabola through three samples) and a least-squares line through log|extremum| against
    time. Meant for a record dominated by one mode (the least damped one, late in a run)."""
    sel = time >= t_start
    t, y = time[sel], signal[sel]
    d = np.diff(y)
    idx = np.flatnonzero(np.sign(d[1:]) * np.sign(d[:-1]) < 0) + 1
    idx = idx[(idx > 0) & (idx < y.size - 1)]
    if idx.size < 4:
        raise ValueError(f"only {idx.size} extrema after t = {t_start} s: run longer")
    y0, y1, y2 = y[idx - 1], y[idx], y[idx + 1]
    den = y0 - 2.0 * y1 + y2
    shift = np.where(den != 0.0, 0.5 * (y0 - y2) / np.where(den != 0.0, den, 1.0), 0.0)
    peak = y1 - 0.25 * (y0 - y2) * shift
    h = t[1] - t[0]
    tp = t[idx] + shift * h
    slope, _ = np.polyfit(tp, np.log(np.abs(peak)), 1)
    frequency = 0.5 * (idx.size - 1) / (tp[-1] - tp[0])
    return float(slope), float(frequency)


def zero_crossing(speeds: np.ndarray, rates: np.ndarray) -> float:
    """Speed at which the growth rate changes sign (linear interpolation between the first
    pair of speeds that bracket it); nan when none does."""
    speeds = np.asarray(speeds, float)
    rates = np.asarray(rates, float)
    for i in range(speeds.size - 1):
        if rates[i] <= 0.0 < rates[i + 1]:
            slope = (rates[i + 1] - rates[i]) / (speeds[i + 1] - speeds[i])
            return float(speeds[i] - rates[i] / slope)
    return float("nan")


def ramp_down(contact: Mapping[str, Any] | None, speeds_kmh, duration_s: float,
              lateral_m: float, decayed_m: float = 1.0e-5, time_step_s: float = 1.0e-4,
              composition: tuple[str, ...] = ("trailer",)) -> list[dict]:
    """Stepwise ramp-down (module docstring): ``speeds_kmh`` in decreasing order, the first run
    from a lateral offset ``lateral_m`` of the leading wheelset, each next one from the last
    state of the previous; stops after the first speed whose run ends with the lead wheelset's
    amplitude (last second) below ``decayed_m``. Returns per speed the amplitude over the last
    second (the lead wheelset's, and every wheelset's) and the growth rate and frequency over
    the run's second half."""
    out = []
    start = None
    for v in speeds_kmh:
        case = hunting_case(contact, v, time_step_s, composition)
        run = disturbed_run(case, duration_s, lateral_m if start is None else 0.0, start)
        rate, freq = growth_rate(run.time, run.lateral[:, 0], 0.5 * duration_s)
        amp = run.amplitude()
        out.append({"speed_kmh": float(v), "amplitude_m": amp,
                     "wheelset_amplitudes_m": [run.amplitude(1.0, w)
                                               for w in range(run.lateral.shape[1])],
                     "growth_rate_1_s": rate, "frequency_hz": freq, "wall_s": run.wall_s})
        log.info("ramp-down %.1f km/h: amplitude %.3g mm, rate %.3g 1/s", v, 1e3 * amp, rate)
        if amp < decayed_m:
            break
        start = (run.q_end, run.v_end)
    return out
