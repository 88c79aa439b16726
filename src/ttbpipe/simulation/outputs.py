"""Results of a coupled run: the time-history table, the response indices, the summary.

* :func:`results_table`: time histories at the output steps: per wheel P, Q, the contact flag,
  Q/P and the unloading ratio; per wheelset H and the lateral displacement; car-body floor
  accelerations; every structure monitor (column names carry units).
* :func:`response_indices`: every index of the registry (:mod:`ttbpipe.response_indices`),
  named as the study's extremes table and the results schema name it, plus the per-span deck and
  per-car Sperling indices. Peaks of forces are taken at every time step (the recorders);
  deck accelerations are low-passed at ``deck_filter_hz`` (EN 1990 A2 A2.4.4.2.1) on the output
  histories; rail accelerations and girder displacements are peaks over every step.
* :func:`summarise`: the indices plus what the run did (step, limits, static state, contact
  loss, Sperling per car, monitor peaks), flat: the index names are keys of the summary.
* :func:`check_finite`: nothing non-finite leaves a run.
"""

from __future__ import annotations

import logging
from typing import Any, Mapping

import numpy as np
import pandas as pd

from ..response_indices import PER_CAR, PER_SPAN
from ..structure.monitors import deck_columns
from ..vehicle.comfort import sperling_index
from .recorder import decimated, derailment_coefficients
from .setup import CoupledSetup, diagnosis_limits, wheel_labels

log = logging.getLogger(__name__)

CARBODY_POINTS = ("front", "centre", "rear")
#: Default low-pass of the deck accelerations (EN 1990 A2 A2.4.4.2.1: deck accelerations are
#: checked for frequencies up to 30 Hz).
DECK_FILTER_HZ = 30.0


def carbody_accelerations(setup: CoupledSetup, acc: np.ndarray) -> dict[str, np.ndarray]:
    """Car-body floor accelerations (vertical, lateral) above the bogie pivots and at the centre,
    from ``acc[row, j]``: the car bodies' (z, y, pitch, yaw) accelerations, four per car.

    At a point x_p from the car centre (rigid body, small rotations): a_z = z'' - x_p pitch'',
    a_y = y'' + x_p yaw'' (model.point_row), at the car's centre-of-gravity height.
    """
    out = {}
    for ci, car in enumerate(setup.train.cars):
        z, y, pitch, yaw = (acc[:, 4 * ci + k] for k in range(4))
        for name, xp in zip(CARBODY_POINTS, (car.bogie_half_spacing, 0.0, -car.bogie_half_spacing)):
            out[f"car{ci + 1}_body_{name}_az_m_s2"] = z - xp * pitch
            out[f"car{ci + 1}_body_{name}_ay_m_s2"] = y + xp * yaw
    return out


def results_table(setup: CoupledSetup, raw) -> pd.DataFrame:
    """Time histories: wheel forces, contact flag, Q/P, unloading, H, car-body accelerations,
    monitors.

    Forces, accelerations, displacements and monitors are the anti-aliased histories
    (ttbpipe.decimation: low-passed before sampling, valid to the output Nyquist frequency);
    ``<wheel>_in_contact`` (int8, 1/0) is the contact state at the output step itself (normal
    force N > 0). Q/P is defined in contact only: |Q|/P there and 0 where the wheel is off the
    rail (a lifted wheel with a flange force would give |Q|/0). The loss of contact itself is
    its own index (summary ``contact_loss_*``).
    """
    m = setup.model
    labels = wheel_labels(m)
    p0 = setup.static_wheel[:, :, 2]
    train = raw.train
    n_mon = 0 if setup.monitors is None else setup.monitors.n
    hist = decimated(train, n_mon)
    cols: dict[str, np.ndarray] = {"time_s": train.t_out,
                                   "x_lead_m": setup.x_lead0 + setup.velocity * train.t_out}
    for w, lab in enumerate(labels):
        for k, side in enumerate(("left", "right")):
            p = hist["wheel"][:, w, k, 2]
            qf = hist["wheel"][:, w, k, 1]
            contact = train.wheel_hist[:, w, k, 4] > 0.0
            cols[f"{lab}_{side}_P_N"] = p
            cols[f"{lab}_{side}_Q_N"] = qf
            cols[f"{lab}_{side}_in_contact"] = contact.astype(np.int8)
            cols[f"{lab}_{side}_QP"] = derailment_coefficients(qf, p, contact)
            cols[f"{lab}_{side}_unloading"] = (p0[w, k] - p) / p0[w, k]
        cols[f"{lab}_H_N"] = hist["wheel"][:, w, 0, 1] + hist["wheel"][:, w, 1, 1]
        cols[f"{lab}_y_mm"] = 1e3 * hist["disp"][:, w]
    cols.update(carbody_accelerations(setup, hist["acc"]))
    if setup.monitors is not None:
        for i, name in enumerate(setup.monitors.names):
            cols[name] = hist["monitors"][:, i]
    return pd.DataFrame(cols)


def lowpass_peak(values: np.ndarray, dt: float, cutoff_hz: float) -> float:
    """max |x| after a zero-phase 4th-order Butterworth low-pass at cutoff_hz (scipy
    ``sosfiltfilt``); the raw max when the cutoff is at or above 0.95 of the Nyquist frequency."""
    return float(lowpass_peaks(np.asarray(values)[:, None], dt, cutoff_hz)[0])


def lowpass_peaks(columns: np.ndarray, dt: float, cutoff_hz: float) -> np.ndarray:
    """:func:`lowpass_peak` of each column of ``columns`` (n, k), filtered in one call (the
    same numbers as column by column: scipy filters each column on its own)."""
    from scipy import signal

    from ..filters import butterworth_sos

    nyquist = 0.5 / dt
    if cutoff_hz >= 0.95 * nyquist:
        return np.max(np.abs(columns), axis=0)
    sos = butterworth_sos(4, float(cutoff_hz), "lowpass", 1.0 / dt)
    return np.max(np.abs(signal.sosfiltfilt(sos, columns, axis=0)), axis=0)


def _sperling_per_car(setup: CoupledSetup, table: pd.DataFrame) -> dict[str, float]:
    dt_out = setup.dt * setup.out_every
    record_s = len(table) * dt_out
    if record_s < 5.0:
        log.warning("Sperling indices from a %.2f s record (shorter than the 5 s window of the "
                    "standard): each evaluated as one window", record_s)
    sperling = {}
    for ci in range(setup.train.n_cars):
        for direction, key in (("vertical", "az"), ("lateral", "ay")):
            vals = [sperling_index(table[f"car{ci + 1}_body_{p}_{key}_m_s2"].to_numpy(), dt_out,
                                   direction, quiet=True)[0] for p in CARBODY_POINTS]
            sperling[f"car{ci + 1}_{direction}"] = float(max(vals))
    return sperling


def response_indices(setup: CoupledSetup, raw, table: pd.DataFrame,
                     deck_filter_hz: float = DECK_FILTER_HZ,
                     sperling: dict[str, float] | None = None) -> dict[str, float]:
    """Every response index of the run, by its registry name (module docstring), and the
    per-span deck and per-car Sperling indices (``sperling``: the per-car indices of
    :func:`_sperling_per_car` when the caller has them)."""
    p0 = setup.static_wheel[:, :, 2]
    peak = raw.train.wheel_peak
    names = table.columns.tolist()       # a list: iterating the Index is ten times slower
    out: dict[str, float] = {
        "max_derailment_coefficient": float(peak[:, :, 3].max()),
        "max_wheel_unloading_ratio": float(((p0 - peak[:, :, 1]) / p0).max()),
        "max_lateral_wheelset_force_N": float(raw.train.h_peak.max()),
        "max_wheel_vertical_force_N": float(peak[:, :, 0].max()),
        "max_wheel_lateral_force_N": float(peak[:, :, 2].max()),
        "max_carbody_vertical_acc_m_s2": float(max(
            np.abs(table[c].to_numpy()).max() for c in names if c.endswith("_az_m_s2"))),
        "max_carbody_lateral_acc_m_s2": float(max(
            np.abs(table[c].to_numpy()).max() for c in names if c.endswith("_ay_m_s2"))),
    }
    from .diagnosis import contact_loss_stats

    loss = contact_loss_stats(raw.train.contact_loss, setup.dt, setup.wheelset_x0,
                              setup.velocity, wheel_labels(setup.model))
    out["contact_loss_count"] = float(loss["contact_loss_count"])
    out["contact_loss_total_duration_s"] = float(loss["contact_loss_total_s"])
    out["contact_loss_max_duration_s"] = float(loss["contact_loss_max_s"])
    if sperling is None:
        sperling = _sperling_per_car(setup, table)
    for direction in ("vertical", "lateral"):
        per_car = {k: v for k, v in sperling.items() if k.endswith(f"_{direction}")}
        out[f"sperling_{direction}"] = float(max(per_car.values()))
    deck_peak: dict[str, float] = {}       # filtered deck peak per column, filtered once
    if setup.monitors is not None:
        peaks = {name: float(raw.monitors.peak[i]) for i, name in enumerate(setup.monitors.names)}
        dt_out = float(np.median(np.diff(table["time_s"].to_numpy())))
        deck_names = list(dict.fromkeys(c for axis in ("z", "y")
                                        for cols in deck_columns(names, axis).values()
                                        for c in cols))
        if deck_names:
            values = np.column_stack([table[c].to_numpy(float) for c in deck_names])
            deck_peak = dict(zip(deck_names,
                                 lowpass_peaks(values, dt_out, deck_filter_hz).tolist()))
        for direction, axis in (("vertical", "z"), ("lateral", "y")):
            deck = [c for cols in deck_columns(names, axis).values() for c in cols]
            rail = [k for k in peaks if k.startswith("rail_") and k.endswith(f"_{axis}_acc_m_s2")]
            if deck:
                out[f"max_deck_{direction}_acc_m_s2"] = max(deck_peak[c] for c in deck)
            if rail:
                out[f"max_rail_{direction}_acc_m_s2"] = float(max(peaks[k] for k in rail))
        disp = [k for k in peaks if k.startswith("girder_span") and k.endswith("_z_disp_mm")]
        if disp:
            out["max_girder_vertical_disp_m"] = 1e-3 * float(max(peaks[k] for k in disp))
    for key, value in sorted(sperling.items()):
        car, direction = key.split("_")
        out[PER_CAR[0 if direction == "vertical" else 1].format(car=car[3:])] = float(value)
    if setup.monitors is not None:
        for axis, name in zip(("z", "y"), PER_SPAN):
            for s, cols in deck_columns(names, axis).items():
                out[name.format(span=s)] = max(deck_peak[c] for c in cols)
    return out


def summarise(setup: CoupledSetup, raw, table: pd.DataFrame,
              deck_filter_hz: float = DECK_FILTER_HZ) -> dict:
    """The run's response indices (registry names, flat) and what the run did."""
    m = setup.model
    labels = wheel_labels(m)
    p0 = setup.static_wheel[:, :, 2]
    dt_out = setup.dt * setup.out_every
    summary: dict[str, Any] = {
        "speed_kmh": setup.speed * 3.6, "time_step_s": setup.dt, "n_steps": setup.n_steps,
        "simulated_s": setup.n_steps * setup.dt, "wall_s": raw.wall_s,
        "wall_s_per_simulated_s": raw.wall_s / (setup.n_steps * setup.dt),
        "dt_limits": setup.dt_limits, "static_iterations": setup.static_iterations,
        "n_spans": setup.n_spans,
        "static_wheel_load_N": {lab: p0[w].tolist() for w, lab in enumerate(labels)},
        # where each wheelset runs: x = x_lead_m + offset (the assessment's track under a wheel)
        "wheelset_offset_m": {lab: float(x0 - setup.x_lead0)
                              for lab, x0 in zip(labels, setup.wheelset_x0)},
        "min_wheel_vertical_force_N": float(raw.train.wheel_peak[:, :, 1].min()),
        "contact": setup.geom.description,
        "irregularity": dict(setup.irregularity_info),
        "deck_filter_hz": float(deck_filter_hz),
    }
    from .diagnosis import contact_loss_stats
    summary.update(contact_loss_stats(raw.train.contact_loss, setup.dt, setup.wheelset_x0,
                                      setup.velocity, labels))
    if setup.monitors is not None:
        summary["monitor_peaks"] = {name: float(raw.monitors.peak[i])
                                    for i, name in enumerate(setup.monitors.names)}
    summary["sperling_record_s"] = len(table) * dt_out
    summary["sperling"] = _sperling_per_car(setup, table)
    summary.update(response_indices(setup, raw, table, deck_filter_hz, summary["sperling"]))
    return summary


#: How the train-side indices of two trains combine into the run's: the largest of the two, or
#: the sum (counts and total durations over all wheels of both trains).
_SUMMED = ("contact_loss_count", "contact_loss_total_duration_s")


def train_index_names() -> list[str]:
    """Registry indices computed from a train's own records (not from the structure)."""
    from ..response_indices import RESPONSE_INDEX_REGISTRY

    structure = ("max_deck_", "max_rail_", "max_girder_")
    return [r.name for r in RESPONSE_INDEX_REGISTRY if not r.name.startswith(structure)]


def placement(setup: CoupledSetup) -> dict:
    """Where a train ran: its track (0-based), direction (+1: +x), speed."""
    return {"track_index": int(setup.track_index), "direction": int(setup.direction),
            "speed_kmh": float(setup.speed * 3.6), "x_lead0_m": float(setup.x_lead0)}


def add_second_train(setup: CoupledSetup, raw, table: pd.DataFrame, summary: dict,
                     deck_filter_hz: float = DECK_FILTER_HZ) -> tuple[pd.DataFrame, dict]:
    """The second train of a two-train run added to the first's table and summary.

    Table: its columns (wheel forces, Q/P, unloading, H, car-body accelerations, ``x_lead_m``)
    prefixed ``train2_``; the first train's keep the names of a one-train run, the monitors
    are the structure's. Summary: the train-side registry indices (:func:`train_index_names`)
    become the run's over both trains (the larger of the two; contact-loss counts and total
    durations summed), each train's own as ``train1_<index>`` and ``train2_<index>``; the
    second train's whole summary (static loads, contact loss per wheel, Sperling per car) in
    ``second_train``; both placements in ``trains``.
    """
    from .loop import RawResult
    from ..structure.monitors import no_monitors

    second = setup.second
    raw2 = RawResult(raw.second, no_monitors(), raw.wall_s, raw.final_second)
    table2 = results_table(second, raw2)
    summary2 = summarise(second, raw2, table2, deck_filter_hz)
    table = pd.concat([table, table2.drop(columns="time_s").add_prefix(second.label)], axis=1)
    out = dict(summary)
    for name in train_index_names():
        one, two = summary[name], summary2[name]
        out[f"train1_{name}"], out[f"{second.label}{name}"] = one, two
        out[name] = one + two if name in _SUMMED else max(one, two)
    out["contact_loss_max_s"] = max(summary["contact_loss_max_s"], summary2["contact_loss_max_s"])
    out["contact_loss_wheels"] = summary["contact_loss_wheels"] + summary2["contact_loss_wheels"]
    out["contact_loss_total_s"] = (summary["contact_loss_total_s"]
                                   + summary2["contact_loss_total_s"])
    out["second_train"] = summary2
    out["trains"] = [placement(setup), placement(second)]
    return table, out


def _nonfinite_entries(summary: Mapping[str, Any], prefix: str = "") -> list[str]:
    bad = []
    for key, value in summary.items():
        if isinstance(value, Mapping):
            bad += _nonfinite_entries(value, f"{prefix}{key}.")
        elif isinstance(value, (float, np.floating)) and not np.isfinite(value):
            bad.append(f"{prefix}{key}")
    return bad


def check_finite(setup: CoupledSetup, table: pd.DataFrame, summary: dict) -> None:
    """Raise ValueError naming the column(s) and summary key(s) with a non-finite value and the
    likely cause (:func:`ttbpipe.simulation.diagnosis.explain`): nothing non-finite reaches a
    results table."""
    values = table.to_numpy(dtype=float)
    bad_rows = ~np.isfinite(values)
    columns = [c for c, b in zip(table.columns.tolist(), bad_rows.any(axis=0)) if b]
    keys = _nonfinite_entries(summary)
    if not columns and not keys:
        return
    from .diagnosis import explain
    where = ""
    if columns:
        row = int(np.flatnonzero(bad_rows.any(axis=1))[0])
        where = (f" (first at t = {table['time_s'].iloc[row]:.4f} s, leading wheelset at x = "
                 f"{table['x_lead_m'].iloc[row]:.1f} m)")
    loss = {k: v for k, v in summary.items() if k.startswith("contact_loss")}
    _, text = explain(setup.dt, diagnosis_limits(setup), setup.irregularity_info, loss,
                      setup.irregularity_config, setup.speed, propose_auto=setup.propose_auto)
    raise ValueError(f"non-finite values in the coupled run's results: column(s) {columns[:8]}"
                     f"{' ...' if len(columns) > 8 else ''} ({len(columns)} in all){where}, "
                     f"summary key(s) {keys}; the loop only stops on a non-finite vehicle or "
                     f"structure state, so this is a defect of the post-processing or of an "
                     f"input; {text}")
