"""Validation and cleaning of one inspection campaign.

:func:`clean_campaign` checks a campaign table read by
:func:`ttbpipe.inspection.format.read_campaign` and applies the documented repairs, in this order:

0. **Mapping** (optional, config ``inspections.columns`` / ``inspections.units``): the file's
   columns renamed to ttbpipe's names and declared units converted
   (:func:`ttbpipe.inspection.format.apply_mapping`; logged, listed in the report as
   ``renamed_columns`` and ``unit_conversions``). Errors then name the file's own column.
1. **Schema.** Required columns present (a column written with another length unit, e.g.
   ``vertical_left_m``, is an error that names the expected unit); text in a number column is an
   error naming the first offending row and column. Extra columns are ignored and logged.
2. **Chainage.** No missing value, strictly increasing (a duplicate or a step back is an error
   naming the row); a median step below 1 cm or above 10 m is in the wrong unit, and a step that
   is a round metric step (:data:`COMMON_STEPS_M`) written in feet is chainage in feet.
3. **Sensor faults.** A channel that reads exactly 0 everywhere is a dead sensor, one with zero
   variance a stuck sensor; so is a run of exactly equal samples longer than
   ``max_constant_run_m`` (no real geometry is constant over metres at the resolution of an
   inspection car; a run of zeros: a dead sensor or missing values written as 0). Errors name
   the first row of the run.
   **Units.** A channel whose values are all tiny (99th percentile of ``|x|`` below 0.05 with a
   standard deviation below 0.01) is in metres, one whose median ``|x|`` exceeds
   ``plausible_limit_mm`` is in micrometres (or holds the absolute gauge).
4. **Sampling.** Every step must lie within ``max_jitter`` (25 %) of a whole multiple of the
   median step, else it is a jump (an error naming the row). The grid step is fitted to the file
   (least squares on the grid indices) and the grid origin is the median offset of the samples.
   Samples within ``sampling_tolerance * h`` (1 %) of the grid are on it; if any sample is
   further off (jitter), every channel is re-gridded by linear interpolation (logged, counted as
   ``regridded``). Missing rows (dropouts) of up to ``max_gap_m`` in total length are
   re-inserted (counted as ``dropout_interpolated``); longer dropouts are errors.
5. **Missing values.** Runs of NaN (together with re-inserted rows) of up to ``max_gap_m``
   (``n_samples * h``) are interpolated linearly (at the ends of the file: the nearest valid
   value is held); longer runs are errors naming the file, the first row and the column.
6. **Spikes.** A sample deviating more than ``spike_threshold_mm`` from the median of its
   ``4 * max_spike_run`` neighbours is flagged; runs of at most ``max_spike_run`` flagged samples
   are replaced by linear interpolation (``spike_replaced``). Longer runs are real geometry or a
   sensor fault: they are kept and logged as a warning.
7. **Plausibility.** Any ``|value| > plausible_limit_mm`` after the repairs is an error. The
   band RMS of each channel over 2-200 m must lie within the range of the standard spectra from
   the best to the worst track class, widened by ``band_rms_margin``
   (:mod:`ttbpipe.inspection.plausibility`): below it the values are in centimetres or inches.
8. **Detrending** per channel (``none`` | ``constant`` | ``linear``, scipy.signal.detrend), with
   the removed mean and slope logged and reported.

Information only: the RMS of ``cross_level - (vertical_left - vertical_right)``. Inspection cars
measure cross-level (inertial/gyro) and the rail profiles (chord or inertial per rail) with
different sensors, so the two need not agree and this is never enforced.

Preprocessing practice (outlier removal, linear interpolation, zero mean, detrending) follows the
CARS practice for inspection data cited in the reference notes (physics.md section 2).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import warnings
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np
import pandas as pd
import scipy.signal

from ..channels import INSPECTION_COLUMNS
from ..io import jsonable
from .format import (CHAINAGE_COLUMN, CHAINAGE_UNITS_TO_M, REQUIRED_COLUMNS, InspectionError,
                     apply_mapping, campaign_date, numeric_column, unit_error_message)
from .plausibility import check_band_rms

logger = logging.getLogger(__name__)

#: Repair kinds counted in :class:`CleaningReport` ``repairs`` (samples per channel).
REPAIR_KINDS: tuple[str, ...] = ("regridded", "dropout_interpolated", "nan_interpolated",
                                 "spike_replaced")

DETREND_KINDS: tuple[str, ...] = ("none", "constant", "linear")

#: Plausible sampling steps (m); outside this range the chainage is in another unit.
MIN_STEP_M, MAX_STEP_M = 0.01, 10.0

#: Round metric sampling steps (m) of inspection cars (0.25 m is the usual one). A chainage whose
#: step is none of them but becomes one times 0.3048 (m per foot) is written in feet.
COMMON_STEPS_M: tuple[float, ...] = (0.1, 0.125, 0.2, 0.25, 0.5, 1.0)

#: Relative tolerance of the comparison with :data:`COMMON_STEPS_M` (the step is measured over
#: the whole file, so rounding of the chainage values hardly affects it).
COMMON_STEP_TOLERANCE = 1e-4

#: Defaults of the cleaning options, the keys of config section ``inspections.cleaning`` (plus
#: ``sampling_tolerance`` and ``max_jitter``, function arguments only). The one home of these
#: numbers: :func:`clean_campaign`, the ``check-inspection`` command line and the synthetic
#: generator take them from here.
#:
#: ``band_rms_margin``: a factor of 3 on the RMS (9 on the PSD) below the best and above the worst
#: standard spectrum keeps real track of any class (and the synthetic campaigns, with their
#: noise, defects and maintenance) inside the range, while TB/T 3352 or German track in
#: centimetres (10 times too small) or inches (25.4 times) falls outside it.
#: ``max_constant_run_m``: 20 m is 80 samples at 0.25 m; real geometry measured to 0.01 mm never
#: repeats one value that long, while a dropout written as constant values does.
CLEANING_DEFAULTS: Mapping[str, Any] = MappingProxyType({
    "max_gap_m": 2.0,
    "spike_threshold_mm": 15.0,
    "max_spike_run": 2,
    "plausible_limit_mm": 60.0,
    "detrend": "linear",
    "sampling_tolerance": 0.01,
    "max_jitter": 0.25,
    "band_rms_margin": 3.0,
    "max_constant_run_m": 20.0,
})

_NOMINAL_GAUGES_MM = (1000.0, 1067.0, 1435.0, 1520.0, 1668.0)


@dataclasses.dataclass
class CleaningReport:
    """What :func:`clean_campaign` found and repaired in one campaign file.

    ``repairs[kind][column]`` counts repaired samples and ``repair_runs[kind][column]`` the
    contiguous runs they form, for each kind of :data:`REPAIR_KINDS` and each channel.
    """

    source: str
    campaign_date: str | None = None
    rows_in: int = 0
    rows_out: int = 0
    sampling_interval_m: float = math.nan
    start_chainage_m: float = math.nan
    end_chainage_m: float = math.nan
    length_m: float = math.nan
    repairs: dict[str, dict[str, int]] = dataclasses.field(default_factory=dict)
    repair_runs: dict[str, dict[str, int]] = dataclasses.field(default_factory=dict)
    max_off_grid_m: float = 0.0
    long_excursions_kept: dict[str, int] = dataclasses.field(default_factory=dict)
    ignored_columns: list[str] = dataclasses.field(default_factory=list)
    renamed_columns: dict[str, str] = dataclasses.field(default_factory=dict)
    unit_conversions: dict[str, dict[str, Any]] = dataclasses.field(default_factory=dict)
    band_rms_band_m: list[float] | None = None
    band_rms_mm: dict[str, float] = dataclasses.field(default_factory=dict)
    detrend: str = "linear"
    trend_removed: dict[str, dict[str, float]] = dataclasses.field(default_factory=dict)
    cross_level_rms_difference_mm: float | None = None
    settings: dict[str, Any] = dataclasses.field(default_factory=dict)
    notes: list[str] = dataclasses.field(default_factory=list)

    def __post_init__(self) -> None:
        for kind in REPAIR_KINDS:
            self.repairs.setdefault(kind, {c: 0 for c in INSPECTION_COLUMNS})
            self.repair_runs.setdefault(kind, {c: 0 for c in INSPECTION_COLUMNS})

    def total(self, kind: str) -> int:
        """Repaired samples of one kind, summed over the channels."""
        return int(sum(self.repairs[kind].values()))

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (floats, ints, strings, lists, dicts; NaN -> None)."""
        return jsonable(dataclasses.asdict(self), nan_as_none=True)

    def note(self, message: str, level: int = logging.INFO) -> None:
        """Log ``message`` (prefixed with the source) and keep it in the report."""
        self.notes.append(message)
        logger.log(level, "%s: %s", self.source, message)

    def summary(self) -> str:
        """A one-screen, human-readable summary of the checks and repairs."""
        lines = [
            f"inspection file: {self.source}"
            + (f"  (campaign {self.campaign_date})" if self.campaign_date else ""),
            f"rows: {self.rows_in} read -> {self.rows_out} clean; sampling interval "
            f"{self.sampling_interval_m:g} m; chainage {self.start_chainage_m:.2f} .. "
            f"{self.end_chainage_m:.2f} m (length {self.length_m:.2f} m)",
            f"repaired samples (runs) per channel; trend removed (detrend: {self.detrend}):",
            f"  {'channel':20s}" + "".join(f"{k.split('_')[0]:>13s}" for k in REPAIR_KINDS)
            + f"{'mean mm':>10s}{'mm/km':>9s}",
        ]
        for c in INSPECTION_COLUMNS:
            cells = "".join(f"{self.repairs[k][c]:>7d} ({self.repair_runs[k][c]:>3d})"
                            for k in REPAIR_KINDS)
            trend = self.trend_removed.get(c)
            trend_text = (f"{trend['mean_mm']:>+10.3f}{trend['slope_mm_per_km']:>+9.3f}"
                          if trend else f"{'-':>10s}{'-':>9s}")
            lines.append(f"  {c:20s}{cells}{trend_text}")
        if self.max_off_grid_m:
            lines.append(f"largest chainage deviation from the grid: {self.max_off_grid_m:.4g} m")
        if any(self.long_excursions_kept.values()):
            lines.append(f"long excursions kept (not spikes): {self.long_excursions_kept}")
        if self.ignored_columns:
            lines.append(f"ignored extra columns: {', '.join(self.ignored_columns)}")
        if self.renamed_columns:
            lines.append("columns mapped (inspections.columns): " + ", ".join(
                f"{k} -> {v}" for k, v in self.renamed_columns.items()))
        if self.unit_conversions:
            lines.append("units converted (inspections.units): " + ", ".join(
                f"{k} from {v['unit']}" for k, v in self.unit_conversions.items()))
        if self.band_rms_band_m:
            lines.append(f"band RMS {self.band_rms_band_m[0]:g}-{self.band_rms_band_m[1]:g} m "
                         "(mm): " + ", ".join(f"{k.removesuffix('_mm')} {v:.3g}"
                                              for k, v in self.band_rms_mm.items()))
        if self.cross_level_rms_difference_mm is not None:
            lines.append("cross_level vs vertical_left - vertical_right: RMS difference "
                         f"{self.cross_level_rms_difference_mm:.3f} mm (information only)")
        return "\n".join(lines)


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Contiguous True runs of a boolean array as (start, stop) index pairs."""
    padded = np.concatenate(([False], mask.astype(bool), [False]))
    edges = np.flatnonzero(np.diff(padded.astype(np.int8)))
    return list(zip(edges[0::2].tolist(), edges[1::2].tolist()))


def _check_schema(df: pd.DataFrame, source: str) -> tuple[dict[str, np.ndarray], list[str]]:
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


def _check_units(values: dict[str, np.ndarray], source: str, plausible_limit_mm: float) -> None:
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


def _check_chainage(chainage: np.ndarray, source: str) -> float:
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


def _check_sensor_faults(values: dict[str, np.ndarray], source: str, step: float,
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
        for start, stop in _runs(same):
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


@dataclasses.dataclass
class _Grid:
    chainage: np.ndarray       # uniform grid positions (m)
    data: np.ndarray           # (n_grid, n_channels), NaN where missing / re-inserted
    source_row: np.ndarray     # 1-based file row of each grid sample, 0 when re-inserted
    inserted: np.ndarray       # bool, re-inserted (dropout) samples
    step: float


def grid_indices(chainage: np.ndarray) -> tuple[np.ndarray, float]:
    """(grid index of every sample, median step): sample i sits ``k[i]`` median steps after the
    first, each step rounded to a whole number of median steps. The cleaned campaign has
    ``k[-1] + 1`` rows (dropouts re-inserted), so this also tells, from the chainage alone, how
    many rows and full sections a campaign will have (ttbpipe.study.plan, before any job runs)."""
    chainage = np.asarray(chainage, dtype=float)
    steps = np.diff(chainage)
    median_step = float(np.median(steps))
    k = np.concatenate(([0], np.cumsum(np.rint(steps / median_step)))).astype(np.int64)
    return k, median_step


def _regrid(chainage: np.ndarray, data: np.ndarray, source: str, report: CleaningReport,
            max_gap_m: float, sampling_tolerance: float, max_jitter: float) -> _Grid:
    """Put the samples on a uniform grid; re-grid jitter, re-insert dropouts; errors for jumps.

    Every step must lie within ``max_jitter`` of a whole multiple ``m >= 1`` of the median step
    (else: a jump, an error naming the row); ``m - 1`` is the number of missing rows. The grid
    step is then fitted by least squares to the positions and their grid indices, the origin is
    the median offset of the samples; both are rounded (step to 0.1 mm, origin to 1 mm, or else to
    1 micrometre) when the rounding moves the grid by at most ``sampling_tolerance`` (step, over
    the whole file) or half of it (origin).
    Samples further than ``max_jitter`` steps from the fitted grid (a drift) are errors too.
    """
    steps = np.diff(chainage)
    k, median_step = grid_indices(chainage)
    multiples = np.diff(k).astype(float)
    step_error = np.abs(steps - multiples * median_step)
    jumps = np.flatnonzero((step_error > max_jitter * median_step) | (multiples < 1))
    if jumps.size:
        i = int(jumps[0]) + 1
        raise InspectionError(
            source, i + 1, CHAINAGE_COLUMN,
            f"irregular sampling: a jump in chainage, the step from {chainage[i - 1]:.6g} m "
            f"(row {i}) to {chainage[i]:.6g} m is {steps[i - 1]:.6g} m, not a multiple of the "
            f"{median_step:.6g} m median step (tolerance max_jitter = {max_jitter:g} step)")
    fitted = float(np.polyfit(k, chainage, 1)[0])
    half_tolerance = 0.5 * sampling_tolerance * median_step
    step = round(fitted, 4) if abs(round(fitted, 4) - fitted) * k[-1] <= 2 * half_tolerance \
        else round(fitted, 6)
    offset = float(np.median(chainage - k * step))
    offset = round(offset, 3) if abs(round(offset, 3) - offset) <= half_tolerance \
        else round(offset, 6)
    deviation = chainage - (offset + k * step)
    far = np.flatnonzero(np.abs(deviation) > max_jitter * step)
    if far.size:
        i = int(far[0])
        raise InspectionError(
            source, i + 1, CHAINAGE_COLUMN,
            f"irregular sampling: chainage {chainage[i]:.6g} m is {deviation[i]:+.4g} m off the "
            f"{step:g} m grid fitted to the file (more than max_jitter = {max_jitter:g} step): "
            "the chainage drifts")
    dk = np.diff(k)
    same = np.flatnonzero(dk == 0)
    if same.size:
        i = int(same[0]) + 1
        raise InspectionError(
            source, i + 1, CHAINAGE_COLUMN,
            f"irregular sampling: chainage {chainage[i]:.6g} m falls in the same {step:g} m grid "
            f"cell as row {i} ({chainage[i - 1]:.6g} m): a near-duplicate or a jump")
    missing = dk - 1
    too_long = np.flatnonzero(missing * step > max_gap_m + 1e-9 * step)
    if too_long.size:
        j = int(too_long[0])
        raise InspectionError(
            source, j + 2, CHAINAGE_COLUMN,
            f"{int(missing[j])} rows missing between chainage {chainage[j]:.6g} m (row {j + 1}) "
            f"and {chainage[j + 1]:.6g} m: a dropout of {missing[j] * step:g} m exceeds "
            f"max_gap_m = {max_gap_m:g} m")
    off_grid = np.abs(deviation) > sampling_tolerance * step
    report.max_off_grid_m = float(np.max(np.abs(deviation)))
    values = data
    if off_grid.any():
        targets = offset + k * step
        values = np.column_stack([np.interp(targets, chainage, data[:, c])
                                  for c in range(data.shape[1])])
        n_off = int(off_grid.sum())
        for c in INSPECTION_COLUMNS:
            report.repairs["regridded"][c] = n_off
            report.repair_runs["regridded"][c] = len(_runs(off_grid))
        report.note(f"sampling jitter: {n_off} samples off the {step:g} m grid by more than "
                    f"{sampling_tolerance:g} step (largest {report.max_off_grid_m:.4g} m); "
                    "all channels re-gridded by linear interpolation", logging.WARNING)
    n_grid = int(k[-1] - k[0]) + 1
    position = k - k[0]
    grid_data = np.full((n_grid, data.shape[1]), np.nan)
    grid_data[position] = values
    source_row = np.zeros(n_grid, dtype=np.int64)
    source_row[position] = np.arange(1, chainage.size + 1)
    inserted = source_row == 0
    if inserted.any():
        runs = _runs(inserted)
        for c in INSPECTION_COLUMNS:
            report.repairs["dropout_interpolated"][c] = int(inserted.sum())
            report.repair_runs["dropout_interpolated"][c] = len(runs)
        report.note(f"dropouts: {int(inserted.sum())} missing rows in {len(runs)} gap(s) "
                    f"re-inserted on the grid and interpolated (longest "
                    f"{max(b - a for a, b in runs) * step:g} m)", logging.WARNING)
    grid_chainage = np.round(offset + (k[0] + np.arange(n_grid)) * step, 9)
    return _Grid(grid_chainage, grid_data, source_row, inserted, step)


def _row_of(grid: _Grid, index: int) -> tuple[int | None, str]:
    """File row of grid sample ``index`` and a note when it is a re-inserted sample."""
    row = int(grid.source_row[index])
    if row:
        return row, ""
    before = grid.source_row[:index][grid.source_row[:index] > 0]
    if before.size:
        return int(before[-1]), " (a re-inserted sample after this row)"
    return None, " (a re-inserted sample at the start)"


def _local_median_of_neighbours(values: np.ndarray, half_width: int) -> np.ndarray:
    """Median of the ``2 * half_width`` neighbours of each sample (itself excluded; NaN ignored)."""
    padded = np.pad(values, half_width, constant_values=np.nan)
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * half_width + 1)
    neighbours = np.delete(windows, half_width, axis=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN windows -> NaN, not flagged
        return np.nanmedian(neighbours, axis=1)


_D = CLEANING_DEFAULTS


def clean_campaign(df: pd.DataFrame, source: str | Path, *,
                   max_gap_m: float = _D["max_gap_m"],
                   spike_threshold_mm: float = _D["spike_threshold_mm"],
                   max_spike_run: int = _D["max_spike_run"],
                   plausible_limit_mm: float = _D["plausible_limit_mm"],
                   detrend: str = _D["detrend"],
                   sampling_tolerance: float = _D["sampling_tolerance"],
                   max_jitter: float = _D["max_jitter"],
                   band_rms_margin: float = _D["band_rms_margin"],
                   max_constant_run_m: float = _D["max_constant_run_m"],
                   columns: Mapping[str, str] | None = None,
                   units: Mapping[str, str] | None = None
                   ) -> tuple[pd.DataFrame, CleaningReport]:
    """Validate one campaign and apply the documented repairs (see the module docstring).

    Defaults: :data:`CLEANING_DEFAULTS`.

    Parameters
    ----------
    df
        The campaign as read by :func:`ttbpipe.inspection.format.read_campaign` (row ``i`` of the
        frame is data row ``i + 1`` of the file).
    source
        The file it came from; named in every error and in the report.
    max_gap_m
        Longest stretch (``n_samples * step``) of missing values or missing rows repaired by
        linear interpolation.
    spike_threshold_mm, max_spike_run
        A run of at most ``max_spike_run`` samples deviating more than ``spike_threshold_mm`` from
        the median of the ``4 * max_spike_run`` neighbouring samples is a spike.
    plausible_limit_mm
        Largest plausible ``|value|`` after the repairs; also the unit check's threshold.
    detrend
        ``none`` | ``constant`` | ``linear``, per channel.
    sampling_tolerance, max_jitter
        Chainage deviations from the uniform grid up to ``sampling_tolerance`` steps are ignored,
        up to ``max_jitter`` steps re-gridded by interpolation, larger ones are errors.
    band_rms_margin
        Factor (>= 1) on the band RMS below the best and above the worst standard spectrum
        within which a channel is plausible (:mod:`ttbpipe.inspection.plausibility`).
    max_constant_run_m
        Longest run of exactly equal samples (``n_samples * step``) accepted; longer: a stuck or
        dead sensor.
    columns, units
        Column and unit mapping of the file (config ``inspections.columns`` and
        ``inspections.units``, :func:`ttbpipe.inspection.format.apply_mapping`), for a table
        that :func:`read_campaign` did not map already.

    Returns
    -------
    (clean, report)
        ``clean`` has ``chainage_m`` on a uniform grid and the six channels in mm (float64, no
        NaN); ``report`` is the :class:`CleaningReport`.

    Raises
    ------
    InspectionError
        naming the file, the first offending row and the column.
    """
    source = str(source)
    if columns or units:
        df = apply_mapping(df, source, columns=columns, units=units)
    renamed = dict(df.attrs.get("renamed_columns") or {})
    conversions = dict(df.attrs.get("unit_conversions") or {})
    try:
        return _clean_campaign(df, source, renamed, conversions, max_gap_m=max_gap_m,
                               spike_threshold_mm=spike_threshold_mm,
                               max_spike_run=max_spike_run,
                               plausible_limit_mm=plausible_limit_mm, detrend=detrend,
                               sampling_tolerance=sampling_tolerance, max_jitter=max_jitter,
                               band_rms_margin=band_rms_margin,
                               max_constant_run_m=max_constant_run_m)
    except InspectionError as exc:
        original = {target: name for name, target in renamed.items()}
        if exc.column not in original and exc.column not in conversions:
            raise
        # Name the file's own column, and say the values were converted.
        column = (f"{original[exc.column]} (read as {exc.column})" if exc.column in original
                  else exc.column)
        reason = exc.reason
        if exc.column in conversions:
            reason += (f" [values converted from {conversions[exc.column]['unit']} by "
                       "inspections.units]")
        raise InspectionError(exc.file, exc.row, column, reason) from None


def _clean_campaign(df: pd.DataFrame, source: str, renamed: dict[str, str],
                    conversions: dict[str, dict[str, Any]], *, max_gap_m: float,
                    spike_threshold_mm: float, max_spike_run: int, plausible_limit_mm: float,
                    detrend: str, sampling_tolerance: float, max_jitter: float,
                    band_rms_margin: float, max_constant_run_m: float
                    ) -> tuple[pd.DataFrame, CleaningReport]:
    """:func:`clean_campaign` after the mapping (its errors name ttbpipe's columns)."""
    if detrend not in DETREND_KINDS:
        raise ValueError(f"detrend must be one of {DETREND_KINDS}, not {detrend!r}")
    if max_spike_run < 1 or spike_threshold_mm <= 0 or plausible_limit_mm <= 0 or max_gap_m < 0:
        raise ValueError("cleaning options: need max_spike_run >= 1, spike_threshold_mm > 0, "
                         "plausible_limit_mm > 0, max_gap_m >= 0")
    if not 0 <= sampling_tolerance <= max_jitter < 0.5:
        raise ValueError("need 0 <= sampling_tolerance <= max_jitter < 0.5")
    if not band_rms_margin >= 1.0 or not max_constant_run_m > 0:
        raise ValueError("cleaning options: need band_rms_margin >= 1 and "
                         "max_constant_run_m > 0")
    date = df.attrs.get("campaign_date")
    if date is None:
        try:
            date = campaign_date(source).isoformat()
        except InspectionError:
            date = None
    report = CleaningReport(source=source, campaign_date=date, rows_in=len(df), detrend=detrend,
                            settings=dict(max_gap_m=max_gap_m,
                                          spike_threshold_mm=spike_threshold_mm,
                                          max_spike_run=max_spike_run,
                                          plausible_limit_mm=plausible_limit_mm, detrend=detrend,
                                          sampling_tolerance=sampling_tolerance,
                                          max_jitter=max_jitter,
                                          band_rms_margin=band_rms_margin,
                                          max_constant_run_m=max_constant_run_m))
    for name, target in renamed.items():
        report.renamed_columns[name] = target
        report.notes.append(f"column {name!r} read as {target!r} (inspections.columns)")
    for column, conversion in conversions.items():
        report.unit_conversions[column] = dict(conversion)
        report.notes.append(f"{column} converted from {conversion['unit']} "
                            f"(x {conversion['factor']:g}, inspections.units)")
    if df.attrs.get("trailing_blank_rows_removed"):
        report.note(f"{df.attrs['trailing_blank_rows_removed']} blank row(s) at the end of the "
                    "file removed")
    if len(df) == 0:
        raise InspectionError(source, None, None, "empty table: no data rows")

    # 1-2. Schema and units.
    values, extra = _check_schema(df, source)
    if extra:
        report.ignored_columns = extra
        report.note(f"extra columns ignored (not in the cleaned table): {', '.join(extra)}")
    if len(df) < 3:
        raise InspectionError(source, None, None, f"only {len(df)} data row(s); need at least 3")
    # 2-3. Chainage, sensor faults, units.
    chainage = values[CHAINAGE_COLUMN]
    median_step = _check_chainage(chainage, source)
    _check_sensor_faults(values, source, median_step, max_constant_run_m)
    _check_units(values, source, plausible_limit_mm)

    # 4. Sampling.
    data = np.column_stack([values[c] for c in INSPECTION_COLUMNS])
    grid = _regrid(chainage, data, source, report, max_gap_m, sampling_tolerance, max_jitter)
    step = grid.step
    data = grid.data

    # 5. Missing values (original NaN and re-inserted rows together).
    missing = np.isnan(data)
    for c, col in enumerate(INSPECTION_COLUMNS):
        for start, stop in _runs(missing[:, c]):
            if (stop - start) * step > max_gap_m + 1e-9 * step:
                first = start
                while first < stop and grid.inserted[first]:
                    first += 1
                row, where = _row_of(grid, first if first < stop else start)
                n_inserted = int(grid.inserted[start:stop].sum())
                raise InspectionError(
                    source, row, col,
                    f"{stop - start} consecutive missing values ({(stop - start) * step:g} m"
                    + (f", including {n_inserted} missing rows" if n_inserted else "")
                    + f"){where} exceed max_gap_m = {max_gap_m:g} m; fix the file or raise "
                    "inspections.cleaning.max_gap_m")
        original_nan = missing[:, c] & ~grid.inserted
        if original_nan.any():
            report.repairs["nan_interpolated"][col] = int(original_nan.sum())
            report.repair_runs["nan_interpolated"][col] = len(_runs(original_nan))

    # 6. Spikes: judged against the median of the neighbours, NaN ignored.
    half_width = 2 * max_spike_run
    spikes = np.zeros_like(missing)
    for c, col in enumerate(INSPECTION_COLUMNS):
        median = _local_median_of_neighbours(data[:, c], half_width)
        flagged = np.abs(data[:, c] - median) > spike_threshold_mm  # False where NaN
        long_runs = 0
        for start, stop in _runs(flagged):
            if stop - start <= max_spike_run:
                spikes[start:stop, c] = True
            else:
                long_runs += 1
        if long_runs:
            report.long_excursions_kept[col] = long_runs
            report.note(f"{col}: {long_runs} run(s) of more than {max_spike_run} samples "
                        f"deviating more than {spike_threshold_mm:g} mm from the local median "
                        "kept as geometry (not spikes)", logging.WARNING)
        if spikes[:, c].any():
            report.repairs["spike_replaced"][col] = int(spikes[:, c].sum())
            report.repair_runs["spike_replaced"][col] = len(_runs(spikes[:, c]))

    # Linear interpolation over everything to repair (ends: nearest valid value held).
    repaired = data.copy()
    to_fill = missing | spikes
    x = grid.chainage
    for c in range(repaired.shape[1]):
        good = ~to_fill[:, c]
        if to_fill[:, c].any():
            repaired[~good, c] = np.interp(x[~good], x[good], repaired[good, c])
    for kind in ("nan_interpolated", "spike_replaced"):
        if report.total(kind):
            report.note(f"{kind}: {report.total(kind)} samples in "
                        f"{sum(report.repair_runs[kind].values())} run(s), per channel "
                        f"{ {k: v for k, v in report.repairs[kind].items() if v} }",
                        logging.WARNING)

    # 7. Plausibility after the repairs.
    beyond = np.abs(repaired) > plausible_limit_mm
    if beyond.any():
        i, c = (int(v) for v in np.argwhere(beyond)[0])
        row, where = _row_of(grid, i)
        raise InspectionError(
            source, row, INSPECTION_COLUMNS[c],
            f"value {repaired[i, c]:.4g} mm{where} exceeds plausible_limit_mm = "
            f"{plausible_limit_mm:g} mm after the repairs (wrong unit or a sensor fault)")
    band, band_rms = check_band_rms(
        {col: repaired[:, c] for c, col in enumerate(INSPECTION_COLUMNS)}, step, source,
        margin=band_rms_margin)
    report.band_rms_band_m = list(band) if band else None
    report.band_rms_mm = band_rms
    if band:
        logger.info("%s: band RMS over %g-%g m (mm): %s, within the standard spectra's range",
                    source, band[0], band[1], {k: round(v, 3) for k, v in band_rms.items()})

    # Information: cross-level against the difference of the rail profiles (not enforced).
    columns = {col: repaired[:, c] for c, col in enumerate(INSPECTION_COLUMNS)}
    difference = columns["cross_level_mm"] - (columns["vertical_left_mm"]
                                              - columns["vertical_right_mm"])
    difference = scipy.signal.detrend(difference, type="linear")
    report.cross_level_rms_difference_mm = float(np.sqrt(np.mean(difference ** 2)))
    logger.info("%s: RMS of cross_level - (vertical_left - vertical_right) = %.3f mm "
                "(information; different sensors)", source,
                report.cross_level_rms_difference_mm)

    # 8. Detrending.
    if detrend != "none":
        span = x[-1] - x[0]
        for c, col in enumerate(INSPECTION_COLUMNS):
            detrended = scipy.signal.detrend(repaired[:, c], type=detrend)
            trend = repaired[:, c] - detrended
            report.trend_removed[col] = {
                "mean_mm": float(np.mean(trend)),
                "slope_mm_per_km": float((trend[-1] - trend[0]) / span * 1000.0),
            }
            repaired[:, c] = detrended
        report.note(f"detrend ({detrend}) per channel: removed mean (mm) "
                    f"{ {k: round(v['mean_mm'], 4) for k, v in report.trend_removed.items()} }")

    clean = pd.DataFrame({CHAINAGE_COLUMN: x,
                          **{col: repaired[:, c] for c, col in enumerate(INSPECTION_COLUMNS)}})
    report.rows_out = len(clean)
    report.sampling_interval_m = step
    report.start_chainage_m = float(x[0])
    report.end_chainage_m = float(x[-1])
    report.length_m = float(x[-1] - x[0])
    logger.info("%s: clean, %d rows, step %g m, %.1f m; repairs: %s", source, len(clean), step,
                report.length_m, {k: report.total(k) for k in REPAIR_KINDS})
    return clean, report


def check_campaign(path: str | Path, *, columns: Mapping[str, str] | None = None,
                   units: Mapping[str, str] | None = None,
                   **options: Any) -> tuple[pd.DataFrame, CleaningReport]:
    """Read and clean one campaign file: :func:`read_campaign` then :func:`clean_campaign`.

    ``columns`` / ``units``: the file's column and unit mapping (applied when reading);
    ``options``: the cleaning options of :func:`clean_campaign`.
    """
    from .format import read_campaign
    frame = read_campaign(path, columns=columns, units=units)
    return clean_campaign(frame, path, **options)


def options_from_config(inspections: Mapping[str, Any] | None) -> dict[str, Any]:
    """Keyword arguments of :func:`check_campaign` from a configuration's ``inspections`` section.

    The ``cleaning`` options, and ``columns`` / ``units`` when the section has a mapping.
    """
    section = dict(inspections or {})
    options: dict[str, Any] = dict(section.get("cleaning") or {})
    for key in ("columns", "units"):
        if section.get(key):
            options[key] = dict(section[key])
    return options
