"""Checks of a campaign table before any repair: schema, chainage, sensor faults and units.

Steps 1-3 of :func:`ttbpipe.inspection.validate.clean_campaign` (its module docstring describes
each check and why). Every failure raises :class:`~ttbpipe.inspection.format.InspectionError`
naming the file, the first offending row and the column.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..channels import INSPECTION_COLUMNS
from .format import (CHAINAGE_COLUMN, CHAINAGE_UNITS_TO_M, REQUIRED_COLUMNS, InspectionError,
                     numeric_column, unit_error_message)

#: Plausible sampling steps (m); outside this range the chainage is in another unit.
MIN_STEP_M, MAX_STEP_M = 0.01, 10.0

#: Round metric sampling steps (m) of inspection cars (0.25 m is the usual one). A chainage whose
#: step is none of them but becomes one times 0.3048 (m per foot) is written in feet.
COMMON_STEPS_M: tuple[float, ...] = (0.1, 0.125, 0.2, 0.25, 0.5, 1.0)

#: Relative tolerance of the comparison with :data:`COMMON_STEPS_M` (the step is measured over
#: the whole file, so rounding of the chainage values hardly affects it).
COMMON_STEP_TOLERANCE = 1e-4

#: Nominal track gauges (mm): a gauge channel around one of them holds the absolute gauge.
_NOMINAL_GAUGES_MM = (1000.0, 1067.0, 1435.0, 1520.0, 1668.0)


def true_runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Contiguous True runs of a boolean array as (start, stop) index pairs."""
    padded = np.concatenate(([False], mask.astype(bool), [False]))
    edges = np.flatnonzero(np.diff(padded.astype(np.int8)))
    return list(zip(edges[0::2].tolist(), edges[1::2].tolist()))


def check_schema(df: pd.DataFrame, source: str) -> tuple[dict[str, np.ndarray], list[str]]:
    """Required columns as float arrays, and the list of ignored extra columns."""
    columns = [str(c) for c in df.columns]
    for required in REQUIRED_COLUMNS:
        if required in columns:
            continue
        for col in columns:
            message = unit_error_message(col)
            if message and col.lower().startswith(required.rpartition("_")[0] + "_"):
                raise InspectionError(source, None, col, message)
        raise InspectionError(source, None, required,
                              f"missing column {required!r} (found: {', '.join(columns)}); "
                              f"required: {', '.join(REQUIRED_COLUMNS)}")
    extra = [c for c in columns if c not in REQUIRED_COLUMNS]
    values = {c: numeric_column(df[c], source, c) for c in REQUIRED_COLUMNS}
    for c, v in values.items():
        inf = np.isinf(v)
        if inf.any():
            raise InspectionError(source, int(np.flatnonzero(inf)[0]) + 1, c, "infinite value")
    return values, extra


def check_units(values: dict[str, np.ndarray], source: str, plausible_limit_mm: float) -> None:
    """Detect channels in metres (all tiny) or micrometres (huge), and absolute gauges."""
    for col in INSPECTION_COLUMNS:
        finite = values[col][np.isfinite(values[col])]
        if finite.size < 3:
            continue  # all or almost all missing: the NaN-run check names it
        magnitude = np.abs(finite)
        median_abs = float(np.median(magnitude))
        if col == "gauge_mm":
            median_value = float(np.median(finite))
            for nominal in _NOMINAL_GAUGES_MM:
                if abs(median_value - nominal) < 40.0:
                    raise InspectionError(
                        source, None, col,
                        f"values around {median_value:.1f} mm look like the absolute gauge; "
                        f"gauge_mm is the deviation from nominal (subtract {nominal:g} mm)")
        if median_abs > plausible_limit_mm:
            raise InspectionError(
                source, None, col,
                f"implausible magnitude: median |value| = {median_abs:.4g} mm exceeds "
                f"plausible_limit_mm = {plausible_limit_mm:g} mm; the values seem to be in "
                "micrometres (divide by 1000, or declare the unit in inspections.units) or "
                "another unit; expected millimetres")
        if magnitude.max() > 0 and np.percentile(magnitude, 99) < 0.05 \
                and float(np.std(finite)) < 0.01:
            raise InspectionError(
                source, None, col,
                f"implausible magnitude: all values tiny (99th percentile of |value| = "
                f"{np.percentile(magnitude, 99):.3g}, standard deviation "
                f"{np.std(finite):.3g}); the values seem to be in metres (multiply by 1000, or "
                "declare the unit in inspections.units); expected millimetres")


def _is_common_step(step: float) -> bool:
    return any(abs(step - s) <= COMMON_STEP_TOLERANCE * s for s in COMMON_STEPS_M)


def check_chainage(chainage: np.ndarray, source: str) -> float:
    """No missing chainage; strictly increasing; a plausible step, not in feet.

    Returns the median step (m).
    """
    missing = ~np.isfinite(chainage)
    if missing.any():
        raise InspectionError(source, int(np.flatnonzero(missing)[0]) + 1, CHAINAGE_COLUMN,
                              "missing chainage value")
    steps = np.diff(chainage)
    bad = np.flatnonzero(steps <= 0)
    if bad.size:
        i = int(bad[0]) + 1  # 0-based index of the offending sample
        if steps[bad[0]] == 0:
            raise InspectionError(source, i + 1, CHAINAGE_COLUMN,
                                  f"duplicate chainage {chainage[i]:.6g} m (same as row {i})")
        raise InspectionError(source, i + 1, CHAINAGE_COLUMN,
                              f"chainage not increasing: {chainage[i]:.6g} m after "
                              f"{chainage[i - 1]:.6g} m in row {i}")
    step = float(np.median(steps))
    if not MIN_STEP_M <= step <= MAX_STEP_M:
        raise InspectionError(source, None, CHAINAGE_COLUMN,
                              f"implausible median sampling step {step:.6g} m (expected "
                              f"{MIN_STEP_M:g}..{MAX_STEP_M:g} m, typically 0.25 m): is the "
                              "chainage in metres? (convert it, or declare its unit in "
                              "inspections.units, e.g. chainage: km)")
    # The step over the whole file (not one rounded step): a chainage rounded to 1 mm in feet
    # still gives the step to about 1e-7 relative.
    n_steps = float(np.sum(np.rint(steps / step)))
    mean_step = float(chainage[-1] - chainage[0]) / n_steps
    foot = CHAINAGE_UNITS_TO_M["ft"]
    if not _is_common_step(mean_step) and _is_common_step(mean_step * foot):
        common = ", ".join(f"{s:g}" for s in COMMON_STEPS_M)
        raise InspectionError(
            source, None, CHAINAGE_COLUMN,
            f"chainage looks like feet: the sampling step {mean_step:.6g} is "
            f"{mean_step * foot:.6g} m in feet, a common metric step ({common} m), but no "
            f"common step itself; convert the chainage to metres (multiply by {foot:g}) or "
            "declare inspections.units: {chainage: ft}")
    return step


def check_sensor_faults(values: dict[str, np.ndarray], source: str, step: float,
                        max_constant_run_m: float) -> None:
    """Dead (all zero) and stuck (constant) channels, and long runs of one exact value."""
    for col in INSPECTION_COLUMNS:
        v = values[col]
        finite_rows = np.flatnonzero(np.isfinite(v))
        if finite_rows.size == 0:
            continue  # all missing: the NaN-run check names it
        finite = v[finite_rows]
        first = int(finite_rows[0]) + 1
        if np.all(finite == 0.0):
            raise InspectionError(
                source, first, col,
                f"dead sensor: all {finite.size} values are exactly 0 (no signal); check the "
                "sensor and the export of this channel")
        if np.all(finite == finite[0]):
            raise InspectionError(
                source, first, col,
                f"stuck sensor: all {finite.size} values are exactly {finite[0]:g} mm (zero "
                "variance); no real track geometry is constant")
        same = v[1:] == v[:-1]  # NaN never equals: a missing value ends a run
        for start, stop in true_runs(same):
            n_samples = stop - start + 1
            if n_samples * step <= max_constant_run_m + 1e-9 * step:
                continue
            value = float(v[start])
            extent = (f"{n_samples} consecutive samples (rows {start + 1}-{stop + 1}, "
                      f"{n_samples * step:g} m) read exactly {value:g} mm, longer than "
                      f"max_constant_run_m = {max_constant_run_m:g} m")
            if value == 0.0:
                reason = (f"dead sensor: {extent} (or missing values written as 0 instead of "
                          "empty cells)")
            else:
                reason = (f"stuck sensor: {extent}; no real track geometry is constant that "
                          "long (raise inspections.cleaning.max_constant_run_m only for a "
                          "coarse measuring resolution)")
            raise InspectionError(source, start + 1, col, reason)
