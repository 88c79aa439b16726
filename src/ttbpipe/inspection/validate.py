"""Validation and cleaning of one inspection campaign.

:func:`clean_campaign` checks a campaign table read by
:func:`ttbpipe.inspection.format.read_campaign` and applies the documented repairs, in this order
(the checks of steps 1-3 in :mod:`.checks`, the grid of step 4 in :mod:`.grid`, the repairs of
steps 5, 6 and 8 in :mod:`.repairs`, the report in :mod:`.cleaning_report`):

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

import logging
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np
import pandas as pd

from ..channels import INSPECTION_COLUMNS
from .checks import (COMMON_STEP_TOLERANCE, COMMON_STEPS_M, MAX_STEP_M, MIN_STEP_M,
                     check_chainage, check_schema, check_sensor_faults, check_units)
from .cleaning_report import REPAIR_KINDS, CleaningReport
from .format import CHAINAGE_COLUMN, InspectionError, apply_mapping, campaign_date
from .grid import grid_indices, regrid, row_of
from .plausibility import check_band_rms
from .repairs import (DETREND_KINDS, check_missing_values, detrend_channels, find_spikes,
                      interpolate_flagged)

# The steps' public names stay importable from here, the entry point of the cleaning.
__all__ = ["CLEANING_DEFAULTS", "DETREND_KINDS", "REPAIR_KINDS", "MIN_STEP_M", "MAX_STEP_M",
           "COMMON_STEPS_M", "COMMON_STEP_TOLERANCE", "CleaningReport", "grid_indices",
           "clean_campaign", "check_campaign", "options_from_config"]

logger = logging.getLogger(__name__)

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
    values, extra = check_schema(df, source)
    if extra:
        report.ignored_columns = extra
        report.note(f"extra columns ignored (not in the cleaned table): {', '.join(extra)}")
    if len(df) < 3:
        raise InspectionError(source, None, None, f"only {len(df)} data row(s); need at least 3")
    # 2-3. Chainage, sensor faults, units.
    chainage = values[CHAINAGE_COLUMN]
    median_step = check_chainage(chainage, source)
    check_sensor_faults(values, source, median_step, max_constant_run_m)
    check_units(values, source, plausible_limit_mm)

    # 4. Sampling.
    data = np.column_stack([values[c] for c in INSPECTION_COLUMNS])
    grid = regrid(chainage, data, source, report, max_gap_m, sampling_tolerance, max_jitter)
    step = grid.step
    data = grid.data

    # 5. Missing values (original NaN and re-inserted rows together).
    missing = check_missing_values(grid, source, report, max_gap_m)
    # 6. Spikes: judged against the median of the neighbours, NaN ignored.
    spikes = find_spikes(data, report, spike_threshold_mm, max_spike_run)
    # Linear interpolation over everything to repair (ends: nearest valid value held).
    x = grid.chainage
    repaired = interpolate_flagged(data, x, missing | spikes, report)

    # 7. Plausibility after the repairs.
    beyond = np.abs(repaired) > plausible_limit_mm
    if beyond.any():
        i, c = (int(v) for v in np.argwhere(beyond)[0])
        row, where = row_of(grid, i)
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
    from scipy import signal   # on use, as in ttbpipe.irregularity.psd.welch_psd

    difference = signal.detrend(difference, type="linear")
    report.cross_level_rms_difference_mm = float(np.sqrt(np.mean(difference ** 2)))
    logger.info("%s: RMS of cross_level - (vertical_left - vertical_right) = %.3f mm "
                "(information; different sensors)", source,
                report.cross_level_rms_difference_mm)

    # 8. Detrending.
    detrend_channels(repaired, x, detrend, report)

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
