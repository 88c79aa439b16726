"""Validation and cleaning of one inspection campaign.

:func:`clean_campaign` checks a campaign table read by
:func:`ttbpipe.inspection.format.read_campaign` and applies the documented repairs, in this order:

1. **Schema.** Required columns present (a column written with another length unit, e.g.
   ``vertical_left_m``, is an error that names the expected unit); text in a number column is an
   error naming the first offending row and column. Extra columns are ignored and logged.
2. **Units.** Implausible magnitudes: a channel whose values are all tiny (99th percentile of
   ``|x|`` below 0.05 with a standard deviation below 0.01) is in metres, one whose median ``|x|``
   exceeds ``plausible_limit_mm`` is in micrometres (or holds the absolute gauge); a chainage step
   below 1 cm or above 10 m is in the wrong unit.
3. **Chainage.** No missing value, strictly increasing (a duplicate or a step back is an error
   naming the row).
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
7. **Plausibility.** Any ``|value| > plausible_limit_mm`` after the repairs is an error.
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
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import scipy.signal

from ..channels import INSPECTION_COLUMNS
from .format import (CHAINAGE_COLUMN, REQUIRED_COLUMNS, InspectionError, campaign_date,
                     unit_error_message)

logger = logging.getLogger(__name__)

#: Repair kinds counted in :class:`CleaningReport` ``repairs`` (samples per channel).
REPAIR_KINDS: tuple[str, ...] = ("regridded", "dropout_interpolated", "nan_interpolated",
                                 "spike_replaced")

DETREND_KINDS: tuple[str, ...] = ("none", "constant", "linear")

#: Plausible sampling steps (m); outside this range the chainage is in another unit.
MIN_STEP_M, MAX_STEP_M = 0.01, 10.0

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
        def clean(obj: Any) -> Any:
            if isinstance(obj, dict):
                return {str(k): clean(v) for k, v in obj.items()}
            if isinstance(obj, (list, tuple)):
                return [clean(v) for v in obj]
            if isinstance(obj, (np.integer,)):
                return int(obj)
            if isinstance(obj, (float, np.floating)):
                return None if not math.isfinite(obj) else float(obj)
            return obj
        return clean(dataclasses.asdict(self))

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
        if self.cross_level_rms_difference_mm is not None:
            lines.append("cross_level vs vertical_left - vertical_right: RMS difference "
                         f"{self.cross_level_rms_difference_mm:.3f} mm (information only)")
        return "\n".join(lines)


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Contiguous True runs of a boolean array as (start, stop) index pairs."""
    padded = np.concatenate(([False], mask.astype(bool), [False]))
    edges = np.flatnonzero(np.diff(padded.astype(np.int8)))
    return list(zip(edges[0::2].tolist(), edges[1::2].tolist()))


_NA_TEXT = re.compile(r"^\s*(|nan|na|n/a|null|none|-nan|<na>)\s*$", re.IGNORECASE)


def _numeric_column(series: pd.Series, source: str, column: str) -> np.ndarray:
    """Column as float64; text that is not a number is an error naming its first row."""
    if pd.api.types.is_bool_dtype(series.dtype):
        raise InspectionError(source, None, column, "boolean column; expected numbers")
    if pd.api.types.is_numeric_dtype(series.dtype):
        return series.to_numpy(dtype=float, na_value=np.nan)
    converted = pd.to_numeric(series, errors="coerce")
    bad = converted.isna().to_numpy() & ~series.isna().to_numpy()
    if bad.any():
        texts = series.astype(str).to_numpy()
        for i in np.flatnonzero(bad):
            if _NA_TEXT.match(texts[i]):
                continue  # a spelled-out missing value: handled as NaN
            hint = ""
            if re.fullmatch(r"\s*[-+]?\d+,\d+\s*", texts[i]):
                hint = " (decimal comma? use a point)"
            raise InspectionError(source, int(i) + 1, column,
                                  f"text {texts[i]!r} in a number column{hint}")
    return converted.to_numpy(dtype=float, na_value=np.nan)


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
    values = {c: _numeric_column(df[c], source, c) for c in REQUIRED_COLUMNS}
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
                "micrometres (divide by 1000) or another unit; expected millimetres")
        if magnitude.max() > 0 and np.percentile(magnitude, 99) < 0.05 \
                and float(np.std(finite)) < 0.01:
            raise InspectionError(
                source, None, col,
                f"implausible magnitude: all values tiny (99th percentile of |value| = "
                f"{np.percentile(magnitude, 99):.3g}, standard deviation "
                f"{np.std(finite):.3g}); the values seem to be in metres (multiply by 1000); "
                "expected millimetres")


def _check_chainage(chainage: np.ndarray, source: str) -> None:
    """No missing chainage; strictly increasing; a plausible step."""
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
                              "chainage in metres?")


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


def clean_campaign(df: pd.DataFrame, source: str | Path, *, max_gap_m: float = 2.0,
                   spike_threshold_mm: float = 15.0, max_spike_run: int = 2,
                   plausible_limit_mm: float = 60.0, detrend: str = "linear",
                   sampling_tolerance: float = 0.01,
                   max_jitter: float = 0.25) -> tuple[pd.DataFrame, CleaningReport]:
    """Validate one campaign and apply the documented repairs (see the module docstring).

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
    if detrend not in DETREND_KINDS:
        raise ValueError(f"detrend must be one of {DETREND_KINDS}, not {detrend!r}")
    if max_spike_run < 1 or spike_threshold_mm <= 0 or plausible_limit_mm <= 0 or max_gap_m < 0:
        raise ValueError("cleaning options: need max_spike_run >= 1, spike_threshold_mm > 0, "
                         "plausible_limit_mm > 0, max_gap_m >= 0")
    if not 0 <= sampling_tolerance <= max_jitter < 0.5:
        raise ValueError("need 0 <= sampling_tolerance <= max_jitter < 0.5")
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
                                          max_jitter=max_jitter))
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
    _check_units(values, source, plausible_limit_mm)

    # 3-4. Chainage and sampling.
    chainage = values[CHAINAGE_COLUMN]
    _check_chainage(chainage, source)
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


def check_campaign(path: str | Path, **options: Any) -> tuple[pd.DataFrame, CleaningReport]:
    """Read and clean one campaign file: :func:`read_campaign` then :func:`clean_campaign`."""
    from .format import read_campaign
    frame = read_campaign(path)
    return clean_campaign(frame, path, **options)
