"""Spectral evolution of track irregularities between inspection campaigns (seed paper §3.3, §5.4).

Seed paper eqs. 50-56, in the notation used here (ς = channel, ω_d = spatial frequency n_k):

* eq. 50-51: for consecutive campaigns t_i, t_{i+1}, the spectral density matrix
  Ω_i(q, ω) (E sections × W frequencies) and the evolution matrix
  Ω̃_i = Ω_{i+1} − Ω_i, section by section (the same track portion q in both campaigns);
  Ω = ∪ Ω_i and Ω̃ = ∪ Ω̃_i over all fitted transitions.
* eq. 52: the amplitude domain [P_l(ω_d), P_u(ω_d)] = [min Ω, max Ω] at each frequency is cut
  into Z partitions Θ_g. The paper cuts it into equal widths in S (``partition_scale="linear"``);
  PSD ordinates are close to lognormal (docs/tipm.md), so the default cuts equal widths in log S
  (``"log"``); ``"quantile"`` gives equal counts. The paper's int[·] on the width is dropped (it
  would round widths < 1 mm²/(1/m) to zero).
* eq. 53: the increments whose starting value lies in Θ_g form the conditional distribution
  f_{ω_d}(P̃_Θg), kept as its empirical quantile function F⁻¹ on a probability grid; the
  cumulative probability index p in (0, 1) picks the increment F⁻¹(p). A partition holding fewer
  than ``min_partition_count`` increments pools the increments of its nearest neighbours.
* eq. 54 / 56: P(t_{i+1}) = P(t_i) + F⁻¹_{ω, g(P(t_i))}(p(t_i)), iterated over the horizon; the
  partition is re-evaluated at every step (the paper: the domain of t_{i+2} is "confirmed by the
  spectral characteristics of P(t_{i+1})"). One p per step is shared by all frequencies and
  channels (the paper's p_ς per irregularity type, here one for all types so that the forecast
  stays coherent). The forecast is floored at the smallest value ever observed, P_l (a PSD
  cannot become negative); floor hits are counted and logged.

Envelopes: ``forecast_fixed(p)`` iterates eq. 56 with a constant p (the paper's "general, upper
and lower limits", p = 0.5 / 0.95 / 0.05); ``simulate`` draws p ~ U(0, 1) independently per
step ("selected by random simulation methods", eq. 54 step 8) and ``envelope`` returns the
percentiles of the simulated paths, the predictive band whose nominal coverage is stated.
One step is one inspection interval (the median interval of the fitted campaigns, in months).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Iterator, Sequence

import numpy as np
import pandas as pd

from ..jit import kernel
from .population import PSDPopulation

__all__ = ["SpectralEvolution", "matched_transitions", "forecast_coverage", "PARTITION_SCALES"]

log = logging.getLogger(__name__)

PARTITION_SCALES = ("log", "linear", "quantile")


def matched_transitions(populations: Sequence[PSDPopulation]) -> list[tuple[np.ndarray, np.ndarray]]:
    """(Ω_i, Ω_{i+1}) pairs of consecutive campaigns restricted to the sections both contain.

    Sections are matched on (section_start_m, section_end_m): the same track portion q (eq. 51).
    Unmatched sections are logged with their count, never silently dropped.
    """
    pairs = []
    for before, after in zip(populations[:-1], populations[1:]):
        key_b = list(zip(before.sections["section_start_m"].round(6), before.sections["section_end_m"].round(6)))
        key_a = {k: j for j, k in enumerate(zip(after.sections["section_start_m"].round(6),
                                                after.sections["section_end_m"].round(6)))}
        idx_b = [i for i, k in enumerate(key_b) if k in key_a]
        idx_a = [key_a[key_b[i]] for i in idx_b]
        unmatched = before.n_sections + after.n_sections - 2 * len(idx_b)
        if unmatched:
            log.warning("campaigns %s -> %s: %d sections have no counterpart and form no increment",
                        before.sections["campaign_date"].iloc[0], after.sections["campaign_date"].iloc[0],
                        unmatched)
        if idx_b:
            pairs.append((before.psd_mm2_m[idx_b], after.psd_mm2_m[idx_a]))
    return pairs


@kernel
def _step_kernel(state, p, edges, quantiles, floor, out):
    """One step of eq. 54 for ``state[n, F, C]`` with index ``p[n]``: out = max(state +
    F⁻¹_{f,c,g(state)}(p), floor), F⁻¹ linearly interpolated on the uniform probability grid of
    ``quantiles[F, C, Z, P]``; partition g = number of inner edges ``edges[f, c, 1:Z]`` <= state.
    Returns the number of floored ordinates."""
    n, n_f, n_c = state.shape
    n_z = quantiles.shape[2]
    n_p = quantiles.shape[3]
    hits = 0
    for i in range(n):
        position = p[i] * (n_p - 1)
        lower = min(int(np.floor(position)), n_p - 2)
        frac = position - lower
        for f in range(n_f):
            for c in range(n_c):
                value = state[i, f, c]
                g = 0
                for e in range(1, n_z):
                    if value >= edges[f, c, e]:
                        g += 1
                q0 = quantiles[f, c, g, lower]
                new = value + q0 + frac * (quantiles[f, c, g, lower + 1] - q0)
                if new < floor[f, c]:
                    new = floor[f, c]
                    hits += 1
                out[i, f, c] = new
    return hits


@dataclass
class _Fitted:
    edges: np.ndarray          # (F, C, Z+1) partition edges in S (mm²/(1/m))
    quantiles: np.ndarray      # (F, C, Z, P) increment quantile function on probability_grid
    counts: np.ndarray         # (F, C, Z) increments whose start lies in the partition
    pooled_counts: np.ndarray  # (F, C, Z) increments used after pooling
    floor: np.ndarray          # (F, C) P_l = min Ω
    probability_grid: np.ndarray


def _nanquantile_columns(values: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``np.nanquantile(values, q, axis=0)`` (method ``linear``), the same numbers, for every
    column at once: numpy takes the quantiles of each column with NaNs in a Python-level loop
    (``apply_along_axis``), which was nine tenths of the evolution fit. Here one sort puts each
    column's NaNs last; the virtual index ``(n - 1) q`` of its ``n`` values, the neighbours and
    numpy's ``_lerp`` (``a + (b - a) t``, or ``b - (b - a)(1 - t)`` for ``t >= 0.5``) follow
    numpy's ``_quantile``. A column without values gives NaN (numpy also warns).
    tests/test_tipm_evolution.py compares the two."""
    ordered = np.sort(values, axis=0)
    count = np.sum(~np.isnan(values), axis=0)
    q = np.asarray(q, dtype=float).reshape((-1,) + (1,) * count.ndim)
    virtual = (count - 1) * q                                   # (Q, *columns)
    last = count - 1
    # numpy's neighbours: floor and floor + 1; at or above the last value both are index -1
    # (the last value), below 0 both are 0; its weight is the virtual index minus the lower one
    above = virtual >= last
    previous = np.where(above, -1.0, np.where(virtual < 0, 0.0, np.floor(virtual)))
    gamma = virtual - previous
    prev_index = np.where(previous < 0, last, previous).astype(np.intp)
    next_index = np.where(above, last, np.where(virtual < 0, 0, prev_index + 1)).astype(np.intp)
    # a column without values (last = -1) reads its first row, masked to NaN below
    prev_index = np.clip(prev_index, 0, None)
    next_index = np.clip(next_index, 0, None)
    a = np.take_along_axis(ordered, prev_index, axis=0)
    b = np.take_along_axis(ordered, next_index, axis=0)
    diff = b - a
    out = a + diff * gamma
    np.subtract(b, diff * (1 - gamma), out=out, where=gamma >= 0.5)
    return np.where(count > 0, out, np.nan)


class SpectralEvolution:
    """Conditional increment model of PSD evolution (seed paper eqs. 50-56).

    Parameters
    ----------
    n_partitions
        Z, number of partitions of the amplitude domain (eq. 52).
    partition_scale
        ``"log"`` (default), ``"linear"`` (the paper's literal eq. 52) or ``"quantile"``.
    min_partition_count
        Partitions with fewer increments pool their nearest neighbours' increments.
    n_probability
        Points of the stored quantile function per partition.
    """

    def __init__(self, n_partitions: int = 5, partition_scale: str = "log",
                 min_partition_count: int = 10, n_probability: int = 101):
        if n_partitions < 1:
            raise ValueError(f"n_partitions must be >= 1, got {n_partitions}")
        if partition_scale not in PARTITION_SCALES:
            raise ValueError(f"partition_scale must be one of {PARTITION_SCALES}, got {partition_scale!r}")
        self.n_partitions = int(n_partitions)
        self.partition_scale = partition_scale
        self.min_partition_count = int(min_partition_count)
        self.n_probability = int(n_probability)
        self.frequency_per_m: np.ndarray | None = None
        self.channels: tuple[str, ...] = ()
        self.interval_months: float = 1.0
        self.n_increments: int = 0
        self._fit: _Fitted | None = None

    # -- fitting ------------------------------------------------------------------------------
    def fit(self, populations: Sequence[PSDPopulation], months: Sequence[float] | None = None
            ) -> "SpectralEvolution":
        """Fit on campaigns in time order; ``months`` = their times in months (for the step)."""
        if len(populations) < 2:
            raise ValueError("spectral evolution needs at least two campaigns")
        first = populations[0]
        self.frequency_per_m = first.frequency_per_m.copy()
        self.channels = first.channels
        if months is not None:
            gaps = np.diff(np.asarray(months, dtype=float))
            if np.any(gaps <= 0):
                raise ValueError("campaign times must increase strictly")
            self.interval_months = float(np.median(gaps))
            if np.any(np.abs(gaps - self.interval_months) > 0.5 * self.interval_months):
                log.warning("campaign intervals range %.2f-%.2f months; one model step is the median "
                            "%.2f months", gaps.min(), gaps.max(), self.interval_months)
        pairs = matched_transitions(populations)
        if not pairs:
            raise ValueError("no section appears in two consecutive campaigns: no increments (eq. 50)")
        start = np.concatenate([b for b, _ in pairs])             # Ω, (E, F, C)
        increments = np.concatenate([a - b for b, a in pairs])    # Ω̃, eq. 50-51
        all_states = np.concatenate([first.psd_mm2_m] + [a for _, a in pairs])
        self.n_increments = start.shape[0]
        self._fit = self._fit_partitions(start, increments, all_states)
        log.info("spectral evolution: %d increments from %d transitions, Z = %d (%s), step %.2f months",
                 self.n_increments, len(pairs), self.n_partitions, self.partition_scale,
                 self.interval_months)
        return self

    def _edges(self, all_states: np.ndarray) -> np.ndarray:
        z = self.n_partitions
        lower, upper = all_states.min(axis=0), all_states.max(axis=0)   # P_l, P_u (eq. 52)
        g = np.arange(z + 1).reshape(-1, 1, 1) / z
        if self.partition_scale == "linear":
            edges = lower + g * (upper - lower)
        elif self.partition_scale == "log":
            edges = np.exp(np.log(lower) + g * (np.log(upper) - np.log(lower)))
        else:
            edges = np.quantile(all_states, g[:, 0, 0], axis=0)
        return np.moveaxis(edges, 0, -1)                                 # (F, C, Z+1)

    def _fit_partitions(self, start: np.ndarray, increments: np.ndarray,
                        all_states: np.ndarray) -> _Fitted:
        z = self.n_partitions
        edges = self._edges(all_states)
        grid = np.linspace(0.0, 1.0, self.n_probability)
        _, n_f, n_c = start.shape
        quantiles = np.empty((n_f, n_c, z, grid.size))
        counts = np.zeros((n_f, n_c, z), dtype=int)
        pooled = np.zeros((n_f, n_c, z), dtype=int)
        labels = self._partition_of(start, edges)                         # (E, F, C)
        counts = np.stack([(labels == g).sum(axis=0) for g in range(z)], axis=-1)
        cumulative = np.concatenate([np.zeros((n_f, n_c, 1), int), np.cumsum(counts, axis=-1)], axis=-1)
        for g in range(z):
            lo = np.full((n_f, n_c), g)
            hi = np.full((n_f, n_c), g)
            # pool the nearest partitions until the conditional sample is large enough
            for _ in range(z):
                total = np.take_along_axis(cumulative, hi[..., None] + 1, -1)[..., 0] - \
                    np.take_along_axis(cumulative, lo[..., None], -1)[..., 0]
                short = total < self.min_partition_count
                if not short.any():
                    break
                lo = np.where(short & (lo > 0), lo - 1, lo)
                total = np.take_along_axis(cumulative, hi[..., None] + 1, -1)[..., 0] - \
                    np.take_along_axis(cumulative, lo[..., None], -1)[..., 0]
                short = total < self.min_partition_count
                hi = np.where(short & (hi < z - 1), hi + 1, hi)
            member = (labels >= lo) & (labels <= hi)
            pooled[..., g] = member.sum(axis=0)
            quantiles[:, :, g, :] = np.moveaxis(
                _nanquantile_columns(np.where(member, increments, np.nan), grid), 0, -1)
        n_pooled = int((pooled > counts).sum())
        if n_pooled:
            log.info("%d of %d partitions had < %d increments and pooled their neighbours",
                     n_pooled, counts.size, self.min_partition_count)
        return _Fitted(edges, quantiles, counts, pooled, all_states.min(axis=0), grid)

    @staticmethod
    def _partition_of(state: np.ndarray, edges: np.ndarray) -> np.ndarray:
        """Partition index g of each ordinate (values beyond [P_l, P_u] go to the end partitions)."""
        inner = edges[..., 1:-1]                                          # (F, C, Z-1)
        return np.sum(state[..., None] >= inner, axis=-1)

    # -- eqs. 53-56 ------------------------------------------------------------------------------
    @property
    def fitted(self) -> _Fitted:
        if self._fit is None:
            raise RuntimeError("SpectralEvolution is not fitted: call fit() or from_table() first")
        return self._fit

    def increment(self, state: np.ndarray, p: np.ndarray | float) -> np.ndarray:
        """Eq. 53: F⁻¹_{ω, g(state)}(p); ``state`` (..., F, C), ``p`` broadcastable to state[..., 0, 0]."""
        fit = self.fitted
        state = np.asarray(state, dtype=float)
        p = np.clip(np.asarray(p, dtype=float), 0.0, 1.0)
        p = np.broadcast_to(p.reshape(p.shape + (1, 1)), state.shape)
        g = self._partition_of(state, fit.edges)
        position = p * (fit.probability_grid.size - 1)
        lower = np.minimum(np.floor(position).astype(int), fit.probability_grid.size - 2)
        frac = position - lower
        n_f, n_c, z, n_p = fit.quantiles.shape
        cell = (np.arange(n_f).reshape(-1, 1) * n_c + np.arange(n_c).reshape(1, -1)) * z
        flat = ((cell + g) * n_p + lower).ravel()
        table = fit.quantiles.reshape(-1)
        q_lo = table.take(flat).reshape(state.shape)
        q_hi = table.take(flat + 1).reshape(state.shape)
        return q_lo + frac * (q_hi - q_lo)

    def step(self, state: np.ndarray, p: np.ndarray | float) -> tuple[np.ndarray, int]:
        """Eq. 54: one inspection interval ahead; returns (new state, number of floor hits).

        Same arithmetic as ``state + increment(state, p)`` floored at P_l, in the numba kernel
        :func:`_step_kernel` (tests compare the two).
        """
        fit = self.fitted
        state = np.ascontiguousarray(state, dtype=float)
        n_f, n_c = state.shape[-2:]
        lead = state.shape[:-2]
        p = np.ascontiguousarray(np.broadcast_to(np.clip(np.asarray(p, float), 0.0, 1.0), lead)).reshape(-1)
        flat = state.reshape(-1, n_f, n_c)
        out = np.empty_like(flat)
        hits = _step_kernel(flat, p, fit.edges, fit.quantiles, fit.floor, out)
        return out.reshape(state.shape), int(hits)

    def steps_for(self, horizon_months: float) -> int:
        return max(1, int(round(float(horizon_months) / self.interval_months)))

    def forecast_fixed(self, state: np.ndarray, n_steps: int, p: float) -> np.ndarray:
        """Eq. 56 with a constant cumulative probability index p, iterated ``n_steps`` times."""
        hits = 0
        for _ in range(int(n_steps)):
            state, h = self.step(state, p)
            hits += h
        if hits:
            log.debug("forecast p = %.3g: %d ordinate-steps floored at the smallest observed PSD", p, hits)
        return state

    def simulate(self, state: np.ndarray, n_steps: int, n_paths: int,
                 rng: np.random.Generator, p_draws: np.ndarray | None = None) -> Iterator[np.ndarray]:
        """Monte Carlo paths of eq. 54: yields the (n_paths, *state.shape) state after each step.

        p ~ U(0, 1) independently per path, step and leading index of ``state`` (e.g. section or
        representative sample), shared by its frequencies and channels; ``p_draws`` (n_steps,
        n_paths, *state.shape[:-2]) overrides the draws. States are yielded one step at a time so
        that long horizons need no memory for the whole path history.
        """
        state = np.broadcast_to(np.asarray(state, float), (n_paths,) + np.shape(state)).copy()
        hits = 0
        for s in range(int(n_steps)):
            p = rng.uniform(size=state.shape[:-2]) if p_draws is None else p_draws[s]
            state, h = self.step(state, p)
            hits += h
            yield state
        if hits:
            log.debug("Monte Carlo forecast: %d of %d ordinate-steps floored at the smallest "
                      "observed PSD", hits, int(n_steps) * state.size)

    def envelope(self, state: np.ndarray, n_steps: int, levels: Sequence[float], n_paths: int,
                 rng: np.random.Generator, delta_n_per_m: float | None = None,
                 at_steps: Sequence[int] | None = None, max_elements: int = 4_000_000
                 ) -> tuple[np.ndarray, np.ndarray | None]:
        """Percentiles (``levels`` in (0, 1)) of the simulated paths after steps ``at_steps``
        (1-based; default every step 1..n_steps).

        ``state`` is (n_items, F, C) (sections or representative sets). Items are independent
        (their own p draws, all drawn from ``rng`` up front), so they are simulated in chunks of
        at most ``max_elements`` path ordinates without changing the result.
        Returns (psd (len(at_steps), len(levels), *state.shape), tqi) where ``tqi``
        (len(at_steps), len(levels), n_items, C) are the percentiles of the paths' equivalent TQI
        sqrt(Σ S Δn) (mm) when ``delta_n_per_m`` is given, else None.
        """
        state = np.asarray(state, float)
        if state.ndim != 3:
            raise ValueError(f"envelope expects a (items, frequencies, channels) state, got {state.shape}")
        levels = np.asarray(levels, float)
        wanted = sorted(set(range(1, int(n_steps) + 1) if at_steps is None else (int(s) for s in at_steps)))
        n_items, n_f, n_c = state.shape
        p_all = rng.uniform(size=(int(n_steps), n_paths, n_items))
        psd_out = np.empty((len(wanted), levels.size) + state.shape)
        tqi_out = np.empty((len(wanted), levels.size, n_items, n_c))
        chunk = max(1, int(max_elements // (n_paths * n_f * n_c)))
        hits_total = 0
        for lo in range(0, n_items, chunk):
            hi = min(n_items, lo + chunk)
            k = 0
            for step, paths in enumerate(self.simulate(state[lo:hi], n_steps, n_paths, rng,
                                                       p_draws=p_all[:, :, lo:hi]), start=1):
                hits_total += int(np.sum(paths == self.fitted.floor))
                if step not in wanted:
                    continue
                psd_out[k, :, lo:hi] = np.quantile(paths, levels, axis=0)
                if delta_n_per_m is not None:
                    tqi_out[k, :, lo:hi] = np.quantile(np.sqrt(paths.sum(axis=-2) * delta_n_per_m),
                                                       levels, axis=0)
                k += 1
        if hits_total:
            log.info("Monte Carlo forecast: %.2g %% of the path ordinate-steps sit on the floor P_l "
                     "(smallest observed PSD)", 100.0 * hits_total / (int(n_steps) * n_paths * state.size))
        return psd_out, (tqi_out if delta_n_per_m is not None else None)

    # -- storage -------------------------------------------------------------------------------
    def to_table(self) -> pd.DataFrame:
        """Long table of the fitted model (one row per channel, frequency, partition, probability)."""
        fit = self.fitted
        n_f, n_c, z, n_p = fit.quantiles.shape
        shape = (n_f, n_c, z, n_p)
        f_idx, c_idx, g_idx, p_idx = np.indices(shape).reshape(4, -1)
        return pd.DataFrame({
            "channel": np.array(self.channels, dtype=object)[c_idx],
            "spatial_frequency_per_m": self.frequency_per_m[f_idx],
            "partition": g_idx,
            "partition_lower_mm2_m": fit.edges[f_idx, c_idx, g_idx],
            "partition_upper_mm2_m": fit.edges[f_idx, c_idx, g_idx + 1],
            "n_increments": fit.counts[f_idx, c_idx, g_idx],
            "n_increments_pooled": fit.pooled_counts[f_idx, c_idx, g_idx],
            "floor_mm2_m": fit.floor[f_idx, c_idx],
            "probability": fit.probability_grid[p_idx],
            "increment_mm2_m": fit.quantiles.reshape(-1),
        })

    def metadata(self) -> dict:
        return {"n_partitions": self.n_partitions, "partition_scale": self.partition_scale,
                "min_partition_count": self.min_partition_count,
                "interval_months": self.interval_months, "n_increments": self.n_increments}

    @classmethod
    def from_table(cls, table: pd.DataFrame, metadata: dict) -> "SpectralEvolution":
        """Rebuild a fitted model from :meth:`to_table` and :meth:`metadata`."""
        from ..channels import SPECTRAL_CHANNELS
        model = cls(metadata["n_partitions"], metadata["partition_scale"],
                    metadata["min_partition_count"])
        model.interval_months = float(metadata["interval_months"])
        model.n_increments = int(metadata["n_increments"])
        present = set(table["channel"].astype(str).unique())
        channels = tuple(c for c in SPECTRAL_CHANNELS if c in present)
        order = {c: i for i, c in enumerate(channels)}
        t = table.assign(_c=table["channel"].map(order)).sort_values(
            ["spatial_frequency_per_m", "_c", "partition", "probability"])
        freqs = np.sort(t["spatial_frequency_per_m"].unique())
        grid = np.sort(t["probability"].unique())
        z = model.n_partitions
        shape = (freqs.size, len(channels), z, grid.size)
        q = t["increment_mm2_m"].to_numpy(float).reshape(shape)
        first = t[t["probability"] == grid[0]]
        lower = first["partition_lower_mm2_m"].to_numpy(float).reshape(shape[:3])
        upper = first["partition_upper_mm2_m"].to_numpy(float).reshape(shape[:3])
        edges = np.concatenate([lower, upper[..., -1:]], axis=-1)
        counts = first["n_increments"].to_numpy(int).reshape(shape[:3])
        pooled = first["n_increments_pooled"].to_numpy(int).reshape(shape[:3])
        floor = first["floor_mm2_m"].to_numpy(float).reshape(shape[:3])[..., 0]
        model.frequency_per_m, model.channels = freqs, channels
        model._fit = _Fitted(edges, q, counts, pooled, floor, grid)
        return model


def forecast_coverage(model: SpectralEvolution, base: PSDPopulation,
                      observed: Sequence[tuple[float, PSDPopulation]], levels: tuple[float, float],
                      n_paths: int, rng: np.random.Generator
                      ) -> tuple[pd.DataFrame, np.ndarray, np.ndarray]:
    """Share of observed section ordinates inside the forecast band, per channel and horizon.

    ``observed`` = [(months after ``base``, population)]; sections matched on chainage. For each
    horizon two bands are scored: the Monte Carlo predictive band (percentiles ``levels`` of the
    paths, nominal coverage levels[1] − levels[0]) and the fixed-p envelope of eq. 56
    (p = levels[0] and levels[1] held for every step).
    Returns (coverage table, PSD band, TQI band), the bands from :meth:`SpectralEvolution.envelope`
    at every step with the levels (levels[0], 0.5, levels[1]).
    """
    lo_level, hi_level = levels
    max_steps = max(model.steps_for(h) for h, _ in observed)
    band, tqi_band = model.envelope(base.psd_mm2_m, max_steps, [lo_level, 0.5, hi_level], n_paths,
                                    rng, base.delta_n_per_m)
    fixed = {p: [] for p in (lo_level, hi_level)}
    for p in fixed:
        state = base.psd_mm2_m
        for _ in range(max_steps):
            state = model.forecast_fixed(state, 1, p)
            fixed[p].append(state)
    rows = []
    for horizon, pop in observed:
        s = model.steps_for(horizon) - 1
        (b_idx, o_idx) = _match(base, pop)
        lower, upper = band[s, 0][b_idx], band[s, 2][b_idx]
        fixed_lo, fixed_hi = fixed[lo_level][s][b_idx], fixed[hi_level][s][b_idx]
        obs = pop.psd_mm2_m[o_idx]
        for c, channel in enumerate(model.channels):
            o = obs[..., c]
            rows.append({"channel": channel, "horizon_months": float(horizon),
                         "campaign_date": str(pop.sections["campaign_date"].iloc[0]),
                         "n_ordinates": int(o.size),
                         "nominal_coverage": hi_level - lo_level,
                         "coverage_mc": float(np.mean((o >= lower[..., c]) & (o <= upper[..., c]))),
                         "coverage_fixed_p": float(np.mean((o >= fixed_lo[..., c]) & (o <= fixed_hi[..., c]))),
                         "below_mc": float(np.mean(o < lower[..., c])),
                         "above_mc": float(np.mean(o > upper[..., c]))})
    return pd.DataFrame(rows), band, tqi_band


def _match(a: PSDPopulation, b: PSDPopulation) -> tuple[list[int], list[int]]:
    key_b = {k: j for j, k in enumerate(zip(b.sections["section_start_m"].round(6),
                                            b.sections["section_end_m"].round(6)))}
    ia, ib = [], []
    for i, k in enumerate(zip(a.sections["section_start_m"].round(6), a.sections["section_end_m"].round(6))):
        if k in key_b:
            ia.append(i)
            ib.append(key_b[k])
    if not ia:
        raise ValueError("no section of the forecast base appears in the observed campaign")
    return ia, ib
