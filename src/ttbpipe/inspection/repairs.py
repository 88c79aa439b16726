"""Repairs of a campaign on its grid: missing values, spikes, interpolation, detrending.

Steps 5, 6 and 8 of :func:`ttbpipe.inspection.validate.clean_campaign` (its module docstring
states each rule and its default). Every repaired sample is counted in the
:class:`~ttbpipe.inspection.cleaning_report.CleaningReport`; what cannot be repaired raises
:class:`~ttbpipe.inspection.format.InspectionError` naming the file, the row and the column.
"""

from __future__ import annotations

import logging
import warnings

import numpy as np

from ..channels import INSPECTION_COLUMNS
from .checks import true_runs
from .cleaning_report import CleaningReport
from .format import InspectionError
from .grid import Grid, row_of

#: Detrending of each channel after the repairs (``scipy.signal.detrend`` types, or none).
DETREND_KINDS: tuple[str, ...] = ("none", "constant", "linear")


def local_median_of_neighbours(values: np.ndarray, half_width: int) -> np.ndarray:
    """Median of the ``2 * half_width`` neighbours of each sample (itself excluded; NaN ignored)."""
    padded = np.pad(values, half_width, constant_values=np.nan)
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * half_width + 1)
    neighbours = np.delete(windows, half_width, axis=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN windows -> NaN, not flagged
        return np.nanmedian(neighbours, axis=1)


def check_missing_values(grid: Grid, source: str, report: CleaningReport,
                         max_gap_m: float) -> np.ndarray:
    """Step 5: runs of missing values (original NaN and re-inserted rows together) longer than
    ``max_gap_m`` are errors; the original NaN are counted as ``nan_interpolated``. Returns the
    mask of missing samples (grid rows x channels)."""
    data, step = grid.data, grid.step
    missing = np.isnan(data)
    for c, col in enumerate(INSPECTION_COLUMNS):
        for start, stop in true_runs(missing[:, c]):
            if (stop - start) * step > max_gap_m + 1e-9 * step:
                first = start
                while first < stop and grid.inserted[first]:
                    first += 1
                row, where = row_of(grid, first if first < stop else start)
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
            report.repair_runs["nan_interpolated"][col] = len(true_runs(original_nan))
    return missing


def find_spikes(data: np.ndarray, report: CleaningReport, spike_threshold_mm: float,
                max_spike_run: int) -> np.ndarray:
    """Step 6: samples deviating more than ``spike_threshold_mm`` from the median of their
    ``4 * max_spike_run`` neighbours (NaN ignored), in runs of at most ``max_spike_run``, are
    spikes (``spike_replaced``); longer runs are kept as geometry and logged. Returns the mask of
    spikes."""
    half_width = 2 * max_spike_run
    spikes = np.zeros(data.shape, dtype=bool)
    for c, col in enumerate(INSPECTION_COLUMNS):
        median = local_median_of_neighbours(data[:, c], half_width)
        flagged = np.abs(data[:, c] - median) > spike_threshold_mm  # False where NaN
        long_runs = 0
        for start, stop in true_runs(flagged):
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
            report.repair_runs["spike_replaced"][col] = len(true_runs(spikes[:, c]))
    return spikes


def interpolate_flagged(data: np.ndarray, x: np.ndarray, to_fill: np.ndarray,
                        report: CleaningReport) -> np.ndarray:
    """Linear interpolation over every sample to repair (missing or spike; at the ends of the
    file the nearest valid value is held). Returns the repaired copy of ``data``."""
    repaired = data.copy()
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
    return repaired


def detrend_channels(repaired: np.ndarray, x: np.ndarray, detrend: str,
                     report: CleaningReport) -> None:
    """Step 8: remove each channel's trend (``detrend``: ``none`` | ``constant`` | ``linear``)
    in place, reporting the removed mean and slope."""
    if detrend != "none":
        from scipy import signal   # on use, as in ttbpipe.irregularity.psd.welch_psd

        span = x[-1] - x[0]
        for c, col in enumerate(INSPECTION_COLUMNS):
            detrended = signal.detrend(repaired[:, c], type=detrend)
            trend = repaired[:, c] - detrended
            report.trend_removed[col] = {
                "mean_mm": float(np.mean(trend)),
                "slope_mm_per_km": float((trend[-1] - trend[0]) / span * 1000.0),
            }
            repaired[:, c] = detrended
        report.note(f"detrend ({detrend}) per channel: removed mean (mm) "
                    f"{ {k: round(v['mean_mm'], 4) for k, v in report.trend_removed.items()} }")
