"""The chainage grid of a campaign: grid indices, re-gridding of jitter, re-inserted dropouts.

Step 4 of :func:`ttbpipe.inspection.validate.clean_campaign`. :func:`grid_indices` also tells,
from the chainage alone, how many rows a campaign will have once cleaned (ttbpipe.study.plan).
"""

from __future__ import annotations

import dataclasses
import logging

import numpy as np

from ..channels import INSPECTION_COLUMNS
from .checks import true_runs
from .cleaning_report import CleaningReport
from .format import CHAINAGE_COLUMN, InspectionError


@dataclasses.dataclass
class Grid:
    """A campaign on its uniform chainage grid (:func:`regrid`)."""

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


def regrid(chainage: np.ndarray, data: np.ndarray, source: str, report: CleaningReport,
           max_gap_m: float, sampling_tolerance: float, max_jitter: float) -> Grid:
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
            report.repair_runs["regridded"][c] = len(true_runs(off_grid))
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
        runs = true_runs(inserted)
        for c in INSPECTION_COLUMNS:
            report.repairs["dropout_interpolated"][c] = int(inserted.sum())
            report.repair_runs["dropout_interpolated"][c] = len(runs)
        report.note(f"dropouts: {int(inserted.sum())} missing rows in {len(runs)} gap(s) "
                    f"re-inserted on the grid and interpolated (longest "
                    f"{max(b - a for a, b in runs) * step:g} m)", logging.WARNING)
    grid_chainage = np.round(offset + (k[0] + np.arange(n_grid)) * step, 9)
    return Grid(grid_chainage, grid_data, source_row, inserted, step)


def row_of(grid: Grid, index: int) -> tuple[int | None, str]:
    """File row of grid sample ``index`` and a note when it is a re-inserted sample."""
    row = int(grid.source_row[index])
    if row:
        return row, ""
    before = grid.source_row[:index][grid.source_row[:index] > 0]
    if before.size:
        return int(before[-1]), " (a re-inserted sample after this row)"
    return None, " (a re-inserted sample at the start)"
