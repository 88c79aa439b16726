"""The EN 1991-2 dynamic-analysis study: every configured train over the speed range, per span.

Configuration: the ``en1991:`` section (schema: ttbpipe/schemas/study.schema.yaml; defaults
there) and the study's ``structure:`` (its distinct span lengths, girder, track). Outputs (the
rules of workflow/rules/en1991.smk, or :func:`run_train` and :func:`summarise` directly):

* per train, one row per span and speed (:func:`ttbpipe.en1991.dynamic.sweep_train`);
* ``envelope``: per span and speed the largest value over the trains, and the train that gave
  it;
* ``resonance``: per span and train, the predicted resonance speeds n0 D / i in the range and
  the speed of the largest acceleration found;
* ``checks``: per span, EN 1991-2 Figure 6.9 (need for a dynamic analysis), the Figure 6.10
  frequency limits, and the EN 1990 A2.4.4.2.1 deck acceleration check against the envelope,
  in words;
* ``summary.md`` and the figures (acceleration, deflection and end rotation against speed).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from ..trains import get_train
from .dynamic import span_model, sweep_train
from .limits import dynamic_analysis_need, maximum_design_speed_kmh, resonance_speeds_kmh

log = logging.getLogger(__name__)

__all__ = ["settings", "span_lengths_m", "speeds_kmh", "run_train", "summarise",
           "write_figures", "RESONANCE_ORDERS"]

#: Resonance orders i of v_i = n0 D / i added to the speed grid and reported.
RESONANCE_ORDERS = (1, 2, 3, 4)
#: Envelope quantities: column, label, unit.
QUANTITIES = (("deck_acc_m_s2", "deck acceleration (EN 1990 A2 band)", "m/s²"),
              ("deflection_mm", "midspan deflection", "mm"),
              ("end_rotation_mrad", "end rotation", "mrad"))


def settings(config: Mapping[str, Any]) -> dict[str, Any]:
    """The ``en1991`` section validated, its defaults filled in (study schema)."""
    from ..configuration import validate_section

    return validate_section(config.get("en1991"), "en1991")


def span_lengths_m(config: Mapping[str, Any]) -> list[float]:
    """The distinct span lengths of the study's bridge."""
    from ..structure import properties

    spans = properties.resolve(config.get("structure"))["layout"]["spans_m"]
    return sorted({round(float(s), 6) for s in spans})


def _spacing_m(train_name: str) -> float | None:
    """The regular axle-group spacing of a library train (HSLM-A: the coach length D)."""
    return get_train(train_name).parameters.get("D_m")


def speeds_kmh(cfg: Mapping[str, Any], n0_hz: float, trains: Sequence[str]) -> np.ndarray:
    """The sweep: from ``speed_min_kmh`` to 1.2 x ``line_speed_kmh`` (EN 1991-2 6.4.6.2) in
    ``speed_step_kmh``, plus every resonance speed n0 D / i of the trains inside that range (so
    the peaks are not missed between grid points)."""
    top = maximum_design_speed_kmh(cfg["line_speed_kmh"])
    lo, step = float(cfg["speed_min_kmh"]), float(cfg["speed_step_kmh"])
    grid = list(np.arange(lo, top + 1e-9, step))
    if grid[-1] < top - 1e-9:
        grid.append(top)
    for name in trains:
        D = _spacing_m(name)
        if D:
            grid += [v for v in resonance_speeds_kmh(n0_hz, D, RESONANCE_ORDERS).values()
                     if lo <= v <= top]
    return np.unique(np.round(np.asarray(grid, float), 6))


def run_train(config: Mapping[str, Any], train_name: str) -> pd.DataFrame:
    """All spans and speeds of one train (rows of :func:`sweep_train` plus n0, n3, zeta)."""
    cfg = settings(config)
    get_train(train_name)                       # unknown name: the library's error
    tables = []
    for L in span_lengths_m(config):
        span = span_model(config.get("structure"), L,
                          additional_damping=bool(cfg["additional_damping"]))
        speeds = speeds_kmh(cfg, span.n0_hz, cfg["trains"])
        table = sweep_train(span, train_name, speeds, time_step_s=cfg["time_step_s"])
        table["n0_hz"], table["n3_hz"] = span.n0_hz, span.n3_hz
        table["torsion_hz"], table["damping_ratio"] = span.torsion_hz, span.damping_ratio
        table["band_hz"] = span.band_hz
        table["acc_limit_m_s2"] = span.acceleration_limit_m_s2
        table["track_type"] = span.track_type
        tables.append(table)
        log.info("EN 1991-2 sweep: %s on %.1f m span, %d speeds, peak deck acceleration %.3f "
                 "m/s2", train_name, L, len(speeds), table["deck_acc_m_s2"].max())
    return pd.concat(tables, ignore_index=True)


def summarise(tables: Sequence[pd.DataFrame], config: Mapping[str, Any]) -> dict[str, Any]:
    """Envelope, resonance table, checks and the summary page from the per-train tables."""
    cfg = settings(config)
    data = pd.concat(list(tables), ignore_index=True)
    envelope_rows, resonance_rows, check_rows = [], [], []
    for L, per_span in data.groupby("span_m"):
        first = per_span.iloc[0]
        for v, at_speed in per_span.groupby("speed_kmh"):
            row = {"span_m": L, "speed_kmh": v}
            for column, _, _ in QUANTITIES:
                k = at_speed[column].idxmax()
                row[column] = float(at_speed.loc[k, column])
                row[f"{column}_train"] = str(at_speed.loc[k, "train"])
            envelope_rows.append(row)
        for train, per_train in per_span.groupby("train"):
            k = per_train["deck_acc_m_s2"].idxmax()
            D = _spacing_m(str(train))
            predicted = resonance_speeds_kmh(first["n0_hz"], D, RESONANCE_ORDERS) if D else {}
            top = maximum_design_speed_kmh(cfg["line_speed_kmh"])
            inside = {i: v for i, v in predicted.items() if cfg["speed_min_kmh"] <= v <= top}
            found = float(per_train.loc[k, "speed_kmh"])
            nearest = min(inside.items(), key=lambda iv: abs(iv[1] - found)) if inside else None
            resonance_rows.append({
                "span_m": L, "train": train, "spacing_m": D,
                "predicted_kmh": ", ".join(f"i={i}: {v:.1f}" for i, v in inside.items()) or "none",
                "peak_speed_kmh": found,
                "peak_deck_acc_m_s2": float(per_train.loc[k, "deck_acc_m_s2"]),
                "nearest_order": nearest[0] if nearest else None,
                "nearest_predicted_kmh": nearest[1] if nearest else None})
        need = dynamic_analysis_need(cfg["line_speed_kmh"], L, first["n0_hz"], first["torsion_hz"])
        worst = per_span.loc[per_span["deck_acc_m_s2"].idxmax()]
        limit = float(first["acc_limit_m_s2"])
        check_rows.append({
            "span_m": L, "n0_hz": first["n0_hz"], "n3_hz": first["n3_hz"],
            "torsion_hz": first["torsion_hz"], "damping_ratio": first["damping_ratio"],
            "n0_lower_hz": need.n0_lower_hz, "n0_upper_hz": need.n0_upper_hz,
            "need_for_dynamic_analysis": need.verdict, "need_reason": need.reason,
            "band_hz": first["band_hz"], "track_type": first["track_type"],
            "acc_limit_m_s2": limit, "max_deck_acc_m_s2": float(worst["deck_acc_m_s2"]),
            "max_deck_acc_train": str(worst["train"]),
            "max_deck_acc_speed_kmh": float(worst["speed_kmh"]),
            "utilisation": float(worst["deck_acc_m_s2"]) / limit,
            "deck_acceleration_verdict": "met" if worst["deck_acc_m_s2"] <= limit else "not met",
            "max_deflection_mm": float(per_span["deflection_mm"].max()),
            "max_dynamic_amplification": float(per_span["dynamic_amplification"].max()),
            "max_end_rotation_mrad": float(per_span["end_rotation_mrad"].max())})
    envelope = pd.DataFrame(envelope_rows)
    resonance = pd.DataFrame(resonance_rows)
    checks = pd.DataFrame(check_rows)
    return {"envelope": envelope, "resonance": resonance, "checks": checks,
            "summary": summary_markdown(checks, resonance, cfg, data)}


def summary_markdown(checks: pd.DataFrame, resonance: pd.DataFrame, cfg: Mapping[str, Any],
                     data: pd.DataFrame) -> str:
    """The checker's page: what was run, the checks in words, the resonance table."""
    top = maximum_design_speed_kmh(cfg["line_speed_kmh"])
    lines = ["# EN 1991-2 dynamic analysis", "",
             f"Trains: {', '.join(sorted(data['train'].unique(), key=_train_order))} "
             f"(ttbpipe train library) as moving constant axle loads on the track's centre "
             f"line; speeds {cfg['speed_min_kmh']:g}-{top:g} km/h (1.2 x the line speed "
             f"{cfg['line_speed_kmh']:g} km/h, EN 1991-2 6.4.6.2) in steps of "
             f"{cfg['speed_step_kmh']:g} km/h plus the resonance speeds n0 D / i; "
             f"{len(data)} runs. Damping EN 1991-2 Table 6.6"
             f"{' plus eq. 6.13' if cfg['additional_damping'] else ''}; deck accelerations "
             "filtered to max(30 Hz, 1.5 n0, n3) (EN 1990 A2.4.4.2.1).", ""]
    for _, c in checks.iterrows():
        lines += [f"## Span {c['span_m']:g} m", "",
                  f"* First bending frequency n0 = {c['n0_hz']:.3f} Hz (Figure 6.10 limits "
                  + (f"{c['n0_lower_hz']:.3f}-{c['n0_upper_hz']:.3f} Hz" if pd.notna(c["n0_lower_hz"])
                     else "not defined for this span") + f"), n3 = {c['n3_hz']:.2f} Hz, first "
                  f"torsion {c['torsion_hz']:.2f} Hz, damping {100 * c['damping_ratio']:.2f} %.",
                  f"* Need for a dynamic analysis (EN 1991-2 6.4.4, Figure 6.9): "
                  f"**{c['need_for_dynamic_analysis']}** ({c['need_reason']}).",
                  f"* Deck acceleration (EN 1990 A2.4.4.2.1, {c['track_type']} track, limit "
                  f"{c['acc_limit_m_s2']:g} m/s², band up to {c['band_hz']:.1f} Hz): largest "
                  f"{c['max_deck_acc_m_s2']:.3f} m/s² ({c['max_deck_acc_train']} at "
                  f"{c['max_deck_acc_speed_kmh']:.1f} km/h), utilisation "
                  f"{c['utilisation']:.2f}: the limit is **{c['deck_acceleration_verdict']}**.",
                  f"* Largest midspan deflection {c['max_deflection_mm']:.3f} mm, dynamic "
                  f"amplification y_dyn/y_stat up to {c['max_dynamic_amplification']:.3f}, end "
                  f"rotation up to {c['max_end_rotation_mrad']:.4f} mrad.", "",
                  "| train | D (m) | resonance speeds n0 D / i in range (km/h) | peak at (km/h) "
                  "| peak deck acc. (m/s²) |", "|---|---|---|---|---|"]
        for _, r in resonance[resonance["span_m"] == c["span_m"]].sort_values(
                "train", key=lambda s: s.map(_train_order)).iterrows():
            lines.append(f"| {r['train']} | {r['spacing_m']:g} | {r['predicted_kmh']} | "
                         f"{r['peak_speed_kmh']:.1f} | {r['peak_deck_acc_m_s2']:.3f} |")
        lines.append("")
    return "\n".join(lines) + "\n"


def _train_order(name: str):
    head, _, tail = str(name).rpartition("A")
    return (head, int(tail)) if tail.isdigit() else (str(name), 0)


def write_figures(tables: Sequence[pd.DataFrame], summary: Mapping[str, Any],
                  out_dir: str | Path) -> list[Path]:
    """One figure per span and quantity: every train against speed, the envelope, the limit."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    data = pd.concat(list(tables), ignore_index=True)
    written = []
    for L, per_span in data.groupby("span_m"):
        check = summary["checks"].set_index("span_m").loc[L]
        for column, label, unit in QUANTITIES:
            fig, ax = plt.subplots(figsize=(8, 4.5))
            for train, per_train in sorted(per_span.groupby("train"),
                                           key=lambda kv: _train_order(kv[0])):
                ax.plot(per_train["speed_kmh"], per_train[column], lw=0.9, label=train)
            env = summary["envelope"][summary["envelope"]["span_m"] == L]
            ax.plot(env["speed_kmh"], env[column], "k-", lw=2.0, label="envelope")
            if column == "deck_acc_m_s2":
                ax.axhline(check["acc_limit_m_s2"], color="r", ls="--",
                           label=f"EN 1990 A2 limit {check['acc_limit_m_s2']:g} m/s²")
            ax.set_xlabel("speed (km/h)")
            ax.set_ylabel(f"{label} ({unit})")
            ax.set_title(f"{L:g} m span, n0 = {check['n0_hz']:.2f} Hz: {label}")
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7, ncol=3)
            fig.tight_layout()
            path = out_dir / f"span{L:g}m_{column}.png"
            tmp = path.with_name(path.stem + ".tmp.png")
            fig.savefig(tmp, dpi=110)
            plt.close(fig)
            tmp.replace(path)
            written.append(path)
    return written
