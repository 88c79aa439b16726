"""Synthetic series of inspection campaigns: the embedded default data of ttbpipe.

No open raw high-speed track-geometry data exist (physics.md section 3, "Datasets"), so the
default study runs on a synthetic line whose geometry starts at a standard spectrum and degrades
from campaign to campaign. The model, per campaign ``k`` at ``t_k`` months after the first one
(``dt = t_k - t_{k-1}``), in this order:

1. **Base line** (``k = 0``): the four spectral channels (vertical, alignment, cross-level,
   gauge) drawn from the chosen standard spectrum over its valid band with
   :func:`ttbpipe.irregularity.synthesis.synthesize_profiles` (TB/T 3352: vertical RMS 1.22 mm
   over 2-200 m).
2. **Sections.** The line is cut into blocks of uniform random length in
   ``block_length_m`` (200-500 m). Block ``b`` has its own amplitude growth rate
   ``g_b ~ lognormal(median growth_rate_median_per_month, sigma growth_rate_sigma)``; the rate
   changes between blocks over a ``ramp_m`` linear transition (no artificial steps).
3. **Degradation** between campaigns: the existing geometry grows,
   ``s <- s * (1 + g(x))**dt``, and new irregularity content is added,
   ``s <- s + increment_fraction * sqrt(dt * g(x) / growth_rate_median_per_month) * p_k`` with
   ``p_k`` a fresh profile of the same spectrum (random-walk growth of the variance).
4. **Local defects** (static positions, growing depth):
   dipped welds (``welds_per_km`` per km, one rail each, a raised-cosine dip of
   ``weld_length_m``, initial depth uniform in ``weld_depth_mm``, growing by
   ``weld_growth_per_month``) and a settlement trough at a bridge abutment (both rails,
   raised-cosine of ``trough_length_m``, depth ``D0 + (D_inf - D0)(1 - exp(-t/tau))`` with
   ``trough_depth_mm = (D0, D_inf)`` and ``trough_time_constant_months = tau``).
5. **Maintenance** (condition-based): after a campaign, a block whose vertical RMS exceeds
   ``intervention_factor`` times its initial RMS is maintained before the next campaign
   (fastener adjustment on slab track for ``tbt3352``, tamping otherwise): all four channels of
   the block (with ``ramp_m`` run-in/out) are scaled down to ``restore_factor`` times the
   initial RMS, its welds are reset to their initial depth and the trough (if in the block) to
   ``D0`` and its settlement clock restarts. Events are logged and stored in the provenance.
6. **Measurement** (per campaign, from its own random stream): per-rail channels from
   :func:`ttbpipe.channels.rails_from_spectral` plus the defects; the cross-level channel is the
   state's cross-level plus the weld height differences, measured with its own sensor; white
   noise of ``noise_mm`` on every channel independently; ``dropouts_per_km`` NaN runs of
   ``dropout_samples`` samples (all channels, or one channel) and ``spikes_per_km`` isolated
   spikes of ``spike_mm`` amplitude (1 or 2 samples, one channel), placed apart from each other
   and from the file ends so that every campaign is repairable by
   :func:`ttbpipe.inspection.validate.clean_campaign` with its default settings. Values are
   rounded to 0.01 mm (a typical inspection-car resolution).

Determinism: the base line, the blocks, the growth rates and the defects come from
``SeedSequence([seed, 0])``; campaign ``k`` draws its increment and measurement artefacts from
``SeedSequence([seed, 1, k])``. So campaign ``k`` depends only on the seed, ``k``, the dates and
the (deterministic) earlier state, never on how many campaigns are written.
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import logging
from pathlib import Path
from typing import Any, Iterator, Mapping

import numpy as np
import pandas as pd
from scipy.ndimage import uniform_filter1d

from .. import streams
from ..channels import INSPECTION_COLUMNS, SPECTRAL_CHANNELS, rails_from_spectral
from ..dates import MEAN_DAYS_PER_MONTH, add_months
from ..io import atomic_path, write_table
from .format import CHAINAGE_COLUMN
from .validate import CLEANING_DEFAULTS

logger = logging.getLogger(__name__)

# Stream ids of the synthetic-inspection seed tree (ttbpipe.streams).
_STREAM_LAYOUT, _STREAM_CAMPAIGN = streams.SYNTHETIC_LAYOUT, streams.SYNTHETIC_CAMPAIGN
# The default of clean_campaign(plausible_limit_mm=...); FRA classes 1-5 exceed it (long waves).
_DEFAULT_PLAUSIBLE_LIMIT_MM = CLEANING_DEFAULTS["plausible_limit_mm"]


@dataclasses.dataclass(frozen=True)
class SyntheticModel:
    """Parameters of the synthetic degradation and measurement model (module docstring)."""

    block_length_m: tuple[float, float] = (200.0, 500.0)
    ramp_m: float = 25.0
    growth_rate_median_per_month: float = 0.01
    growth_rate_sigma: float = 0.6
    increment_fraction: float = 0.1
    welds_per_km: float = 1.0
    weld_length_m: float = 1.0
    weld_depth_mm: tuple[float, float] = (0.2, 0.8)
    weld_growth_per_month: float = 0.03
    trough_length_m: float = 30.0
    trough_depth_mm: tuple[float, float] = (1.0, 6.0)
    trough_time_constant_months: float = 24.0
    intervention_factor: float = 1.5
    restore_factor: float = 0.7
    noise_mm: float = 0.15
    dropouts_per_km: float = 2.0
    dropout_samples: tuple[int, int] = (2, 6)
    spikes_per_km: float = 0.6
    spike_mm: tuple[float, float] = (20.0, 40.0)
    resolution_mm: float = 0.01


@dataclasses.dataclass
class SyntheticCampaign:
    """One generated campaign: the file table and what produced it."""

    index: int
    date: str
    months: float                      # months since the first campaign
    table: pd.DataFrame                # as written: chainage_m + 6 channels (mm), with artefacts
    truth: pd.DataFrame                # the same channels without noise, dropouts or spikes
    maintenance: list[dict[str, Any]]  # events decided after this campaign (seen at k + 1)
    artefacts: dict[str, int]          # numbers of dropouts and spikes inserted


def campaign_dates(start_date: str, campaigns: int, interval_months: int = 1) -> list[str]:
    """ISO dates ``start + k * interval_months`` (day clamped to the month's end), k < campaigns
    (:func:`ttbpipe.dates.add_months`)."""
    return [add_months(start_date, k * int(interval_months)) for k in range(int(campaigns))]


def _raised_cosine(x: np.ndarray, centre: float, length: float) -> np.ndarray:
    """0.5 (1 + cos(2 pi (x - centre) / length)) on |x - centre| < length/2, else 0."""
    s = (x - centre) / length
    return np.where(np.abs(s) < 0.5, 0.5 * (1.0 + np.cos(2.0 * np.pi * s)), 0.0)


def _block_taper(x: np.ndarray, start: float, end: float, ramp: float) -> np.ndarray:
    """1 inside [start, end], linear to 0 over ``ramp`` outside it."""
    below = np.clip((x - (start - ramp)) / ramp, 0.0, 1.0)
    above = np.clip(((end + ramp) - x) / ramp, 0.0, 1.0)
    return np.minimum(below, above)


def _spaced_positions(rng: np.random.Generator, count: int, low: int, high: int,
                      lengths: np.ndarray, taken: np.ndarray, margin: int) -> list[int]:
    """Start indices for ``count`` runs in [low, high) not within ``margin`` of ``taken``."""
    starts: list[int] = []
    for length in lengths[:count]:
        for _ in range(50):
            start = int(rng.integers(low, high - length))
            if not taken[max(start - margin, 0):start + length + margin].any():
                taken[start:start + length] = True
                starts.append(start)
                break
    return starts


def synthetic_campaign_series(dates: list[str], *, spectrum: str = "tbt3352",
                              length_km: float = 5.0, seed: int = 1, dx_m: float = 0.25,
                              model: SyntheticModel | None = None
                              ) -> Iterator[SyntheticCampaign]:
    """Generate the campaigns of ``dates`` one after the other (model: module docstring)."""
    from ..irregularity.synthesis import synthesize_profiles

    model = model or SyntheticModel()
    if not dates:
        return
    parsed = [_dt.date.fromisoformat(d) for d in dates]
    if any(b <= a for a, b in zip(parsed, parsed[1:])):
        raise ValueError(f"campaign dates must be strictly increasing: {dates}")
    length_m = float(length_km) * 1000.0
    layout = np.random.default_rng(np.random.SeedSequence([int(seed), _STREAM_LAYOUT]))

    base = synthesize_profiles(spectrum, length_m, dx_m, rng=layout)
    x = base[CHAINAGE_COLUMN].to_numpy()
    n = x.size
    state = np.column_stack([base[f"{c}_mm"].to_numpy() for c in SPECTRAL_CHANNELS])

    # Blocks and their growth rates.
    edges = [0.0]
    while edges[-1] < length_m:
        edges.append(edges[-1] + layout.uniform(*model.block_length_m))
    edges[-1] = max(edges[-1], length_m)
    if len(edges) > 2 and edges[-1] - edges[-2] < model.block_length_m[0] / 2:
        edges.pop(-2)  # no sliver block at the end
    edges_arr = np.array(edges)
    n_blocks = len(edges) - 1
    rates = model.growth_rate_median_per_month * np.exp(
        model.growth_rate_sigma * layout.standard_normal(n_blocks))
    block_of = np.clip(np.searchsorted(edges_arr, x, side="right") - 1, 0, n_blocks - 1)
    ramp_samples = max(int(round(model.ramp_m / dx_m)), 1)
    rate_x = uniform_filter1d(rates[block_of], ramp_samples, mode="nearest")

    # Defects.
    n_welds = int(layout.poisson(model.welds_per_km * length_km))
    weld_pos = layout.uniform(5.0, length_m - 5.0, n_welds)
    weld_left = layout.random(n_welds) < 0.5
    weld_depth0 = layout.uniform(*model.weld_depth_mm, n_welds)
    weld_shapes = [_raised_cosine(x, p, model.weld_length_m) for p in weld_pos]
    trough_centre = layout.uniform(0.2, 0.8) * length_m
    trough_shape = _raised_cosine(x, trough_centre, model.trough_length_m)
    weld_age = np.zeros(n_welds)      # months since install / last maintenance
    trough_age = 0.0

    def block_rms(values: np.ndarray) -> np.ndarray:
        return np.sqrt(np.bincount(block_of, values ** 2, n_blocks) / np.bincount(block_of,
                                                                              None, n_blocks))

    initial_rms = block_rms(state[:, 0])
    kind = "fastener adjustment" if spectrum == "tbt3352" else "tamping"
    logger.info("synthetic line: %s, %.3f km, %d blocks, growth rates %.3f..%.3f /month, "
                "%d welds, trough at %.0f m", spectrum, length_km, n_blocks, rates.min(),
                rates.max(), n_welds, trough_centre)

    months_prev = 0.0
    for k, date in enumerate(dates):
        rng = np.random.default_rng(np.random.SeedSequence([int(seed), _STREAM_CAMPAIGN, k]))
        months = (parsed[k] - parsed[0]).days / MEAN_DAYS_PER_MONTH
        dt = months - months_prev
        months_prev = months
        if k > 0:
            fresh = synthesize_profiles(spectrum, length_m, dx_m, rng=rng)
            fresh_arr = np.column_stack([fresh[f"{c}_mm"].to_numpy() for c in SPECTRAL_CHANNELS])
            state *= ((1.0 + rate_x) ** dt)[:, None]
            state += (model.increment_fraction
                      * np.sqrt(dt * rate_x / model.growth_rate_median_per_month))[:, None] \
                * fresh_arr
            weld_age += dt
            trough_age += dt

        # Noise-free per-rail geometry with the defects.
        rails = rails_from_spectral(state[:, 0], state[:, 1], state[:, 2], state[:, 3])
        z_left, z_right = rails["z_left"].copy(), rails["z_right"].copy()
        d0, d_inf = model.trough_depth_mm
        trough_depth = d0 + (d_inf - d0) * (1.0 - np.exp(-trough_age
                                                         / model.trough_time_constant_months))
        z_left -= trough_depth * trough_shape
        z_right -= trough_depth * trough_shape
        weld_depth = weld_depth0 * (1.0 + model.weld_growth_per_month) ** weld_age
        for shape, left, depth in zip(weld_shapes, weld_left, weld_depth):
            (z_left if left else z_right)[:] -= depth * shape
        truth = {
            "vertical_left_mm": z_left, "vertical_right_mm": z_right,
            "alignment_left_mm": rails["y_left"], "alignment_right_mm": rails["y_right"],
            "cross_level_mm": state[:, 2] + (z_left - rails["z_left"])
            - (z_right - rails["z_right"]),
            "gauge_mm": state[:, 3],
        }
        truth_table = pd.DataFrame({CHAINAGE_COLUMN: x, **truth})

        # Measurement: noise, dropouts, spikes.
        measured = np.column_stack([truth[c] for c in INSPECTION_COLUMNS])
        measured = measured + model.noise_mm * rng.standard_normal(measured.shape)
        taken = np.zeros(n, dtype=bool)
        edge = 20
        n_drop = int(rng.poisson(model.dropouts_per_km * length_km))
        drop_len = rng.integers(model.dropout_samples[0], model.dropout_samples[1] + 1, n_drop)
        drop_starts = _spaced_positions(rng, n_drop, edge, n - edge, drop_len, taken, 12)
        drop_channel = rng.integers(-len(INSPECTION_COLUMNS), len(INSPECTION_COLUMNS), n_drop)
        for start, length, channel in zip(drop_starts, drop_len, drop_channel):
            if channel < 0:  # whole sensor package lost
                measured[start:start + length, :] = np.nan
            else:
                measured[start:start + length, channel] = np.nan
        n_spike = int(rng.poisson(model.spikes_per_km * length_km))
        spike_len = np.where(rng.random(n_spike) < 0.8, 1, 2)
        spike_starts = _spaced_positions(rng, n_spike, edge, n - edge, spike_len, taken, 12)
        spike_channel = rng.integers(0, len(INSPECTION_COLUMNS), n_spike)
        spike_size = rng.uniform(*model.spike_mm, n_spike) * rng.choice([-1.0, 1.0], n_spike)
        for start, length, channel, size in zip(spike_starts, spike_len, spike_channel,
                                                spike_size):
            measured[start:start + length, channel] += size
        measured = np.round(measured / model.resolution_mm) * model.resolution_mm
        table = pd.DataFrame({CHAINAGE_COLUMN: np.round(x, 6),
                              **{c: measured[:, j] for j, c in enumerate(INSPECTION_COLUMNS)}})

        # Condition-based maintenance, decided on this campaign, seen from the next one.
        events: list[dict[str, Any]] = []
        current = block_rms(state[:, 0])
        for b in np.flatnonzero(current > model.intervention_factor * initial_rms):
            start, end = float(edges_arr[b]), float(edges_arr[b + 1])
            factor = model.restore_factor * initial_rms[b] / current[b]
            taper = _block_taper(x, start, end, model.ramp_m)
            state *= (1.0 - taper * (1.0 - factor))[:, None]
            in_block = (weld_pos >= start) & (weld_pos < end)
            weld_age[in_block] = 0.0
            trough_reset = bool(start <= trough_centre < end)
            if trough_reset:
                trough_age = 0.0
            event = {"after_campaign": k, "date": date, "kind": kind, "start_m": start,
                     "end_m": end, "vertical_rms_before_mm": float(current[b]),
                     "vertical_rms_after_mm": float(block_rms(state[:, 0])[b]),
                     "welds_reset": int(in_block.sum()), "trough_reset": trough_reset}
            events.append(event)
            logger.info("synthetic maintenance after campaign %d (%s): %s %.0f-%.0f m, vertical "
                        "RMS %.2f -> %.2f mm", k, date, kind, start, end,
                        event["vertical_rms_before_mm"], event["vertical_rms_after_mm"])
        yield SyntheticCampaign(index=k, date=date, months=months, table=table, truth=truth_table,
                                maintenance=events,
                                artefacts={"dropouts": len(drop_starts),
                                           "spikes": len(spike_starts)})


def write_synthetic_campaigns(out_dir: str | Path, *, dates: list[str],
                              spectrum: str = "tbt3352", length_km: float = 5.0, seed: int = 1,
                              dx_m: float = 0.25, fmt: str = "parquet",
                              config: Mapping[str, Any] | None = None,
                              model: SyntheticModel | None = None) -> list[Path]:
    """Write one file ``<date>.<fmt>`` per campaign into ``out_dir``; return the paths.

    ``fmt`` is ``parquet`` (written with :func:`ttbpipe.io.write_table`, provenance: ``config``,
    kind ``inspection_synthetic`` and the generator's settings, model, and maintenance history)
    or ``csv`` (written atomically; 0.01 mm resolution, missing values as empty cells).
    """
    if fmt not in ("parquet", "csv"):
        raise ValueError(f"format must be 'parquet' or 'csv', not {fmt!r}")
    model = model or SyntheticModel()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []
    history: list[dict[str, Any]] = []
    for campaign in synthetic_campaign_series(dates, spectrum=spectrum, length_km=length_km,
                                              seed=seed, dx_m=dx_m, model=model):
        path = out_dir / f"{campaign.date}.{fmt}"
        if fmt == "parquet":
            write_table(campaign.table, path, config=config, kind="inspection_synthetic",
                        synthetic={"spectrum": spectrum, "length_km": length_km, "seed": seed,
                                   "dx_m": dx_m, "campaign_index": campaign.index,
                                   "date": campaign.date, "months": campaign.months,
                                   "artefacts": campaign.artefacts,
                                   "maintenance_before": list(history),
                                   "model": dataclasses.asdict(model)})
        else:
            with atomic_path(path) as tmp:
                campaign.table.to_csv(tmp, index=False, float_format="%.10g")
        history.extend(campaign.maintenance)
        paths.append(path)
        largest = float(np.nanmax(np.abs(campaign.table[list(INSPECTION_COLUMNS)].to_numpy())))
        if largest > _DEFAULT_PLAUSIBLE_LIMIT_MM:
            logger.warning("%s: largest |value| %.1f mm exceeds the default plausible_limit_mm "
                           "(%g mm) of the cleaning step: raise inspections.cleaning."
                           "plausible_limit_mm for spectrum %s", path, largest,
                           _DEFAULT_PLAUSIBLE_LIMIT_MM, spectrum)
    logger.info("wrote %d synthetic campaigns (%s, %.3g km, seed %d, %d maintenance events) to "
                "%s", len(paths), spectrum, length_km, seed, len(history), out_dir)
    return paths
