"""Figures of the irregularity stage.

:func:`plot_psd_vs_standard` draws the estimated PSDs of all inspection campaigns against a
standard spectrum, one panel per spectral channel.
"""

from __future__ import annotations

import datetime as _dt
import logging
from typing import Mapping

import numpy as np
import pandas as pd
import matplotlib
from matplotlib import cm, colors
from matplotlib.figure import Figure

from ..channels import SPECTRAL_CHANNELS
from .spectra import TrackSpectrum, get_spectrum

__all__ = ["plot_psd_vs_standard", "campaign_mean_psd"]

log = logging.getLogger(__name__)

CHANNEL_TITLES = {"vertical": "Vertical profile", "alignment": "Alignment",
                  "cross_level": "Cross-level", "gauge": "Gauge"}


def campaign_mean_psd(table: pd.DataFrame) -> pd.DataFrame:
    """Mean PSD over the sections of one campaign: columns ``channel,
    spatial_frequency_per_m, psd_mm2_m`` (arithmetic mean of the section PSDs per frequency)."""
    return (table.groupby(["channel", "spatial_frequency_per_m"], as_index=False)["psd_mm2_m"]
            .mean())


def _date_or_none(label: str) -> _dt.date | None:
    try:
        return _dt.date.fromisoformat(str(label))
    except ValueError:
        return None


def _section_matrix(tables: Mapping[str, pd.DataFrame], channel: str, grid: np.ndarray | None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """(frequencies, PSD matrix sections x frequencies) of one channel over all campaigns.

    With ``grid=None`` all campaigns share one frequency grid; otherwise each section's PSD is
    interpolated log-log onto ``grid`` (NaN outside its own range)."""
    rows, freq = [], grid
    for table in tables.values():
        # one sort per table instead of a pandas group per section (36 campaigns x 4 channels x
        # their sections made the figure's data slower to gather than to draw)
        sub = table.loc[table["channel"] == channel, ["section", "spatial_frequency_per_m",
                                                      "psd_mm2_m"]]
        sub = sub.sort_values(["section", "spatial_frequency_per_m"], kind="stable")
        _, starts = np.unique(sub["section"].to_numpy(), return_index=True)   # rows are sorted
        freq_all = sub["spatial_frequency_per_m"].to_numpy()
        psd_all = sub["psd_mm2_m"].to_numpy()
        for start, stop in zip(starts, [*starts[1:], len(sub)]):
            f, p = freq_all[start:stop], psd_all[start:stop]
            if grid is None:
                freq = f
                rows.append(p)
            else:
                ok = (f > 0) & (p > 0)
                values = np.exp(np.interp(np.log(grid), np.log(f[ok]), np.log(p[ok]),
                                          left=np.nan, right=np.nan))
                rows.append(values)
    return np.asarray(freq), np.vstack(rows)


def plot_psd_vs_standard(psd_by_campaign: Mapping[str, pd.DataFrame],
                         reference_spectrum: str | TrackSpectrum | None = "tbt3352",
                         wavelength_band_m: tuple[float, float] | None = (2.0, 200.0),
                         *, percentiles: tuple[float, float] = (5.0, 95.0)) -> Figure:
    """2x2 log-log figure, one panel per spectral channel.

    * thin lines: mean over sections of each campaign (:func:`campaign_mean_psd`), coloured by
      campaign date (colour bar);
    * grey band: the ``percentiles`` (default 5-95 %) of all section PSDs of all campaigns at each
      frequency (the population the TIPM samples from);
    * thick dashed black line: ``reference_spectrum`` over its valid band within the plotted band;
    * dotted vertical lines: the wavelength band ``wavelength_band_m`` (top axis: wavelength).

    ``psd_by_campaign`` maps a campaign label (ISO date ``YYYY-MM-DD`` for colouring by date) to
    its long-format PSD table (:func:`ttbpipe.irregularity.psd.section_psds`).
    """
    if not psd_by_campaign:
        raise ValueError("no PSD tables to plot")
    labels = sorted(psd_by_campaign)
    dates = [_date_or_none(label) for label in labels]
    if all(d is not None for d in dates):
        ordinals = np.array([d.toordinal() for d in dates], dtype=float)
    else:
        ordinals = np.arange(len(labels), dtype=float)
    norm = colors.Normalize(ordinals.min(), ordinals.max() if ordinals.max() > ordinals.min()
                            else ordinals.min() + 1.0)
    cmap = matplotlib.colormaps["viridis"]

    frequency_sets = {tuple(np.round(np.sort(t["spatial_frequency_per_m"].unique()), 12))
                      for t in psd_by_campaign.values()}
    common_grid = None
    if len(frequency_sets) > 1:
        lo = max(min(s) for s in frequency_sets)
        hi = min(max(s) for s in frequency_sets)
        common_grid = np.geomspace(lo, hi, 400)
        log.info("campaign PSDs have different frequency grids; the percentile band is computed "
                 "on a common log grid of %d points (%g-%g 1/m)", common_grid.size, lo, hi)

    reference = get_spectrum(reference_spectrum) if isinstance(reference_spectrum, str) \
        else reference_spectrum

    means = {label: dict(tuple(campaign_mean_psd(psd_by_campaign[label]).groupby("channel")))
             for label in labels}
    fig = Figure(figsize=(11.0, 8.5), layout="constrained")
    axes = fig.subplots(2, 2)
    for ax, channel in zip(axes.flat, SPECTRAL_CHANNELS):
        freq, matrix = _section_matrix(psd_by_campaign, channel, common_grid)
        with np.errstate(all="ignore"):
            # numpy's nanpercentile runs a Python loop over the columns; without a NaN (every
            # campaign on one frequency grid) np.percentile gives the same numbers at once
            low, high = (np.nanpercentile(matrix, percentiles, axis=0) if np.isnan(matrix).any()
                         else np.percentile(matrix, percentiles, axis=0))
        ax.fill_between(freq, low, high, color="0.75", alpha=0.7, lw=0,
                        label=f"all sections, {percentiles[0]:g}-{percentiles[1]:g} %")
        for label, ordinal in zip(labels, ordinals):
            mean = means[label].get(channel)
            if mean is None:
                continue
            mean = mean[mean["spatial_frequency_per_m"] > 0]
            ax.plot(mean["spatial_frequency_per_m"], mean["psd_mm2_m"], lw=0.6,
                    color=cmap(norm(ordinal)), alpha=0.9)
        if reference is not None:
            lo_n, hi_n = reference.valid_frequency_band_per_m
            if wavelength_band_m is not None:
                lo_n = max(lo_n, 1.0 / wavelength_band_m[1])
                hi_n = min(hi_n, 1.0 / wavelength_band_m[0])
            n = np.geomspace(lo_n, hi_n, 400)
            ax.plot(n, reference.psd_mm2_m(channel, n), "k--", lw=2.5, zorder=5,
                    label=f"{reference.name} (standard)")
        if wavelength_band_m is not None:
            for lam in wavelength_band_m:
                ax.axvline(1.0 / lam, color="k", ls=":", lw=1.0)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("spatial frequency n (1/m)")
        ax.set_ylabel("one-sided PSD (mm²/(1/m))")
        ax.set_title(CHANNEL_TITLES[channel])
        ax.grid(True, which="major", lw=0.4, alpha=0.5)
        top = ax.secondary_xaxis("top", functions=(lambda n: 1.0 / np.maximum(n, 1e-12),
                                                   lambda lam: 1.0 / np.maximum(lam, 1e-12)))
        top.set_xlabel("wavelength (m)")
    axes.flat[0].legend(loc="lower left", fontsize=8)
    mappable = cm.ScalarMappable(norm=norm, cmap=cmap)
    colorbar = fig.colorbar(mappable, ax=axes, shrink=0.6, pad=0.01)
    if all(d is not None for d in dates):
        ticks = np.linspace(ordinals.min(), ordinals.max(), min(6, len(labels)))
        colorbar.set_ticks(ticks)
        colorbar.set_ticklabels([_dt.date.fromordinal(int(round(t))).isoformat() for t in ticks])
        colorbar.set_label("campaign date (thin lines: campaign mean over sections)")
    else:
        colorbar.set_label("campaign (order)")
    band_text = "" if wavelength_band_m is None else \
        f"; dotted: band {wavelength_band_m[0]:g}-{wavelength_band_m[1]:g} m"
    fig.suptitle(f"Estimated track-irregularity PSDs of {len(labels)} campaigns vs "
                 f"{reference.name if reference is not None else 'no standard'}{band_text}")
    return fig
