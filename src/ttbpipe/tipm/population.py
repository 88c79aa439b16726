"""PSD populations: the per-section spectra of one or more inspection campaigns as one array.

A :class:`PSDPopulation` holds ``psd_mm2_m[section, frequency, channel]`` (one-sided PSD in
mm²/(1/m), spatial frequency in cycles/m) plus a table naming each section (campaign date,
section index, start and end chainage). It is built from the long tables that
``ttbpipe.irregularity.psd.section_psds`` writes (columns ``section, section_start_m,
section_end_m, channel, spatial_frequency_per_m, psd_mm2_m``).

Equivalent track quality index (TQI): the section's band RMS per channel from the discrete
Parseval theorem, σ_c = sqrt(Σ_k S_c(n_k)·Δn) (Xu & Zhai, Railway Eng. Sci. 2020, physics.md §3
step 3).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Sequence

import numpy as np
import pandas as pd

from ..channels import SPECTRAL_CHANNELS
from ..io import read_provenance, read_table, write_table

__all__ = ["PSDPopulation", "PooledSections", "load_population", "pooled_population",
           "write_pooled_population", "read_pooled_population", "synthetic_population",
           "population_dates"]

log = logging.getLogger(__name__)

LONG_COLUMNS = ("section", "section_start_m", "section_end_m", "channel",
                "spatial_frequency_per_m", "psd_mm2_m")
#: Columns of a pooled population table (:meth:`PSDPopulation.to_pooled_table`) besides one
#: ``<channel>_psd_mm2_m`` column per channel.
POOLED_COLUMNS = ("population_section", "campaign_date", "section", "section_start_m",
                  "section_end_m", "spatial_frequency_per_m")
POOLED_PSD_SUFFIX = "_psd_mm2_m"
#: Sections per row group of a pooled table (:func:`write_pooled_population`): a Monte Carlo
#: sample reads the row group that holds its section (:class:`PooledSections`), not the table.
POOLED_SECTIONS_PER_ROW_GROUP = 16


@dataclass
class PSDPopulation:
    """Per-section PSDs of one or more campaigns on a common frequency grid.

    Attributes
    ----------
    psd_mm2_m : ndarray (n_sections, n_frequencies, n_channels)
        One-sided PSD, mm²/(1/m); finite and > 0.
    frequency_per_m : ndarray (n_frequencies,)
        Spatial frequencies, cycles/m, strictly increasing and uniformly spaced.
    channels : tuple of str
        Channel names (a subset of :data:`ttbpipe.channels.SPECTRAL_CHANNELS`, in that order).
    sections : DataFrame
        One row per section: ``campaign_date`` (str), ``section``, ``section_start_m``,
        ``section_end_m``.
    """

    psd_mm2_m: np.ndarray
    frequency_per_m: np.ndarray
    channels: tuple[str, ...]
    sections: pd.DataFrame = field(repr=False)

    def __post_init__(self) -> None:
        self.psd_mm2_m = np.asarray(self.psd_mm2_m, dtype=float)
        self.frequency_per_m = np.asarray(self.frequency_per_m, dtype=float)
        self.channels = tuple(self.channels)
        n_sec, n_freq, n_ch = self.psd_mm2_m.shape
        if self.frequency_per_m.shape != (n_freq,) or len(self.channels) != n_ch:
            raise ValueError(f"PSD array {self.psd_mm2_m.shape} does not match "
                             f"{self.frequency_per_m.size} frequencies and {len(self.channels)} channels")
        if len(self.sections) != n_sec:
            raise ValueError(f"{len(self.sections)} section rows for {n_sec} PSD sections")
        if n_freq < 2 or np.any(np.diff(self.frequency_per_m) <= 0):
            raise ValueError("need at least two strictly increasing frequencies")
        spacing = np.diff(self.frequency_per_m)
        if not np.allclose(spacing, spacing[0], rtol=1e-6):
            raise ValueError("the frequency grid must be uniform (a Welch grid) for the Parseval TQI")
        bad = ~np.isfinite(self.psd_mm2_m) | (self.psd_mm2_m <= 0)
        if bad.any():
            s, k, c = np.argwhere(bad)[0]
            row = self.sections.iloc[s]
            raise ValueError(
                f"{int(bad.sum())} PSD values are not finite and > 0; first: campaign "
                f"{row.get('campaign_date', '?')}, section {row.get('section', s)}, channel "
                f"{self.channels[c]}, n = {self.frequency_per_m[k]:g} 1/m: check the PSD estimate")
        self.sections = self.sections.reset_index(drop=True)

    @property
    def n_sections(self) -> int:
        return self.psd_mm2_m.shape[0]

    @property
    def delta_n_per_m(self) -> float:
        return float(self.frequency_per_m[1] - self.frequency_per_m[0])

    def tqi_mm(self) -> np.ndarray:
        """Equivalent TQI σ (mm) per section and channel, (n_sections, n_channels).

        Discrete Parseval theorem: σ² = Σ_k S(n_k)·Δn over the population's frequency grid
        (Xu & Zhai 2020; physics.md §3 step 3).
        """
        return np.sqrt(self.psd_mm2_m.sum(axis=1) * self.delta_n_per_m)

    def subset(self, index: Sequence[int]) -> "PSDPopulation":
        index = np.asarray(index, dtype=int)
        return PSDPopulation(self.psd_mm2_m[index], self.frequency_per_m, self.channels,
                             self.sections.iloc[index].reset_index(drop=True))

    def to_pooled_table(self) -> pd.DataFrame:
        """The population as one table (one row per section and frequency, section-major; one
        PSD column per channel, ``<channel>_psd_mm2_m``), which :meth:`from_pooled_table` reads
        back bit for bit. A study's Monte Carlo batches read this one file instead of every
        campaign's long table and its pivot (about 2 s per batch on paper case 3's 36 campaigns,
        docs/performance.md)."""
        n_sec, n_freq, _ = self.psd_mm2_m.shape
        rows = np.repeat(np.arange(n_sec), n_freq)
        table = {"population_section": rows,
                 "campaign_date": pd.Categorical(
                     self.sections["campaign_date"].astype(str).to_numpy()[rows]),
                 "section": self.sections["section"].to_numpy()[rows],
                 "section_start_m": self.sections["section_start_m"].to_numpy()[rows],
                 "section_end_m": self.sections["section_end_m"].to_numpy()[rows],
                 "spatial_frequency_per_m": np.tile(self.frequency_per_m, n_sec)}
        for c, channel in enumerate(self.channels):
            table[f"{channel}{POOLED_PSD_SUFFIX}"] = self.psd_mm2_m[:, :, c].reshape(-1)
        return pd.DataFrame(table)

    @classmethod
    def from_pooled_table(cls, table: pd.DataFrame,
                          source: str = "pooled PSD table") -> "PSDPopulation":
        """Population from a table of :meth:`to_pooled_table` (checked: section-major rows, one
        frequency grid for every section, the channels of :data:`SPECTRAL_CHANNELS`)."""
        missing = [c for c in POOLED_COLUMNS if c not in table.columns]
        if missing:
            raise ValueError(f"{source}: missing columns {missing}; expected "
                             f"{list(POOLED_COLUMNS)} and one <channel>{POOLED_PSD_SUFFIX} "
                             "column per channel (a table of PSDPopulation.to_pooled_table)")
        channels = tuple(c for c in SPECTRAL_CHANNELS if f"{c}{POOLED_PSD_SUFFIX}" in table.columns)
        unknown = [c for c in table.columns if c.endswith(POOLED_PSD_SUFFIX)
                   and c[:-len(POOLED_PSD_SUFFIX)] not in SPECTRAL_CHANNELS]
        if unknown or not channels:
            raise ValueError(f"{source}: PSD columns {unknown or 'none'}; expected "
                             f"<channel>{POOLED_PSD_SUFFIX} for channels of {SPECTRAL_CHANNELS}")
        if table.empty:
            raise ValueError(f"{source}: no rows (a population without sections)")
        section = table["population_section"].to_numpy()
        frequency = table["spatial_frequency_per_m"].to_numpy(dtype=float)
        starts = np.flatnonzero(np.r_[True, section[1:] != section[:-1]])
        n_sec = starts.size
        n_freq = len(table) // n_sec
        if (n_sec * n_freq != len(table) or not np.array_equal(section[starts], np.arange(n_sec))
                or not np.array_equal(np.diff(np.r_[starts, len(table)]),
                                      np.full(n_sec, n_freq))):
            raise ValueError(f"{source}: rows are not section-major with one block of "
                             "frequencies per population_section 0, 1, 2, ...")
        grid = frequency[:n_freq]
        other_grid = frequency != np.tile(grid, n_sec)
        if other_grid.any():
            bad = int(np.flatnonzero(other_grid)[0])
            raise ValueError(f"{source}: row {bad}: sections do not share one frequency grid")
        psd = np.stack([table[f"{c}{POOLED_PSD_SUFFIX}"].to_numpy(dtype=float)
                        .reshape(n_sec, n_freq) for c in channels], axis=-1)
        sections = pd.DataFrame({
            "campaign_date": table["campaign_date"].iloc[starts].astype(str).to_numpy(),
            "section": table["section"].to_numpy()[starts],
            "section_start_m": table["section_start_m"].to_numpy()[starts],
            "section_end_m": table["section_end_m"].to_numpy()[starts]})
        return cls(psd, grid, channels, sections)

    @classmethod
    def from_long_table(cls, table: pd.DataFrame, campaign_date: str = "",
                        wavelength_band_m: tuple[float, float] | None = None,
                        source: str = "PSD table") -> "PSDPopulation":
        """Population of one campaign from a ``section_psds`` long table.

        ``wavelength_band_m = (λmin, λmax)`` keeps frequencies 1/λmax <= n <= 1/λmin only (the
        band where the estimate and the standards are meaningful; physics.md §7.6-7).
        """
        missing = [c for c in LONG_COLUMNS if c not in table.columns]
        if missing:
            raise ValueError(f"{source}: missing columns {missing}; expected {list(LONG_COLUMNS)}")
        # Arrays and integer keys instead of DataFrame.pivot: the pivot was nine tenths of
        # loading a campaign (docs/performance.md); same checks, same numbers, same order.
        section = table["section"].to_numpy()
        frequency = table["spatial_frequency_per_m"].to_numpy(dtype=float)
        channel = table["channel"]
        psd_values = table["psd_mm2_m"].to_numpy(dtype=float)
        start_m = table["section_start_m"].to_numpy()
        end_m = table["section_end_m"].to_numpy()
        if wavelength_band_m is not None:
            lam_min, lam_max = (float(v) for v in wavelength_band_m)
            keep = ((frequency >= (1 / lam_max) * (1 - 1e-9))
                    & (frequency <= (1 / lam_min) * (1 + 1e-9)))
            section, frequency, psd_values = section[keep], frequency[keep], psd_values[keep]
            start_m, end_m, channel = start_m[keep], end_m[keep], channel[keep]
        channel_codes, channel_names = pd.factorize(channel.astype(str), sort=False)
        present = set(channel_names)
        channels = tuple(c for c in SPECTRAL_CHANNELS if c in present)
        unknown = present - set(SPECTRAL_CHANNELS)
        if unknown:
            raise ValueError(f"{source}: unknown channels {sorted(unknown)}")
        channel_index = np.array([channels.index(c) for c in channel_names],
                                 dtype=np.int64)[channel_codes]
        sections_idx, first_row, section_index = np.unique(section, return_index=True,
                                                           return_inverse=True)
        freqs, frequency_index = np.unique(frequency, return_inverse=True)
        n_sec, n_freq, n_ch = sections_idx.size, freqs.size, len(channels)
        pair = section_index.astype(np.int64) * n_freq + frequency_index
        key = pair * n_ch + channel_index
        if (np.bincount(key, minlength=n_sec * n_freq * n_ch) > 1).any():
            order = np.argsort(key, kind="stable")
            repeated = key[order][1:] == key[order][:-1]
            # the first row (table order) that repeats an earlier (section, channel, frequency)
            row = int(order[1:][repeated].min())
            raise ValueError(f"{source}: duplicate (section, channel, frequency) at row {row}")
        n_pairs = np.count_nonzero(np.bincount(pair, minlength=n_sec * n_freq))
        if n_pairs != n_sec * n_freq:
            raise ValueError(f"{source}: sections do not share one frequency grid "
                             f"({n_pairs} rows, {n_sec * n_freq} expected)")
        psd = np.full(n_sec * n_freq * n_ch, np.nan)
        psd[key] = psd_values
        if np.isnan(psd).any():
            raise ValueError(f"{source}: missing PSD values for some (section, channel, frequency)")
        sec = pd.DataFrame({"section": sections_idx, "section_start_m": start_m[first_row],
                            "section_end_m": end_m[first_row]})
        sec.insert(0, "campaign_date", str(campaign_date))
        return cls(psd.reshape(n_sec, n_freq, n_ch), freqs, channels, sec)

    @classmethod
    def concat(cls, populations: Iterable["PSDPopulation"]) -> "PSDPopulation":
        """Stack the sections of several populations (same frequency grid and channels)."""
        pops = list(populations)
        if not pops:
            raise ValueError("no populations to concatenate")
        first = pops[0]
        for p in pops[1:]:
            if p.channels != first.channels or p.frequency_per_m.shape != first.frequency_per_m.shape \
                    or not np.allclose(p.frequency_per_m, first.frequency_per_m, rtol=1e-9):
                raise ValueError(f"campaign {p.sections['campaign_date'].iloc[0]!r} has another "
                                 "frequency grid or channel set; use one psd configuration for all")
        return cls(np.concatenate([p.psd_mm2_m for p in pops]), first.frequency_per_m,
                   first.channels, pd.concat([p.sections for p in pops], ignore_index=True))


def population_dates(all_dates: Sequence[str], date: str, window: str | int) -> list[str]:
    """Campaigns whose sections form campaign ``date``'s population: every campaign up to and
    including ``date`` (``window="all"``), or the last ``window`` of them. Never a later one,
    so a campaign's selection cannot change when a later campaign is added."""
    earlier = sorted(d for d in all_dates if d <= date)
    if date not in earlier:
        raise ValueError(f"campaign {date} is not among the campaigns {list(all_dates)}")
    if window == "all":
        return earlier
    window = int(window)
    if window < 1:
        raise ValueError(f"tipm.population_campaigns must be 'all' or >= 1, got {window}")
    return earlier[-window:]


def load_population(paths: Sequence[str | Path], wavelength_band_m) -> list[PSDPopulation]:
    """One population per PSD table ``<date>.parquet`` (the campaign date is the file stem)."""
    band = None if wavelength_band_m is None else tuple(wavelength_band_m)
    pops = []
    for path in sorted(paths, key=lambda p: Path(p).stem):
        pops.append(PSDPopulation.from_long_table(read_table(path), Path(path).stem, band,
                                                  source=str(path)))
    return pops


def pooled_population(paths: Sequence[str | Path], wavelength_band_m) -> PSDPopulation:
    """The sections of every PSD table ``<date>.parquet`` in one population (date order)."""
    return PSDPopulation.concat(load_population(paths, wavelength_band_m))


def write_pooled_population(paths: Sequence[str | Path], wavelength_band_m,
                            out: str | Path, **provenance: Any) -> PSDPopulation:
    """Pool the PSD tables ``paths`` (band applied) into one table at ``out`` (written
    atomically; its provenance names the band and the campaigns, which
    :func:`read_pooled_population` checks)."""
    population = pooled_population(paths, wavelength_band_m)
    band = None if wavelength_band_m is None else [float(b) for b in wavelength_band_m]
    write_table(population.to_pooled_table(), out, kind="pooled_psd_population",
                row_group_size=population.frequency_per_m.size * POOLED_SECTIONS_PER_ROW_GROUP,
                wavelength_band_m=band,
                campaigns=sorted(set(population.sections["campaign_date"].astype(str))),
                **provenance)
    return population


def _check_pooled_band(path: str | Path, wavelength_band_m) -> None:
    """Refuse a pooled table written for another wavelength band than ``wavelength_band_m``."""
    written = read_provenance(path).get("wavelength_band_m")
    wanted = None if wavelength_band_m is None else [float(b) for b in wavelength_band_m]
    if written != wanted:
        raise ValueError(f"{path}: pooled over the wavelength band {written} m, the study asks "
                         f"for {wanted} m; pool the PSD tables again with the study's psd."
                         "wavelength_band_m (workflow rule study_mc_population)")


def read_pooled_population(path: str | Path, wavelength_band_m) -> PSDPopulation:
    """The population of :func:`write_pooled_population`'s table, which must have been pooled
    over ``wavelength_band_m`` (the same frequencies :func:`load_population` would keep)."""
    _check_pooled_band(path, wavelength_band_m)
    return PSDPopulation.from_pooled_table(read_table(path), source=str(path))


class PooledSections:
    """The sections of a pooled table (:func:`write_pooled_population`), read as asked for.

    A Monte Carlo batch draws a few dozen of the population's sections (paper case 3: 50 of
    3 060); reading the whole table, 51 MB, and checking it took 0.5-1.6 s of every batch. Here
    each section is read from the row groups that hold it (the ``population_section``
    statistics of the file's row groups locate it; :data:`POOLED_SECTIONS_PER_ROW_GROUP`
    sections per group), the last few groups kept, and checked as
    :meth:`PSDPopulation.from_pooled_table` checks a table. The band is checked on opening; the
    whole table is read and checked once per study by the design of the scenario
    (:func:`read_pooled_population`). A table without the statistics is read whole, once.
    """

    #: Row groups kept in memory (a batch's sections are drawn at random).
    KEPT_GROUPS = 4

    def __init__(self, path: str | Path, wavelength_band_m):
        import pyarrow.parquet as pq

        _check_pooled_band(path, wavelength_band_m)
        self.path = str(path)
        self._file = pq.ParquetFile(self.path)
        self._groups: dict[int, tuple] = {}
        self._grid: np.ndarray | None = None
        self._ranges = self._group_ranges()
        self._whole = None
        if self._ranges is None:
            self._whole = PSDPopulation.from_pooled_table(read_table(self.path), source=self.path)

    def _group_ranges(self) -> list[tuple[int, int]] | None:
        """(first, last) population_section of every row group, checked to be section-major
        from 0; None when the file has no statistics for it."""
        meta = self._file.metadata
        column = self._file.schema_arrow.get_field_index("population_section")
        if column < 0:
            raise ValueError(f"{self.path}: missing column population_section (a table of "
                             "PSDPopulation.to_pooled_table)")
        ranges = []
        for g in range(meta.num_row_groups):
            stats = meta.row_group(g).column(column).statistics
            if stats is None or not stats.has_min_max:
                return None
            ranges.append((int(stats.min), int(stats.max)))
        previous = -1
        for g, (first, last) in enumerate(ranges):
            if first > last or first not in (previous, previous + 1):
                raise ValueError(f"{self.path}: row group {g} holds population_section "
                                 f"{first}-{last} after {previous}; rows are not section-major "
                                 "with population_section 0, 1, 2, ...")
            previous = last
        return ranges

    @property
    def n_sections(self) -> int:
        if self._whole is not None:
            return self._whole.n_sections
        return self._ranges[-1][1] + 1 if self._ranges else 0

    def _group(self, g: int):
        """Row group ``g`` (an Arrow table) and its population_section column."""
        if g not in self._groups:
            if len(self._groups) >= self.KEPT_GROUPS:
                self._groups.pop(next(iter(self._groups)))
            table = self._file.read_row_group(g, use_threads=False)
            self._groups[g] = (table, table.column("population_section").to_numpy())
        return self._groups[g]

    def section(self, section: int) -> PSDPopulation:
        """Population section ``section`` alone (a population of one section)."""
        import pyarrow as pa

        section = int(section)
        if not 0 <= section < self.n_sections:
            raise ValueError(f"{self.path}: section {section} outside the population of "
                             f"{self.n_sections} sections")
        if self._whole is not None:
            return self._whole.subset([section])
        parts = []
        for g, (first, last) in enumerate(self._ranges):
            if first <= section <= last:
                table, sections = self._group(g)
                parts.append(table.take(np.flatnonzero(sections == section)))
        rows = (pa.concat_tables(parts) if len(parts) > 1 else parts[0]).to_pandas()
        source = f"{self.path}, population_section {section}"
        if rows.empty:
            raise ValueError(f"{source}: no rows; rows are not section-major with one block "
                             "of frequencies per population_section 0, 1, 2, ...")
        one = PSDPopulation.from_pooled_table(
            rows.assign(population_section=0).reset_index(drop=True), source=source)
        if self._grid is None:
            self._grid = one.frequency_per_m
        elif not np.array_equal(one.frequency_per_m, self._grid):
            raise ValueError(f"{source}: sections do not share one frequency grid")
        return one


def synthetic_population(n_sections: int, frequency_per_m: np.ndarray, mean_psd: np.ndarray,
                         rng: np.random.Generator, level_sigma_log: float = 0.4,
                         channel_correlation: float = 0.7, welch_dof: float | None = 12.0,
                         channels: Sequence[str] = SPECTRAL_CHANNELS,
                         campaign_date: str = "synthetic") -> PSDPopulation:
    """A population with known statistics, for tests and benchmarks.

    S_i(n, c) = mean_psd(n, c) · L_ic · X_inc, with section levels
    log L_ic ~ N(-σ²/2, σ²) equicorrelated across channels (correlation ``channel_correlation``)
    so that E[L] = 1, and estimation scatter X ~ χ²_ν/ν (Welch-averaged ordinates,
    physics.md §2: ≈ χ²_{2K}/2K) independent per ordinate, or X = 1 when ``welch_dof`` is None.
    Then E[S] = mean_psd and Var[S] = mean_psd²·(E[L²]E[X²] − 1) with E[L²] = exp(σ²) and
    E[X²] = 1 + 2/ν.
    """
    mean_psd = np.asarray(mean_psd, dtype=float)
    n_ch = len(channels)
    corr = np.full((n_ch, n_ch), channel_correlation) + (1 - channel_correlation) * np.eye(n_ch)
    # Cholesky, not numpy's default SVD: the equicorrelation matrix has a repeated eigenvalue, so
    # its singular vectors (and the draws) depend on the LAPACK kernel of the machine (OpenBLAS
    # picks AVX-512 or AVX2 code at run time); the Cholesky factor is unique.
    z = rng.multivariate_normal(np.zeros(n_ch), corr, size=n_sections, method="cholesky")
    levels = np.exp(level_sigma_log * z - 0.5 * level_sigma_log ** 2)
    psd = mean_psd[None, :, :] * levels[:, None, :]
    if welch_dof is not None:
        psd = psd * rng.chisquare(welch_dof, size=psd.shape) / welch_dof
    sections = pd.DataFrame({"campaign_date": campaign_date, "section": np.arange(n_sections),
                             "section_start_m": np.arange(n_sections) * 1000.0,
                             "section_end_m": (np.arange(n_sections) + 1) * 1000.0})
    return PSDPopulation(psd, np.asarray(frequency_per_m, float), tuple(channels), sections)
