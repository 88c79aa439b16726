"""Figures of the TIPM stage (captions: workflow/report/tipm_*.rst)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from .population import PSDPopulation
from .selection import TIPMSelection

__all__ = ["plot_psd_bands", "plot_selection_fidelity", "plot_forecast", "plot_forecast_spectra"]


def _figure(n_rows: int = 1, n_cols: int = 4, size=(15, 4)):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(n_rows, n_cols, figsize=size, squeeze=False, constrained_layout=True)
    return fig, axes


def plot_psd_bands(population: PSDPopulation, selection: TIPMSelection, title: str = ""):
    """Per channel: percentile bands of the sections' PSD ordinates against the weighted
    percentiles of the representative sets, and both means."""
    fig, axes = _figure()
    f = population.frequency_per_m
    pct = np.percentile(population.psd_mm2_m, [5, 25, 50, 75, 95], axis=0)
    order = np.argsort(selection.psd_mm2_m, axis=0)
    cumulative = np.cumsum(selection.weights[order], axis=0)
    sorted_sets = np.take_along_axis(selection.psd_mm2_m, order, axis=0)

    def weighted_percentile(q: float) -> np.ndarray:
        index = np.argmax(cumulative >= q - 1e-12, axis=0)
        return np.take_along_axis(sorted_sets, index[None], axis=0)[0]

    sets_lo, sets_mid, sets_hi = (weighted_percentile(q) for q in (0.05, 0.5, 0.95))
    for c, channel in enumerate(population.channels):
        ax = axes[0, c]
        ax.fill_between(f, pct[0, :, c], pct[4, :, c], color="0.8", label="sections 5-95 %")
        ax.fill_between(f, pct[1, :, c], pct[3, :, c], color="0.6", label="sections 25-75 %")
        ax.plot(f, pct[2, :, c], color="k", lw=1.0, label="sections median")
        ax.plot(f, sets_lo[:, c], color="tab:blue", lw=0.6, label="sets 5 / 50 / 95 % (weighted)")
        ax.plot(f, sets_mid[:, c], color="tab:blue", lw=0.6)
        ax.plot(f, sets_hi[:, c], color="tab:blue", lw=0.6)
        ax.plot(f, population.psd_mm2_m[:, :, c].mean(axis=0), color="tab:red", lw=1.2,
                label="population mean")
        ax.plot(f, selection.weighted_mean()[:, c], color="tab:orange", lw=1.0, ls="--",
                label="weighted mean of sets")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("spatial frequency n (1/m)")
        ax.set_title(channel)
        if c == 0:
            ax.set_ylabel("one-sided PSD (mm²/(1/m))")
            ax.legend(fontsize=7, loc="lower left")
    fig.suptitle(title or f"{population.n_sections} sections, {selection.n_samples} representative sets")
    return fig


def plot_selection_fidelity(population: PSDPopulation, selection: TIPMSelection,
                            metrics: pd.DataFrame | None = None, title: str = ""):
    """Top: weighted mean and std of the sets / population, per frequency. Bottom: ECDF of the
    section band RMS (equivalent TQI): population against the representative sets."""
    fig, axes = _figure(2, 4, (15, 7))
    f = population.frequency_per_m
    ratio_mean = selection.weighted_mean() / population.psd_mm2_m.mean(axis=0)
    ratio_std = selection.weighted_std() / population.psd_mm2_m.std(axis=0)
    tqi_pop, tqi_sel = population.tqi_mm(), selection.tqi_mm()
    for c, channel in enumerate(population.channels):
        ax = axes[0, c]
        ax.axhspan(0.95, 1.05, color="0.9", label="±5 %")
        ax.plot(f, ratio_mean[:, c], label="mean ratio")
        ax.plot(f, ratio_std[:, c], label="std ratio", ls="--")
        ax.set_xscale("log")
        ax.set_ylim(0.5, 1.5)
        ax.set_xlabel("spatial frequency n (1/m)")
        ax.set_title(channel)
        if c == 0:
            ax.set_ylabel("selected sets / population")
            ax.legend(fontsize=7)
        ax = axes[1, c]
        for values, label, weights in ((tqi_pop[:, c], f"{population.n_sections} sections", None),
                                       (tqi_sel[:, c], f"{selection.n_samples} sets", selection.weights)):
            order = np.argsort(values)
            w = np.full(values.size, 1 / values.size) if weights is None else weights[order]
            ax.step(values[order], np.cumsum(w), where="post", label=label)
        ax.set_xlabel("band RMS σ (mm)")
        if metrics is not None:
            row = metrics.set_index("channel").loc[channel]
            ax.set_title(f"KS p = {row['rms_ks_pvalue']:.2f}", fontsize=9)
        if c == 0:
            ax.set_ylabel("cumulative probability")
            ax.legend(fontsize=7)
    fig.suptitle(title)
    return fig


def plot_forecast(tqi: pd.DataFrame, coverage: pd.DataFrame, title: str = ""):
    """Per channel: observed section band RMS over time and the forecast envelopes from the
    last fitted campaign (Monte Carlo 5-95 % band shaded, fixed-p envelope dashed)."""
    fig, axes = _figure(1, 4, (16, 4.5))
    channels = list(dict.fromkeys(tqi["channel"]))
    sections = sorted(tqi["section_start_m"].unique())
    colors = {s: f"C{i % 10}" for i, s in enumerate(sections)}
    for c, channel in enumerate(channels):
        ax = axes[0, c]
        t = tqi[tqi["channel"] == channel]
        obs = t[t["kind"] == "observed"]
        mc = t[t["kind"] == "forecast_mc"]
        fixed = t[t["kind"] == "forecast_fixed_p"]
        levels = sorted(mc["level"].unique())
        for s in sections:
            o = obs[obs["section_start_m"] == s].sort_values("months")
            ax.plot(o["months"], o["tqi_mm"], color=colors[s], lw=0.8, marker=".", ms=3)
            m = mc[mc["section_start_m"] == s]
            lo = m[m["level"] == levels[0]].sort_values("months")
            hi = m[m["level"] == levels[-1]].sort_values("months")
            ax.fill_between(lo["months"], lo["tqi_mm"], hi["tqi_mm"].to_numpy(), color=colors[s], alpha=0.2)
            for level in (levels[0], levels[-1]):
                fx = fixed[(fixed["section_start_m"] == s) & (fixed["level"] == level)].sort_values("months")
                ax.plot(fx["months"], fx["tqi_mm"], color=colors[s], ls="--", lw=0.7)
        ax.axvline(0.0, color="k", lw=0.6)
        cov = coverage[coverage["channel"] == channel]
        ax.set_title(f"{channel}: coverage {cov['coverage_mc'].mean():.2f} "
                     f"(nominal {cov['nominal_coverage'].iloc[0]:.2f})", fontsize=9)
        ax.set_xlabel("months after the last fitted campaign")
        if c == 0:
            ax.set_ylabel("section band RMS σ (mm)")
    fig.suptitle(title or "observed (lines) and forecast band RMS: Monte Carlo band (shaded), "
                 "fixed-p envelope (dashed)")
    return fig


def _band_average(frequency: np.ndarray, values: np.ndarray, n_bands: int = 40):
    """Display smoothing: mean of the ordinates in ``n_bands`` log-spaced frequency bands."""
    edges = np.geomspace(frequency.min(), frequency.max() * (1 + 1e-9), n_bands + 1)
    index = np.digitize(frequency, edges) - 1
    keep = [b for b in range(n_bands) if np.any(index == b)]
    centres = np.array([np.exp(np.log(frequency[index == b]).mean()) for b in keep])
    averaged = np.stack([values[index == b].mean(axis=0) for b in keep])
    return centres, averaged


def plot_forecast_spectra(forecast: pd.DataFrame, selection: TIPMSelection, base_date: str = ""):
    """Per channel: probability-weighted mean PSD of the latest campaign's representative sets
    and of their forecasts (eq. 56, fixed p) at each horizon: p = 0.5 line, p = 0.05-0.95 band.
    Ordinates averaged in 40 log-spaced frequency bands for legibility."""
    fig, axes = _figure(1, 4, (16, 4.5))
    f = selection.frequency_per_m
    fixed = forecast[forecast["envelope"] == "fixed_p"]
    weighted = (fixed.assign(w=fixed["weight"] * fixed["psd_mm2_m"])
                .groupby(["horizon_months", "level", "channel", "spatial_frequency_per_m"])["w"].sum())
    horizons = sorted(fixed["horizon_months"].unique())
    levels = sorted(fixed["level"].unique())
    base_mean = selection.weighted_mean()
    for c, channel in enumerate(selection.channels):
        ax = axes[0, c]
        x, y = _band_average(f, base_mean[:, c])
        ax.plot(x, y, color="k", lw=1.5, label=f"sets {base_date}".strip())
        for i, h in enumerate(horizons):
            curves = {p: weighted.loc[(h, p, channel)].reindex(f).to_numpy() for p in levels}
            color = f"C{i}"
            _, lo = _band_average(f, curves[levels[0]])
            _, hi = _band_average(f, curves[levels[-1]])
            ax.fill_between(x, lo, hi, color=color, alpha=0.2,
                            label=f"{h:g} months, p = {levels[0]:g}-{levels[-1]:g}")
            if 0.5 in curves:
                _, mid = _band_average(f, curves[0.5])
                ax.plot(x, mid, color=color, lw=1.0, label=f"{h:g} months, p = 0.5")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("spatial frequency n (1/m)")
        ax.set_title(channel)
        if c == 0:
            ax.set_ylabel("weighted mean PSD (mm²/(1/m))")
            ax.legend(fontsize=7)
    fig.suptitle("forecast spectra of the representative sets (eq. 56, fixed cumulative probability p)")
    return fig
