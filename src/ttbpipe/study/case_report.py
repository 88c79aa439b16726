"""Figures, tables and summaries of the seed paper's case studies (docs/validation.md).

:func:`sweep_report` (case 1: Figs. 6-8, eq. 55) and :func:`compare_report` (cases 2-4: Table 1,
Figs. 9-17) turn the case outputs into the figures and the short markdown summary that
docs/validation.md compares with the paper. Figures draw forces in kN, displacements in mm.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import pandas as pd

from .. import io
from .cases import (SWEEP_SPEED_FACTOR, bridge_frequencies, compare_histories, forecast_limits,
                    resonance_speeds, sweep_resonances, train_load_interval_m)
from .samples import resolve_simulation

log = logging.getLogger(__name__)


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, folder: Path, name: str) -> Path:
    path = io.save_figure(fig, folder / name, dpi=110)
    _plt().close(fig)
    return path


# ----------------------------------------------------------------------------------------------
# Case 1

def sweep_report(sweep: pd.DataFrame, history: pd.DataFrame, layout: Mapping[str, Any],
                 config: Mapping[str, Any], figures: str | Path) -> tuple[pd.DataFrame, str]:
    """Case 1: (resonance table, markdown summary); writes fig06/fig07/fig08 PNGs."""
    plt = _plt()
    folder = Path(figures)
    folder.mkdir(parents=True, exist_ok=True)
    sweep_cfg = dict((config.get("case") or {}).get("sweep") or {})
    sim = resolve_simulation(config.get("simulation"))
    interval = sweep_cfg.get("load_interval_m") or train_load_interval_m(sim["train"])
    freqs = bridge_frequencies(config["structure"])
    lo, hi = float(sweep["speed_kmh"].min()), float(sweep["speed_kmh"].max())
    predicted = resonance_speeds(freqs, interval, (lo, hi))
    step = float(np.median(np.diff(np.sort(sweep["speed_kmh"].unique())))) if len(sweep) > 1 else 10.0
    window = max(2.0 * step, 0.08 * 0.5 * (lo + hi))
    rows = []
    for direction, column in (("vertical", "max_deck_vertical_acc_m_s2"),
                              ("lateral", "max_deck_lateral_acc_m_s2")):
        pred = predicted[predicted["direction"] == direction]
        found = sweep_resonances(sweep, column, pred["speed_kmh"].tolist(), window)
        if len(found):
            found = found.assign(direction=direction, order=pred["order"].to_numpy()[:len(found)],
                                 frequency_hz=freqs[direction], load_interval_m=float(interval))
            rows.append(found)
    resonance = pd.concat(rows, ignore_index=True) if rows else pd.DataFrame(
        columns=["quantity", "predicted_kmh", "peak_kmh", "peak_value", "ratio_to_median",
                 "direction", "order", "frequency_hz", "load_interval_m"])

    # Fig. 8: maxima against speed, predicted resonances marked
    line_speed = (None if sweep_cfg.get("line_speed_kmh") is None
                  else float(sweep_cfg["line_speed_kmh"]))
    panels = [("max_wheel_vertical_force_N", 1e-3, "max wheel-rail vertical force (kN)"),
              ("max_wheel_lateral_force_N", 1e-3, "max wheel-rail lateral force (kN)"),
              ("max_deck_vertical_acc_m_s2", 1.0, "max midspan vertical acc. (m/s$^2$)"),
              ("max_deck_lateral_acc_m_s2", 1.0, "max midspan lateral acc. (m/s$^2$)")]
    fig, axes = plt.subplots(2, 2, figsize=(10, 6.5), sharex=True)
    for ax, (column, scale, label) in zip(axes.ravel(), panels):
        ax.plot(sweep["speed_kmh"], sweep[column] * scale, "o-", ms=3, lw=1)
        for r in predicted.itertuples():
            ax.axvline(r.speed_kmh, color="C3" if r.direction == "vertical" else "C2", ls="--",
                       lw=0.8, alpha=0.7)
        if line_speed is not None:
            for v, style in ((line_speed, ":"), (SWEEP_SPEED_FACTOR * line_speed, "-.")):
                ax.axvline(v, color="0.3", ls=style, lw=0.9)
        ax.set_ylabel(label, fontsize=9)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("train speed (km/h)")
    marks = ("" if line_speed is None else
             f"; dotted: line speed {line_speed:g} km/h, dash-dot: {SWEEP_SPEED_FACTOR:g} x it "
             "(EN 1991-2 6.4.6.2)")
    fig.suptitle(f"Case 1 (Fig. 8): maxima against speed; dashed: eq. 55 with f_v = "
                 f"{freqs['vertical']:.2f} Hz (red), f_l = {freqs['lateral']:.2f} Hz (green), "
                 f"L_g = {interval:g} m{marks}", fontsize=9)
    _save(fig, folder, "fig08_maxima_vs_speed.png")

    # Fig. 6: rail displacement under the wheel
    t = history["time_s"].to_numpy()
    fig, axes = plt.subplots(2, 1, figsize=(9, 5), sharex=True)
    for ax, name, label in ((axes[0], "rail_vertical_disp_m", "rail vertical disp. (mm)"),
                            (axes[1], "rail_lateral_disp_m", "rail lateral disp. (mm)")):
        ax.plot(history["x_wheel_m"], 1e3 * history[name], lw=0.8)
        for edge in np.arange(layout.get("bridge_start_m", 0), layout.get("bridge_end_m", 0) + 1,
                              layout.get("span_length_m", 32.0)):
            ax.axvline(edge, color="0.6", lw=0.6, ls=":")
        ax.set_ylabel(label, fontsize=9)
        ax.grid(alpha=0.3)
    axes[1].set_xlabel(f"position of wheelset {layout.get('wheel', '')} (m); dotted: piers")
    fig.suptitle(f"Case 1 (Fig. 6): left rail under the trailer's 1st wheelset, "
                 f"{layout.get('speed_kmh', 300):g} km/h", fontsize=9)
    _save(fig, folder, "fig06_rail_displacement_under_wheel.png")

    # Fig. 7: girder midspan
    fig, axes = plt.subplots(2, 2, figsize=(10, 5.5), sharex=True)
    for ax, name, scale, label in (
            (axes[0, 0], "girder_vertical_disp_m", 1e3, "vertical disp. (mm)"),
            (axes[0, 1], "girder_lateral_disp_m", 1e3, "lateral disp. (mm)"),
            (axes[1, 0], "girder_vertical_acc_m_s2", 1.0, "vertical acc. (m/s$^2$)"),
            (axes[1, 1], "girder_lateral_acc_m_s2", 1.0, "lateral acc. (m/s$^2$)")):
        ax.plot(t, history[name] * scale, lw=0.7)
        ax.set_ylabel(label, fontsize=9)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("time (s)")
    fig.suptitle(f"Case 1 (Fig. 7): midspan of span {layout.get('span', '?')}, "
                 f"{layout.get('speed_kmh', 300):g} km/h (unfiltered)", fontsize=9)
    _save(fig, folder, "fig07_girder_midspan.png")

    top_v = sweep.loc[sweep["max_deck_vertical_acc_m_s2"].idxmax()]
    top_l = sweep.loc[sweep["max_deck_lateral_acc_m_s2"].idxmax()]
    top_p = sweep.loc[sweep["max_wheel_vertical_force_N"].idxmax()]
    lines = [f"# Case 1: speed sweep {lo:g}-{hi:g} km/h ({len(sweep)} speeds)", "",
             f"Bridge frequencies (modal analysis of the coupled structure): vertical "
             f"{freqs['vertical']:.3f} Hz, lateral {freqs['lateral']:.3f} Hz; load interval "
             f"L_g = {interval:g} m.", "",
             "| direction | i | eq. 55 (km/h) | sweep peak (km/h) | peak value | peak / median |",
             "|---|---|---|---|---|---|"]
    for r in resonance.itertuples():
        lines.append(f"| {r.direction} | {r.order} | {r.predicted_kmh:.0f} | {r.peak_kmh:.0f} | "
                     f"{r.peak_value:.3g} m/s² | {r.ratio_to_median:.2f} |")
    lines += ["", f"Largest deck vertical acceleration {top_v['max_deck_vertical_acc_m_s2']:.3f} m/s² "
              f"at {top_v['speed_kmh']:g} km/h; largest deck lateral acceleration "
              f"{top_l['max_deck_lateral_acc_m_s2']:.4f} m/s² at {top_l['speed_kmh']:g} km/h; "
              f"largest wheel-rail vertical force {1e-3 * top_p['max_wheel_vertical_force_N']:.1f} kN "
              f"at {top_p['speed_kmh']:g} km/h.", "",
              f"Time histories at {layout.get('speed_kmh', 300):g} km/h: rail under "
              f"{layout.get('wheel', '')}: vertical {1e3 * np.nanmin(history['rail_vertical_disp_m']):.2f} "
              f"to {1e3 * np.nanmax(history['rail_vertical_disp_m']):.2f} mm, lateral "
              f"{1e3 * np.nanmin(history['rail_lateral_disp_m']):.3f} to "
              f"{1e3 * np.nanmax(history['rail_lateral_disp_m']):.3f} mm; girder midspan vertical "
              f"{1e3 * history['girder_vertical_disp_m'].min():.2f} mm, peak |acc| vertical "
              f"{np.abs(history['girder_vertical_acc_m_s2']).max():.3f} m/s², lateral "
              f"{np.abs(history['girder_lateral_acc_m_s2']).max():.4f} m/s² (unfiltered).", ""]
    return resonance, "\n".join(lines)


# ----------------------------------------------------------------------------------------------
# Cases 2-4

def _history_panel(stats: pd.DataFrame, quantity: str, scenarios, title: str, scale: float,
                   unit: str, folder: Path, name: str) -> None:
    plt = _plt()
    fig, axes = plt.subplots(2, 1, figsize=(9, 5.5), sharex=True)
    for s in scenarios:
        block = stats[(stats["scenario"].astype(str) == s) & (stats["quantity"] == quantity)]
        if block.empty:
            continue
        axes[0].plot(block["position_m"], block["mean"] * scale, lw=0.8, label=s)
        axes[1].plot(block["position_m"], block["std"] * scale, lw=0.8, label=s)
    axes[0].set_ylabel(f"mean ({unit})", fontsize=9)
    axes[1].set_ylabel(f"std ({unit})", fontsize=9)
    axes[1].set_xlabel("position of the leading wheelset (m)")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title, fontsize=9)
    _save(fig, folder, name)


def _scale_unit(quantity: str) -> tuple[float, str]:
    if quantity.endswith("_N"):
        return 1e-3, "kN"
    if quantity.endswith("_disp_m"):
        return 1e3, "mm"
    if quantity.endswith("_m_s2"):
        return 1.0, "m/s²"
    return 1.0, "-"


def compare_report(*, extremes: pd.DataFrame, history: pd.DataFrame, table1: pd.DataFrame,
                   table1_history: pd.DataFrame, design: pd.DataFrame, case: Mapping[str, Any],
                   latest_campaign: str, figures: str | Path) -> tuple[pd.DataFrame, str]:
    """Cases 2-4: (comparison table, markdown summary); writes the case's figures."""
    folder = Path(figures)
    folder.mkdir(parents=True, exist_ok=True)
    name = str(case.get("name"))
    kinds = design.drop_duplicates("scenario").set_index("scenario")["kind"].astype(str)
    counts = design.groupby("scenario").size()
    lines = [f"# {name}: study of {len(design)} samples", "",
             "Samples per scenario: " + ", ".join(f"{s} {n}" for s, n in counts.items()), ""]
    rows: list[dict] = []
    if name == "case2":
        fields = [s for s, k in kinds.items() if k == "fields"]
        mc = [s for s, k in kinds.items() if k == "fields_mc"]
        for s in mc:
            ref = s[:-len("_mc")]
            quantity = "girder_vertical_disp_m"
            if ref in fields:
                r = compare_histories(history, quantity, s, ref)
                rows.append(r)
                sc, unit = _scale_unit(quantity)
                _history_panel(history, quantity, [s, ref],
                               f"Case 2 (Fig. 10): girder midspan vertical displacement, MCM "
                               f"({counts[s]}) vs MCM-KLE ({counts[ref]}), condition {ref}",
                               sc, unit, folder, "fig10_kle_vs_mc_girder_disp.png")
                lines += [f"Fig. 10 ({ref}): MCM {counts[s]} vs MCM-KLE {counts[ref]} samples: max |mean "
                          f"difference| {100 * r['max_mean_difference_rel']:.2f} % of max |mean|; "
                          f"max std MCM {1e3 * r['max_std_ref']:.4f} mm, KLE "
                          f"{1e3 * r['max_std_other']:.4f} mm; max |std difference| "
                          f"{100 * r['max_std_difference_rel']:.1f} % of max std; std curves "
                          f"correlate {r['std_correlation']:.3f}.", ""]
        for quantity, fig_name, title in (
                ("girder_lateral_acc_m_s2", "fig11_girder_lateral_acc.png", "Fig. 11: girder lateral acceleration"),
                ("wheel_lateral_force_N", "fig12_wheel_lateral_force.png", "Fig. 12: wheel-rail lateral force"),
                ("carbody_vertical_acc_m_s2", "fig13_carbody_vertical_acc.png", "Fig. 13: car-body vertical acceleration")):
            sc, unit = _scale_unit(quantity)
            _history_panel(history, quantity, fields, f"Case 2 ({title}) per randomness condition",
                           sc, unit, folder, fig_name)
        # Fig. 9: spread of the girder displacement under C4
        if "C4" in fields:
            plt = _plt()
            block = history[(history["scenario"].astype(str) == "C4")
                            & (history["quantity"] == "girder_vertical_disp_m")]
            fig, ax = plt.subplots(figsize=(9, 3.5))
            for col, label in (("minimum", "min"), ("q5", "5 %"), ("mean", "mean"), ("q95", "95 %"),
                               ("maximum", "max")):
                ax.plot(block["position_m"], 1e3 * block[col], lw=0.8, label=label)
            ax.set_xlabel("position of the leading wheelset (m)")
            ax.set_ylabel("girder midspan vertical disp. (mm)")
            ax.legend(fontsize=8, ncol=5)
            ax.grid(alpha=0.3)
            ax.set_title("Case 2 (Fig. 9b): spread of the girder displacement, condition C4", fontsize=9)
            _save(fig, folder, "fig09_girder_disp_spread_C4.png")
        th = table1_history.set_index(table1_history.columns[0])
        shown = [c for c in ("C1", "C2", "C3", "C4") if c in th.columns]
        lines += ["Table 1 (max over position of the std curve, SI units):", "",
                  "| quantity | " + " | ".join(shown) + " | dominant |",
                  "|---|" + "---|" * (len(shown) + 1)]
        for q, r in th[shown].iterrows():
            lines.append(f"| {q} | " + " | ".join(f"{r[c]:.3g}" for c in shown)
                         + f" | {r[shown].astype(float).idxmax()} |")
            rows.append({"quantity": q, "reference": "table1_history",
                         **{c: float(r[c]) for c in shown}})
        lines.append("")
    if name == "case3":
        campaign = [s for s, k in kinds.items() if k == "irregularity"]
        mc = [s for s, k in kinds.items() if k == "irregularity_mc"]
        single = [s for s, k in kinds.items() if k == "single"]
        for ref in mc:
            for other in campaign:
                for quantity in ("rail_vertical_acc_m_s2", "girder_vertical_acc_m_s2",
                                 "wheel_vertical_force_N"):
                    r = compare_histories(history, quantity, ref, other)
                    rows.append(r)
                    lines.append(f"{quantity}: TIPM {counts[other]} vs MCM {counts[ref]} samples: max "
                                 f"std TIPM {r['max_std_other']:.4g}, MCM {r['max_std_ref']:.4g}; max "
                                 f"|std difference| {100 * r['max_std_difference_rel']:.1f} % of max "
                                 f"std; std curves correlate {r['std_correlation']:.3f}.")
                sc, unit = _scale_unit("rail_vertical_acc_m_s2")
                _history_panel(history, "rail_vertical_acc_m_s2", [ref, other],
                               f"Case 3 (Fig. 14): rail vertical acceleration, TIPM ({counts[other]}) "
                               f"vs MCM ({counts[ref]})", sc, unit, folder,
                               "fig14_tipm_vs_mc_rail_acc.png")
        lines.append("")
        # Figs. 15-16: PDFs of the maxima, full (TIPM) vs single excitation
        from ..stats.kde import ExtremeValueKDE  # noqa: F401  (the plot helper uses it)
        from ..stats import plots

        plt = _plt()
        for column, fig_name in (("max_wheel_vertical_force_N", "fig15a_pdf_wheel_vertical_force.png"),
                                 ("max_wheel_lateral_force_N", "fig15b_pdf_wheel_lateral_force.png"),
                                 ("max_rail_vertical_acc_m_s2", "fig16a_pdf_rail_vertical_acc.png"),
                                 ("max_rail_lateral_acc_m_s2", "fig16b_pdf_rail_lateral_acc.png")):
            if column not in extremes.columns:
                continue
            fig = plots.plot_extreme_pdfs(extremes, column, scenarios=campaign + mc + single)
            _save(fig, folder, fig_name)
            for s in campaign + mc:
                block = extremes[extremes["scenario"].astype(str) == s]
                w = block["weight"].to_numpy(float) / block["weight"].sum()
                x = block[column].to_numpy(float)
                one = extremes.loc[extremes["scenario"].astype(str) == "single", column]
                single_value = float(one.iloc[0]) if len(one) else float("nan")
                mean = float(np.sum(w * x))
                std = float(np.sqrt(np.sum(w * (x - mean) ** 2)))
                rows.append({"quantity": column, "reference": s, "other": "single",
                             "mean": mean, "std": std, "single": single_value,
                             "p_exceed_single": float(np.sum(w * (x > single_value)))})
                lines.append(f"{column}, {s}: mean {mean:.4g}, std {std:.4g}, single excitation "
                             f"{single_value:.4g}, P(full > single) {float(np.sum(w * (x > single_value))):.2f}")
        lines.append("")
    if name == "case4":
        plt = _plt()
        from .cases import forecast_limits as _limits

        columns = ("max_deck_vertical_acc_m_s2", "max_deck_lateral_acc_m_s2",
                   "max_carbody_lateral_acc_m_s2", "max_wheel_vertical_force_N",
                   "max_wheel_lateral_force_N")
        fig, axes = plt.subplots(1, len(columns), figsize=(17, 3.6))
        for ax, column in zip(axes, columns):
            lim = _limits(extremes, column, latest_campaign)
            sc, unit = _scale_unit(column)
            for level, block in lim.groupby("level"):
                ax.plot(block["months"], block["mean"] * sc, "o-", ms=3,
                        label={0.05: "lower (p 0.05)", 0.5: "general (p 0.5)",
                               0.95: "upper (p 0.95)"}.get(level, f"p {level:g}"))
                for r in block.itertuples():
                    rows.append({"quantity": column, "reference": "forecast", "months": r.months,
                                 "level": r.level, "mean": r.mean, "n_samples": r.n_samples})
            ax.set_title({"max_deck_vertical_acc_m_s2": "(a) midspan vertical acc.",
                          "max_deck_lateral_acc_m_s2": "(b) midspan lateral acc.",
                          "max_carbody_lateral_acc_m_s2": "car-body lateral acc.",
                          "max_wheel_vertical_force_N": "(c) wheel-rail vertical force",
                          "max_wheel_lateral_force_N": "(d) wheel-rail lateral force"}[column],
                         fontsize=8)
            ax.set_xlabel("months after the latest campaign")
            ax.set_ylabel(unit)
            ax.grid(alpha=0.3)
        axes[0].legend(fontsize=7)
        fig.suptitle("Case 4 (Fig. 17): mean of the maxima over the forecast states at each level",
                     fontsize=9)
        _save(fig, folder, "fig17_forecast_limits.png")
        table = pd.DataFrame([r for r in rows if r.get("reference") == "forecast"])
        lines += ["Fig. 17: mean over the forecast states of each index (SI), per horizon and level:", "",
                  "| index | months | p 0.05 | p 0.5 | p 0.95 |", "|---|---|---|---|---|"]
        for (column, months), block in table.groupby(["quantity", "months"], sort=False):
            by = block.set_index("level")["mean"]
            lines.append(f"| {column} | {months:.0f} | " + " | ".join(
                f"{by.get(p, float('nan')):.4g}" for p in (0.05, 0.5, 0.95)) + " |")
        lines.append("")
    comparison = pd.DataFrame(rows)
    for col in comparison.columns:   # mixed object columns -> strings for Parquet
        if comparison[col].dtype == object:
            comparison[col] = comparison[col].astype("string")
    return comparison, "\n".join(lines)
