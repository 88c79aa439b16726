"""The report of one campaign's cleaning: what the checks found and what the repairs changed.

:class:`CleaningReport` is filled in by :func:`ttbpipe.inspection.validate.clean_campaign` and
its steps (:mod:`.checks`, :mod:`.grid`, :mod:`.repairs`), printed by the ``check-inspection``
command (:meth:`CleaningReport.summary`) and written as JSON next to every cleaned campaign
(:meth:`CleaningReport.to_dict`).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from typing import Any

from ..channels import INSPECTION_COLUMNS
from ..io import jsonable

# Every step of the cleaning logs under the name of its entry point's module, so that one logger
# (and one log filter) covers the whole cleaning of a campaign.
logger = logging.getLogger("ttbpipe.inspection.validate")

#: Repair kinds counted in :class:`CleaningReport` ``repairs`` (samples per channel).
REPAIR_KINDS: tuple[str, ...] = ("regridded", "dropout_interpolated", "nan_interpolated",
                                 "spike_replaced")


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
