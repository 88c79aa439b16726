"""The seed paper's section 5 case studies as ready-made studies (docs/validation.md).

* :func:`apply_scale`: ``--config scale=small`` (or ``medium``) merges a case file's overlay;
* case 1 (section 5.1): :func:`sweep_speeds`, :func:`run_speed` (one deterministic coupled run
  per speed, the maxima of Fig. 8), :func:`time_history_run` (rail displacement under a wheel,
  girder midspan displacement and acceleration: Figs. 6-7), :func:`bridge_frequencies` and
  :func:`resonance_speeds` (eq. 55), :func:`sweep_resonances` (peaks of the sweep);
* cases 2-4 (sections 5.2-5.4) run through the study stage (docs/studies.md: scenario kinds
  ``fields`` / ``fields_mc``, ``irregularity`` / ``irregularity_mc`` / ``single``, ``forecast``
  with several levels); :func:`compare_histories` scores the agreement of two methods' mean and
  std curves (Figs. 10, 14) and :func:`forecast_limits` builds Fig. 17's lower, general and
  upper limits from the forecast scenarios.
"""

from __future__ import annotations

import copy
import logging
from typing import Any, Mapping, MutableMapping, Sequence

import numpy as np
import pandas as pd

from ..dates import months_between
from .samples import (build_case, extremes_from_run, mean_spectrum_irregularity,
                      resolve_simulation)

log = logging.getLogger(__name__)

#: Per-speed maxima of the sweep (Fig. 8) besides the study's extremes columns.
SWEEP_COLUMNS = ("speed_kmh", "max_wheel_vertical_force_N", "max_wheel_lateral_force_N",
                 "max_deck_vertical_acc_m_s2", "max_deck_lateral_acc_m_s2",
                 "max_girder_vertical_disp_m")


def _merge(base: MutableMapping[str, Any], overlay: Mapping[str, Any]) -> None:
    for key, value in overlay.items():
        if isinstance(value, Mapping) and isinstance(base.get(key), Mapping):
            base[key] = dict(base[key])
            _merge(base[key], value)
        else:
            base[key] = copy.deepcopy(value)


SCALES = ("full", "medium", "small")


def apply_scale(config: MutableMapping[str, Any]) -> MutableMapping[str, Any]:
    """``scale: small`` or ``scale: medium`` (``snakemake --config scale=small``): deep-merge the
    configuration's overlay of that name (``small:`` / ``medium:``) into it, in place (lists are
    replaced, mappings merged). ``scale: full`` or no ``scale``: the configuration as it is.
    Every overlay is removed either way, so that the resolved configuration (provenance, report)
    shows what ran."""
    scale = str(config.get("scale", "full"))
    if scale not in SCALES:
        raise ValueError(f"scale: {scale!r}; expected one of {list(SCALES)}")
    overlays = {name: config.pop(name, None) for name in SCALES[1:]}
    if scale != "full":
        overlay = overlays[scale]
        if not overlay:
            raise ValueError(f"scale={scale}, but the configuration has no {scale}: overlay (the "
                             "paper case files config/case*.yaml have one)")
        _merge(config, overlay)
        log.info("scale=%s: merged the %s: overlay (%s)", scale, scale, ", ".join(sorted(overlay)))
    return config


# ----------------------------------------------------------------------------------------------
# Case 1: speed sweep, time histories, resonance speeds

#: EN 1991-2:2003 6.4.6.2(1): a dynamic analysis covers speeds up to 1.2 x the maximum line
#: speed (standards sheet, docs/reference/standards.md [V]).
SWEEP_SPEED_FACTOR = 1.2


def sweep_speeds(sweep: Mapping[str, Any]) -> list[float]:
    """Speeds of the sweep, km/h: ``speeds_kmh: [first, last, step]`` inclusive of ``last``.

    With ``line_speed_kmh`` (the line's maximum speed) the sweep must reach
    :data:`SWEEP_SPEED_FACTOR` times it (EN 1991-2 6.4.6.2): ``last: null`` goes to the first
    step at or above it; an explicit ``last`` below it is an error.
    """
    first, last, step = sweep["speeds_kmh"]
    line = sweep.get("line_speed_kmh")
    first, step = float(first), float(step)
    if step <= 0:
        raise ValueError(f"case.sweep.speeds_kmh: step {step} km/h must be > 0")
    if line is not None:
        required = SWEEP_SPEED_FACTOR * float(line)
        if last is None:
            last = first + np.ceil((required - first) / step - 1e-9) * step
        elif float(last) < required - 1e-9:
            raise ValueError(
                f"case.sweep.speeds_kmh ends at {float(last):g} km/h, below {SWEEP_SPEED_FACTOR:g} x "
                f"the line speed {float(line):g} km/h = {required:g} km/h that EN 1991-2 6.4.6.2 "
                "asks a dynamic analysis to reach; raise the last speed or set it to null")
    elif last is None:
        raise ValueError("case.sweep.speeds_kmh: the last speed is null but no line_speed_kmh is "
                         "given to derive it from (1.2 x line speed, EN 1991-2 6.4.6.2)")
    last = float(last)
    if last < first:
        raise ValueError(f"case.sweep.speeds_kmh [{first}, {last}, {step}]: need first <= last, "
                         "step > 0")
    n = int(np.floor((last - first) / step + 1e-9)) + 1
    return [round(first + k * step, 6) for k in range(n)]


def speed_batches(speeds: Sequence[float], batch_size: int) -> list[tuple[int, int]]:
    """(first, last) index ranges into ``speeds``, at most ``batch_size`` each."""
    size = max(1, int(batch_size))
    return [(k, min(k + size, len(speeds)) - 1) for k in range(0, len(speeds), size)]


def sweep_irregularity(config: Mapping[str, Any]) -> dict[str, Any]:
    """Irregularity of every sweep run: the study's mean-spectrum profile (the same profile at
    every speed, so only the speed changes), or a perfect track (``case.sweep.irregularity:
    false``)."""
    sim = resolve_simulation(config.get("simulation"))
    if not config.get("case", {}).get("sweep", {}).get("irregularity", True):
        return {"source": "none"}
    return mean_spectrum_irregularity(sim["irregularity"], int(config["study"]["seed"]))


def run_speed(config: Mapping[str, Any], speed_kmh: float) -> dict[str, float]:
    """One deterministic coupled run at ``speed_kmh``: the study's extremes (docs/studies.md §2)
    plus ``speed_kmh`` (nominal parameters, :func:`sweep_irregularity`)."""
    from ..simulation.coupled import run_coupled

    sim = resolve_simulation(config.get("simulation"))
    sim["speed_kmh"] = float(speed_kmh)
    case = build_case(sim, config["structure"], irregularity=sweep_irregularity(config))
    try:
        table, summary = run_coupled(case)
    except Exception as exc:
        raise RuntimeError(f"speed sweep: the run at {speed_kmh} km/h failed: {exc}") from exc
    row = extremes_from_run(summary)
    return {"speed_kmh": float(speed_kmh), **row}


def run_sweep(config: Mapping[str, Any], speeds: Sequence[float]) -> pd.DataFrame:
    """:func:`run_speed` over ``speeds`` (one row per speed, in the given order)."""
    rows = []
    for k, v in enumerate(speeds):
        rows.append(run_speed(config, v))
        log.info("speed sweep: %g km/h done (%d/%d)", v, k + 1, len(speeds))
    return pd.DataFrame(rows)


def train_load_interval_m(train_cfg: Mapping[str, Any]) -> float:
    """Regular load interval of the train for eq. 55: the car length when every car has the
    same length (the axle pattern repeats every car); else an error (set
    ``case.sweep.load_interval_m``)."""
    from ..vehicle.parameters import train_from_config

    lengths = {round(float(car.car_length), 9) for car in train_from_config(train_cfg).cars}
    if len(lengths) != 1:
        raise ValueError(f"the train's cars have different lengths {sorted(lengths)}: set "
                         "case.sweep.load_interval_m for eq. 55")
    return lengths.pop()


def bridge_frequencies(structure: Mapping[str, Any], n_modes: int = 40) -> dict[str, float]:
    """First vertical and lateral girder frequencies (Hz) of the coupled track-bridge structure
    (:func:`ttbpipe.structure.modal.modal_analysis`, kinetic-energy share >= 30 %)."""
    from ..structure import build_structure
    from ..structure.modal import modal_analysis

    result = modal_analysis(build_structure(dict(structure)), n_modes=n_modes)
    return {"vertical": result.first("girder_vertical"), "lateral": result.first("girder_lateral")}


def resonance_speeds(frequencies_hz: Mapping[str, float], load_interval_m: float,
                     speed_range_kmh: tuple[float, float], max_order: int = 6) -> pd.DataFrame:
    """Eq. 55 (Xia et al.): V = 3.6 f L / i km/h, i = 1, 2, ..., inside ``speed_range_kmh``.

    Columns: ``direction``, ``frequency_hz``, ``order`` (i), ``speed_kmh``.
    """
    rows = []
    lo, hi = speed_range_kmh
    for direction, f in frequencies_hz.items():
        for i in range(1, int(max_order) + 1):
            v = 3.6 * float(f) * float(load_interval_m) / i
            if lo <= v <= hi:
                rows.append({"direction": direction, "frequency_hz": float(f), "order": i,
                             "speed_kmh": v})
    return pd.DataFrame(rows, columns=["direction", "frequency_hz", "order", "speed_kmh"])


def sweep_resonances(sweep: pd.DataFrame, column: str, predicted_kmh: Sequence[float],
                     window_kmh: float = 40.0) -> pd.DataFrame:
    """For each predicted resonance speed, the sweep's largest ``column`` within
    +-``window_kmh`` and where it occurs (the numerical resonance speed), and its ratio to the
    median of the sweep (how pronounced the peak is)."""
    speeds = sweep["speed_kmh"].to_numpy(float)
    values = sweep[column].to_numpy(float)
    rows = []
    for v in predicted_kmh:
        inside = np.flatnonzero(np.abs(speeds - v) <= window_kmh)
        if inside.size == 0:
            continue
        k = inside[np.argmax(values[inside])]
        rows.append({"quantity": column, "predicted_kmh": float(v), "peak_kmh": float(speeds[k]),
                     "peak_value": float(values[k]), "ratio_to_median": float(values[k] / np.median(values))})
    return pd.DataFrame(rows)


def rail_monitors(structure: Mapping[str, Any], spacing_m: float = 0.25,
                  margin_m: float = 30.0) -> list[dict[str, Any]]:
    """Left-rail displacement monitors every ``spacing_m`` over the bridge and ``margin_m`` of
    the approaches (to follow a wheel along the rail, Fig. 6)."""
    from ..structure import build_structure

    model = build_structure(dict(structure))
    start = model.spans[0].start_m - margin_m
    end = model.spans[-1].start_m + model.spans[-1].length_m + margin_m
    xs = np.arange(max(start, model.layout.rail_x[0]), min(end, model.layout.rail_x[-1]), spacing_m)
    return [{"name": f"railtrack{k:05d}", "kind": "rail", "rail": 0, "x_m": float(x),
             "directions": ["z", "y"], "quantities": ["displacement"]} for k, x in enumerate(xs)]


def time_history_run(config: Mapping[str, Any], speed_kmh: float, *, car: int = 2,
                     wheelset: int = 1, spacing_m: float = 0.25) -> tuple[pd.DataFrame, dict]:
    """Figs. 6-7: one deterministic run at ``speed_kmh``; returns a table against time with the
    left rail's vertical/lateral displacement under wheelset ``wheelset`` of car ``car``
    (1-based; the paper's "1st wheelset of the trailer car" = car 2, wheelset 1), interpolated
    linearly between rail monitors ``spacing_m`` apart, and the middle span's girder midspan
    vertical/lateral displacement and acceleration; and a dict of the bridge's layout.

    Columns: ``time_s``, ``x_lead_m``, ``x_wheel_m``, ``rail_vertical_disp_m``,
    ``rail_lateral_disp_m`` (NaN while the wheel is outside the monitored stretch),
    ``girder_vertical_disp_m``, ``girder_lateral_disp_m``, ``girder_vertical_acc_m_s2``,
    ``girder_lateral_acc_m_s2``.
    """
    from ..simulation.coupled import run_coupled
    from ..structure import build_structure
    from ..structure.monitors import default_monitors
    from ..vehicle.model import WHEELSETS, build_train_model
    from ..vehicle.parameters import train_from_config

    sim = resolve_simulation(config.get("simulation"))
    sim["speed_kmh"] = float(speed_kmh)
    structure = dict(config["structure"])
    model = build_structure(structure)
    rails = rail_monitors(structure, spacing_m)
    case = build_case(sim, structure, irregularity=sweep_irregularity(config))
    case["monitors"] = default_monitors(model) + rails
    table, summary = run_coupled(case)
    train = build_train_model(train_from_config(sim["train"]))
    ws_index = (int(car) - 1) * len(WHEELSETS) + int(wheelset) - 1
    if not 0 <= ws_index < train.wheelset_x.size:
        raise ValueError(f"car {car} wheelset {wheelset}: the train has {train.params.n_cars} cars")
    x_wheel = table["x_lead_m"].to_numpy(float) + float(train.wheelset_x[ws_index])
    xs = np.array([m["x_m"] for m in rails])
    out = {"time_s": table["time_s"].to_numpy(float), "x_lead_m": table["x_lead_m"].to_numpy(float),
           "x_wheel_m": x_wheel}
    inside = (x_wheel >= xs[0]) & (x_wheel <= xs[-1])
    for axis, name in (("z", "vertical"), ("y", "lateral")):
        grid = 1e-3 * table[[f"{m['name']}_{axis}_disp_mm" for m in rails]].to_numpy(float)
        k = np.clip(np.searchsorted(xs, x_wheel) - 1, 0, xs.size - 2)
        w = np.clip((x_wheel - xs[k]) / (xs[k + 1] - xs[k]), 0.0, 1.0)
        rows = np.arange(x_wheel.size)
        value = (1 - w) * grid[rows, k] + w * grid[rows, k + 1]
        out[f"rail_{name}_disp_m"] = np.where(inside, value, np.nan)
    span = len(model.spans) // 2 + 1
    for axis, name in (("z", "vertical"), ("y", "lateral")):
        out[f"girder_{name}_disp_m"] = 1e-3 * table[f"girder_span{span}_mid_{axis}_disp_mm"].to_numpy(float)
        out[f"girder_{name}_acc_m_s2"] = table[f"girder_span{span}_mid_{axis}_acc_m_s2"].to_numpy(float)
    layout = {"span": span, "span_start_m": float(model.spans[span - 1].start_m),
              "span_length_m": float(model.spans[span - 1].length_m),
              "bridge_start_m": float(model.spans[0].start_m),
              "bridge_end_m": float(model.spans[-1].start_m + model.spans[-1].length_m),
              "wheel": f"car{car}_ws{wheelset}", "speed_kmh": float(speed_kmh),
              "max_wheel_vertical_force_N": float(summary["max_wheel_vertical_force_N"])}
    return pd.DataFrame(out), layout


# ----------------------------------------------------------------------------------------------
# Cases 2-4: comparisons over the study's outputs

def compare_histories(stats: pd.DataFrame, quantity: str, reference: str, other: str
                      ) -> dict[str, float]:
    """Agreement of two scenarios' mean and std curves of one history quantity (Figs. 10, 14):
    the largest absolute difference of each, relative to the reference's largest |mean| and
    largest std, and the correlation of the two std curves."""
    a = stats[(stats["scenario"].astype(str) == reference) & (stats["quantity"] == quantity)]
    b = stats[(stats["scenario"].astype(str) == other) & (stats["quantity"] == quantity)]
    if a.empty or b.empty:
        raise ValueError(f"history statistics have no {quantity!r} for scenario "
                         f"{reference if a.empty else other!r}")
    merged = a.merge(b, on="position_m", suffixes=("_ref", "_other"))
    mean_scale = float(np.max(np.abs(merged["mean_ref"])))
    std_scale = float(np.max(merged["std_ref"]))
    return {"quantity": quantity, "reference": reference, "other": other,
            "n_points": int(len(merged)),
            "max_mean_difference_rel": float(np.max(np.abs(merged["mean_ref"] - merged["mean_other"]))
                                             / mean_scale),
            "max_std_ref": std_scale, "max_std_other": float(np.max(merged["std_other"])),
            "max_std_difference_rel": float(np.max(np.abs(merged["std_ref"] - merged["std_other"]))
                                            / std_scale),
            "std_correlation": float(np.corrcoef(merged["std_ref"], merged["std_other"])[0, 1])}


def forecast_limits(extremes: pd.DataFrame, column: str, base_date: str) -> pd.DataFrame:
    """Fig. 17: per forecast horizon, the weighted mean of ``column`` over the forecast states at
    each level (scenario labels ``<target date>_p<level>``): lower / general / upper limits =
    the lowest / middle / highest level. Columns: ``target_date``, ``months``, ``level``,
    ``mean``, ``n_samples``."""
    from .design import parse_forecast_label

    rows = []
    for scenario, block in extremes.groupby(extremes["scenario"].astype(str)):
        date, level = parse_forecast_label(scenario)
        if level is None:
            continue
        w = block["weight"].to_numpy(float)
        rows.append({"target_date": date, "months": months_between(base_date, date),
                     "level": level, "mean": float(np.sum(w * block[column]) / np.sum(w)),
                     "n_samples": int(len(block))})
    if not rows:
        raise ValueError("no forecast scenario with a level (<date>_p<level>) in the extremes; set "
                         "study.scenarios.forecast.levels")
    return pd.DataFrame(rows).sort_values(["months", "level"]).reset_index(drop=True)
