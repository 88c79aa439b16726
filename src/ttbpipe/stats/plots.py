"""Figures of the statistics and reliability layer (matplotlib, no pyplot state).

Every function returns a :class:`matplotlib.figure.Figure`; save it with
:func:`ttbpipe.io.save_figure`. Axes carry quantities and units taken from the column names
(``docs/results_schema.md``).

* :func:`plot_exceedance_convergence`: estimate and confidence band against the number of samples;
* :func:`plot_extreme_pdfs`: PDFs of an extreme per scenario (full vs single excitation, paper
  Figs. 15-16);
* :func:`plot_history_statistics`: mean and standard deviation against time or position per
  scenario (Figs. 10-14);
* :func:`plot_forecast_envelope`: mean and lower/upper quantiles against forecast horizon (Fig. 17).
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from .streaming import HistoryStatistics
from .kde import ExtremeValueKDE, bounds_for
from .schema import unit_of

_UNIT_TEX = {"m/s^2": "m/s²", "rad/s^2": "rad/s²", "1": ""}

_NAMES = {
    "max_derailment_coefficient": "max. derailment coefficient Q/P",
    "max_wheel_unloading_ratio": "max. wheel unloading ratio ΔP/P₀",
    "max_lateral_wheelset_force_N": "max. lateral wheelset force H",
    "max_wheel_vertical_force_N": "max. wheel-rail vertical force",
    "max_wheel_lateral_force_N": "max. wheel-rail lateral force",
    "max_carbody_vertical_acc_m_s2": "max. car-body vertical acceleration",
    "max_carbody_lateral_acc_m_s2": "max. car-body lateral acceleration",
    "sperling_vertical": "Sperling index, vertical",
    "sperling_lateral": "Sperling index, lateral",
    "max_deck_vertical_acc_m_s2": "max. deck vertical acceleration",
    "max_deck_lateral_acc_m_s2": "max. deck lateral acceleration",
    "max_rail_vertical_acc_m_s2": "max. rail vertical acceleration",
    "max_rail_lateral_acc_m_s2": "max. rail lateral acceleration",
    "max_girder_vertical_disp_m": "max. girder vertical displacement",
    "time_s": "time", "position_m": "position along the track",
}

_SUFFIXES = ("_m_s2", "_rad_s2", "_m_s", "_rad_s", "_N_m", "_Pa", "_rad", "_N", "_m", "_s")


def display_scale(column: str) -> tuple[float, str]:
    """(factor, unit) for display: forces in kN and displacements in mm, everything else SI.

    Values are multiplied by ``factor`` only when drawn; tables and files stay SI.
    """
    try:
        unit = unit_of(column)
    except ValueError:
        return 1.0, "?"
    if unit == "N":
        return 1e-3, "kN"
    if unit == "m" and "disp" in column:
        return 1e3, "mm"
    return 1.0, _UNIT_TEX.get(unit, unit)


def axis_label(column: str) -> str:
    """Readable axis label with display unit, e.g. ``'max. deck vertical acceleration (m/s²)'``."""
    unit = display_scale(column)[1]
    name = _NAMES.get(column)
    if name is None:
        stem = column
        for suffix in _SUFFIXES:
            if stem.endswith(suffix):
                stem = stem[: -len(suffix)]
                break
        name = stem.replace("_", " ").replace("acc", "acceleration").replace("disp", "displacement")
    return f"{name} ({unit})" if unit else f"{name} (–)"


def _figure(nrows: int = 1, ncols: int = 1, width: float = 6.4, height: float = 3.6, **kw):
    fig = Figure(figsize=(width * ncols, height * nrows), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False, **kw)
    return fig, axes


def plot_exceedance_convergence(curves: Sequence[pd.DataFrame], *, log_x: bool = True,
                                ncols: int = 2) -> Figure:
    """One panel per curve of :func:`ttbpipe.stats.reliability.convergence_curve`.

    Estimate (line) and two-sided confidence band (shaded; the one interval of every probability
    the study reports) against the number of samples in sample-index order.
    """
    curves = list(curves)
    if not curves:
        raise ValueError("no convergence curves to plot")
    ncols = min(ncols, len(curves))
    nrows = int(np.ceil(len(curves) / ncols))
    fig, axes = _figure(nrows, ncols, width=5.0, height=3.4)
    for ax, curve in zip(axes.flat, curves):
        n = curve["n_samples"].to_numpy()
        a = curve.attrs
        level = f"{100 * a.get('confidence_level', 0.95):g} %"
        ax.fill_between(n, curve["ci_low"], curve["ci_high"], step="post", alpha=0.3,
                        label=f"{level} CI ({a.get('method', '')})")
        ax.step(n, curve["probability"], where="post", color="C0", label="estimate")
        if "sufficient" in curve and bool(curve["sufficient"].iloc[-1]):
            failing = np.flatnonzero(~curve["sufficient"].to_numpy(dtype=bool))
            n_ok = n[failing[-1] + 1] if failing.size else n[0]
            ax.axvline(n_ok, color="k", ls=":", lw=1, label=f"sufficient from n = {n_ok}")
        if log_x and n[-1] > 20:
            ax.set_xscale("log")
        ax.set_xlabel("number of samples (sample-index order)")
        ax.set_ylabel("P(index > limit) (–)")
        ax.set_ylim(bottom=0)
        threshold = str(a.get("threshold", "")).replace("^2", "²")
        ax.set_title(f"{a.get('description', a.get('limit', ''))} > {threshold}\n"
                     f"scenario {a.get('scenario', '')}", fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    for ax in list(axes.flat)[len(curves):]:
        ax.set_visible(False)
    return fig


def plot_extreme_pdfs(extremes: pd.DataFrame, column: str, *, scenarios: Sequence[str] | None = None,
                      labels: Mapping[str, str] | None = None, threshold: float | None = None,
                      boundary: str = "auto", ax=None) -> Figure:
    """PDF of one extreme per scenario (weighted KDE, :class:`ExtremeValueKDE`).

    A scenario with a single sample or no spread (e.g. 'single' excitation with the average
    irregularity) is drawn as a vertical line at its value, as in the paper's Figs. 15-16.
    ``threshold``: the limit, drawn as a dotted vertical line.
    """
    scenarios = list(scenarios) if scenarios is not None else sorted(extremes["scenario"].unique())
    labels = dict(labels or {})
    if ax is None:
        fig, axes = _figure()
        ax = axes[0, 0]
    else:
        fig = ax.figure
    lower, upper = bounds_for(column)
    factor, unit = display_scale(column)
    for i, scenario in enumerate(scenarios):
        block = extremes[extremes["scenario"] == scenario]
        if block.empty:
            raise ValueError(f"no samples for scenario {scenario!r}")
        values = block[column].to_numpy(dtype=float)
        label = labels.get(scenario, str(scenario))
        if values.size < 2 or np.ptp(values) == 0:
            ax.axvline(values[0] * factor, color=f"C{i}", lw=2, label=f"{label} (single value)")
            continue
        kde = ExtremeValueKDE(values, block["weight"].to_numpy(dtype=float), lower=lower,
                              upper=upper, boundary=boundary)
        x, pdf = kde.grid()
        ax.plot(x * factor, pdf / factor, color=f"C{i}", label=f"{label} (n = {values.size})")
    if threshold is not None:
        ax.axvline(threshold * factor, color="k", ls=":", label="limit")
    ax.set_xlabel(axis_label(column))
    per = (f"1/({unit})" if "/" in unit else f"1/{unit}") if unit else "–"
    ax.set_ylabel(f"probability density ({per})")
    ax.set_ylim(bottom=0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def plot_history_statistics(results: Mapping[tuple[str, str], HistoryStatistics], quantity: str, *,
                            scenarios: Sequence[str] | None = None,
                            band: tuple[float, float] | None = None) -> Figure:
    """Mean (top) and standard deviation (bottom) of a quantity against time or position.

    One line per scenario (randomness conditions, TIPM vs MCM, ...), as the paper's Figs. 10-14;
    ``band``: weighted quantiles shaded around the mean when they were aggregated.
    """
    keys = [k for k in results if k[1] == quantity]
    if not keys:
        raise ValueError(f"no statistics for quantity {quantity!r}")
    scenarios = list(scenarios) if scenarios is not None else sorted(k[0] for k in keys)
    fig, axes = _figure(2, 1, sharex=True, height=3.0)
    factor = display_scale(quantity)[0]
    for i, scenario in enumerate(scenarios):
        r = results[(scenario, quantity)]
        axes[0, 0].plot(r.abscissa, r.mean * factor, color=f"C{i}", lw=1,
                        label=f"{scenario} (n = {r.n_samples})")
        if band and band[0] in r.quantiles and band[1] in r.quantiles:
            axes[0, 0].fill_between(r.abscissa, r.quantiles[band[0]] * factor,
                                    r.quantiles[band[1]] * factor, color=f"C{i}", alpha=0.12, lw=0)
        axes[1, 0].plot(r.abscissa, r.std * factor, color=f"C{i}", lw=1, label=scenario)
    r0 = results[keys[0]]
    axes[0, 0].set_ylabel("mean of\n" + axis_label(quantity))
    axes[1, 0].set_ylabel("standard deviation of\n" + axis_label(quantity))
    axes[1, 0].set_xlabel(axis_label(r0.abscissa_name))
    if band:
        axes[0, 0].set_title(f"shaded: weighted {100 * band[0]:g}-{100 * band[1]:g} % quantiles",
                             fontsize=8)
    for ax in axes.flat:
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    return fig


def plot_forecast_envelope(envelope: pd.DataFrame, *, threshold: float | None = None,
                           ax=None) -> Figure:
    """Mean and lower/upper quantile envelope of an index against forecast horizon (Fig. 17).

    ``envelope`` from :func:`ttbpipe.stats.tables.forecast_envelope`; ISO-date scenarios are
    placed on a date axis, others at equal spacing in the given order.
    """
    if ax is None:
        fig, axes = _figure()
        ax = axes[0, 0]
    else:
        fig = ax.figure
    column = envelope.attrs.get("column", "")
    dates = pd.to_datetime(envelope["scenario"], format="%Y-%m-%d", errors="coerce")
    if dates.notna().all():
        x = dates.to_numpy()
        ax.set_xlabel("campaign / forecast date")
    else:
        x = np.arange(len(envelope))
        ax.set_xticks(x, envelope["scenario"].astype(str), rotation=30, ha="right")
        ax.set_xlabel("scenario (forecast horizon)")
    lo_q, hi_q = envelope.attrs.get("lower_q", 0.05), envelope.attrs.get("upper_q", 0.95)
    factor = display_scale(column)[0] if column else 1.0
    ax.fill_between(x, envelope["lower"] * factor, envelope["upper"] * factor, alpha=0.25,
                    label=f"weighted {100 * lo_q:g}-{100 * hi_q:g} % quantiles")
    ax.plot(x, envelope["mean"] * factor, marker="o", ms=3, label="weighted mean")
    ax.plot(x, envelope["lower"] * factor, lw=0.8, color="C0", ls="--")
    ax.plot(x, envelope["upper"] * factor, lw=0.8, color="C0", ls="--")
    if threshold is not None:
        ax.axhline(threshold * factor, color="k", ls=":", label="limit")
    ax.set_ylabel(axis_label(column) if column else "index")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return fig
