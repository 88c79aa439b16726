"""Study design: which samples a study simulates, their weights, inputs and seeds (docs/studies.md).

A sample is the pair (scenario, sample_index). Scenarios come from ``study.scenarios`` of the
configuration:

* ``irregularity``: the TIPM representative irregularity sets of the latest campaign (their
  probability weights, nominal parameters); scenario label = the campaign date; with
  ``single_excitation``, also one run on the single mean-spectrum irregularity (label ``single``,
  the paper's "single excitation" of Figs. 15-16);
* ``forecast``: the forecast states of those sets at each horizon, at one cumulative-probability
  level (eq. 56); scenario label = the forecast's target date, weights = the TIPM weights;
* ``fields``: random-field samples of the parameter groups (KLE), one scenario per randomness
  condition (``C1`` .. ``C4``: only that group random, the paper's case 2; ``all``: every enabled
  group), with one deterministic mean-spectrum irregularity; weight 1;
* ``fields_mc``: the same conditions sampled by plain Monte Carlo of the full field
  (``fields.method: mc``, eq. 36) instead of the KLE, labels ``<condition>_mc`` (the paper's
  MCM reference of Fig. 10, case 2); weight 1;
* ``irregularity_mc``: plain Monte Carlo over the irregularity population (label ``mc``, the
  paper's MCM reference of Fig. 14, case 3): sample i is a whole section drawn at random (equal
  probability) from the latest campaign's pooled PSD population, turned into a profile; weight 1.

``forecast.levels`` (a list) simulates several cumulative-probability levels at once (the lower,
general and upper limits of Fig. 17, case 4); the labels are then ``<target date>_p<level>``.

The design table (:data:`DESIGN_COLUMNS`) lists every sample; the batch runner takes consecutive
index ranges of one scenario (:func:`batches`). The seed of a sample is
``SeedSequence([study_seed, STREAM_ID, scenario_key(label), sample_index])`` -- it depends only on
the study seed, the scenario and the index, never on the batch or the core count. The random
inputs themselves come from the stages that own them, each seeded the same way (TIPM profiles:
``ttbpipe.tipm.profiles.profile_rng``; fields: ``ttbpipe.fields.sampling.sample_generator``).
"""

from __future__ import annotations

import datetime as _dt
import logging
import zlib
from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd

from ..configuration import section_defaults, validate_section

log = logging.getLogger(__name__)

#: Fixed stream number of the simulation stage in the study's seed tree.
STREAM_ID = 7

SCENARIO_KINDS = ("irregularity", "forecast", "fields", "fields_mc", "irregularity_mc")
#: Label of the plain Monte Carlo irregularity scenario (case 3).
MC_IRREGULARITY = "mc"
#: Label of the single-excitation scenario (one run, mean-spectrum irregularity, nominal parameters).
SINGLE = "single"
FIELD_CONDITIONS = ("C1", "C2", "C3", "C4", "all")
DESIGN_COLUMNS = ("scenario", "kind", "sample_index", "weight", "profile_index", "condition",
                  "seed_entropy")

#: Defaults of ``study.scenarios``: the study schema's (its only home).
DEFAULT_SCENARIOS: dict[str, dict[str, Any]] = section_defaults("study", "scenarios")


def resolve_scenarios(study: Mapping[str, Any] | None) -> dict[str, dict[str, Any]]:
    """``study.scenarios`` validated against the study schema, defaults filled in."""
    return validate_section((study or {}).get("scenarios"), "study", "scenarios")


def scenario_key(label: str) -> int:
    """Stable 32-bit integer of a scenario label (CRC-32; part of the sample seed)."""
    return zlib.crc32(str(label).encode())


def sample_seed_sequence(study_seed: int, scenario: str, sample_index: int) -> np.random.SeedSequence:
    """The sample's SeedSequence: [study_seed, STREAM_ID, scenario_key(scenario), sample_index]."""
    if int(sample_index) < 0:
        raise ValueError(f"sample index must be >= 0, got {sample_index}")
    return np.random.SeedSequence([int(study_seed), STREAM_ID, scenario_key(scenario),
                                   int(sample_index)])


def add_months(date: str, months: float) -> str:
    """ISO date ``months`` (rounded to whole months) after ``date``, day clamped to the month."""
    import calendar

    base = _dt.date.fromisoformat(date)
    index = base.month - 1 + int(round(months))
    year, month = base.year + index // 12, index % 12 + 1
    return _dt.date(year, month, min(base.day, calendar.monthrange(year, month)[1])).isoformat()


def scenario_labels(study: Mapping[str, Any], latest_campaign: str,
                    horizons_months: Iterable[float]) -> dict[str, list[str]]:
    """Scenario labels per kind, known from the configuration alone (no data needed)."""
    sc = resolve_scenarios(study)
    out: dict[str, list[str]] = {k: [] for k in (*SCENARIO_KINDS, SINGLE)}
    if sc["irregularity"]["enabled"]:
        out["irregularity"] = [latest_campaign]
        if sc["irregularity"].get("single_excitation", True):
            out[SINGLE] = [SINGLE]
    if sc["forecast"]["enabled"]:
        available = [float(h) for h in horizons_months]
        chosen = sc["forecast"].get("horizons_months")
        chosen = available if chosen is None else [float(h) for h in chosen]
        bad = [h for h in chosen if h not in available]
        if bad:
            raise ValueError(f"study.scenarios.forecast.horizons_months {bad} are not forecast by "
                             f"the TIPM (tipm.forecast.horizons_months = {available})")
        dates = sorted({add_months(latest_campaign, h) for h in chosen})
        levels = forecast_levels(sc["forecast"])
        out["forecast"] = (dates if levels is None else
                           [forecast_label(d, p) for d in dates for p in levels])
    for kind in ("fields", "fields_mc"):
        if not sc[kind]["enabled"]:
            continue
        conditions = list(sc[kind]["conditions"])
        bad = [c for c in conditions if c not in FIELD_CONDITIONS]
        if bad:
            raise ValueError(f"study.scenarios.{kind}.conditions: {bad}; expected a subset of "
                             f"{list(FIELD_CONDITIONS)}")
        out[kind] = conditions if kind == "fields" else [f"{c}_mc" for c in conditions]
    if sc["irregularity_mc"]["enabled"]:
        out["irregularity_mc"] = [MC_IRREGULARITY]
    labels = [lab for v in out.values() for lab in v]
    if len(set(labels)) != len(labels):
        raise ValueError(f"scenario labels are not unique: {labels}")
    return out


def forecast_levels(forecast: Mapping[str, Any]) -> list[float] | None:
    """The list ``forecast.levels`` (several levels, labels with ``_p<level>``) or None (one
    ``forecast.level``, labels = target dates)."""
    levels = forecast.get("levels")
    if levels is None:
        return None
    levels = [float(p) for p in levels]
    if not levels or any(not 0.0 < p < 1.0 for p in levels):
        raise ValueError(f"study.scenarios.forecast.levels {levels}: need levels in (0, 1)")
    return levels


def forecast_label(target_date: str, level: float) -> str:
    """Scenario label of a forecast at one level among several: ``2026-12-15_p0.95``."""
    return f"{target_date}_p{float(level):g}"


def parse_forecast_label(label: str) -> tuple[str, float | None]:
    """(target date, level or None) of a forecast scenario label."""
    date, _, level = str(label).partition("_p")
    return date, (float(level) if level else None)


def mc_section(study_seed: int, sample_index: int, n_sections: int) -> int:
    """Population section of Monte Carlo irregularity sample i: uniform over the sections, drawn
    from the sample's own SeedSequence (independent of every other sample)."""
    if int(n_sections) < 1:
        raise ValueError("irregularity_mc: the population has no section")
    rng = np.random.default_rng(sample_seed_sequence(study_seed, MC_IRREGULARITY, sample_index))
    return int(rng.integers(int(n_sections)))


def _rows(scenario: str, kind: str, indices, weights, profile_indices, condition: str,
          study_seed: int) -> pd.DataFrame:
    indices = np.asarray(indices, dtype=np.int64)
    return pd.DataFrame({
        "scenario": scenario, "kind": kind, "sample_index": indices,
        "weight": np.asarray(weights, dtype=float),
        "profile_index": np.asarray(profile_indices, dtype=np.int64), "condition": condition,
        "seed_entropy": [str(sample_seed_sequence(study_seed, scenario, i).entropy)
                         for i in indices]})


def build_design(study: Mapping[str, Any], *, latest_campaign: str,
                 tipm_weights: pd.DataFrame | None = None,
                 forecast_states: pd.DataFrame | None = None,
                 horizons_months: Iterable[float] = (),
                 n_population_sections: int | None = None) -> pd.DataFrame:
    """Every sample of the study (:data:`DESIGN_COLUMNS`), sorted by scenario and index.

    ``tipm_weights``: the latest campaign's ``results/tipm/selection/<date>.weights.parquet``
    (``sample_index``, ``weight``); ``forecast_states``: ``results/tipm/forecast_states.parquet``
    (``profile_index``, ``target_date``, ``level``, ``sample_index``, ``weight``);
    ``n_population_sections``: sections of the latest campaign's pooled PSD population (scenario
    ``irregularity_mc``: ``profile_index`` = the drawn section).
    """
    sc = resolve_scenarios(study)
    seed = int(study["seed"])
    labels = scenario_labels(study, latest_campaign, horizons_months)
    blocks = []
    if labels["irregularity"]:
        if tipm_weights is None:
            raise ValueError("scenario irregularity needs the TIPM weights table of campaign "
                             f"{latest_campaign}")
        w = tipm_weights.sort_values("sample_index")
        blocks.append(_rows(latest_campaign, "irregularity", w["sample_index"], w["weight"],
                            w["sample_index"], "nominal", seed))
    if labels[SINGLE]:
        blocks.append(_rows(SINGLE, SINGLE, [0], [1.0], [-1], "nominal", seed))
    if labels["forecast"]:
        if forecast_states is None:
            raise ValueError("scenario forecast needs results/tipm/forecast_states.parquet")
        for label in labels["forecast"]:
            target, level = parse_forecast_label(label)
            level = float(sc["forecast"]["level"]) if level is None else level
            states = forecast_states[np.isclose(forecast_states["level"].to_numpy(float), level)]
            block = states[states["target_date"].astype(str) == target].sort_values("sample_index")
            if block.empty:
                raise ValueError(f"forecast_states has no state for target date {target} at level "
                                 f"{level}; study.scenarios.forecast.level must be one of "
                                 f"tipm.forecast.levels {sorted(forecast_states['level'].unique())}")
            blocks.append(_rows(label, "forecast", block["sample_index"], block["weight"],
                                block["profile_index"], "nominal", seed))
    n_fields = int(sc["fields"]["samples"])
    for condition in labels["fields"]:
        if n_fields < 1:
            raise ValueError(f"study.scenarios.fields.samples must be >= 1, got {n_fields}")
        blocks.append(_rows(condition, "fields", np.arange(n_fields), np.ones(n_fields),
                            np.full(n_fields, -1), condition, seed))
    n_mc = int(sc["fields_mc"]["samples"])
    for label in labels["fields_mc"]:
        if n_mc < 1:
            raise ValueError(f"study.scenarios.fields_mc.samples must be >= 1, got {n_mc}")
        blocks.append(_rows(label, "fields_mc", np.arange(n_mc), np.ones(n_mc),
                            np.full(n_mc, -1), label[:-len("_mc")], seed))
    if labels["irregularity_mc"]:
        if n_population_sections is None:
            raise ValueError("scenario irregularity_mc needs the number of sections of the "
                             f"population of campaign {latest_campaign}")
        n = int(sc["irregularity_mc"]["samples"])
        if n < 1:
            raise ValueError(f"study.scenarios.irregularity_mc.samples must be >= 1, got {n}")
        sections = [mc_section(seed, i, n_population_sections) for i in range(n)]
        blocks.append(_rows(MC_IRREGULARITY, "irregularity_mc", np.arange(n), np.ones(n),
                            sections, "nominal", seed))
    if not blocks:
        raise ValueError("study.scenarios: every scenario is disabled; enable at least one")
    design = pd.concat(blocks, ignore_index=True)
    if (design["weight"] <= 0).any() or not np.isfinite(design["weight"]).all():
        bad = design[(design["weight"] <= 0) | ~np.isfinite(design["weight"])].iloc[0]
        raise ValueError(f"sample {bad['scenario']}/{bad['sample_index']}: weight {bad['weight']} "
                         "is not a positive finite number")
    if design.duplicated(["scenario", "sample_index"]).any():
        dup = design[design.duplicated(["scenario", "sample_index"])].iloc[0]
        raise ValueError(f"sample ({dup['scenario']}, {dup['sample_index']}) appears twice")
    log.info("study design: %s", ", ".join(f"{s}: {n} samples" for s, n in
                                          design.groupby("scenario", sort=False).size().items()))
    return design


def batches(design: pd.DataFrame, batch_size: int) -> list[tuple[str, int, int]]:
    """(scenario, first, last) index ranges, at most ``batch_size`` consecutive samples each.

    Ranges are cut in sample-index order, so each sample belongs to exactly one batch whatever the
    batch size; indices need not be contiguous (a range covers the design's indices inside it).
    """
    if int(batch_size) < 1:
        raise ValueError(f"simulation.batch_size must be >= 1, got {batch_size}")
    out = []
    for scenario, block in design.groupby("scenario", sort=True):
        idx = np.sort(block["sample_index"].to_numpy())
        for start in range(0, idx.size, int(batch_size)):
            chunk = idx[start:start + int(batch_size)]
            out.append((str(scenario), int(chunk[0]), int(chunk[-1])))
    return out


def batch_rows(design: pd.DataFrame, scenario: str, first: int, last: int) -> pd.DataFrame:
    """Design rows of one batch, in sample-index order (empty batch -> ValueError)."""
    sel = design[(design["scenario"].astype(str) == str(scenario))
                 & (design["sample_index"] >= int(first)) & (design["sample_index"] <= int(last))]
    if sel.empty:
        raise ValueError(f"batch {scenario} {first}-{last}: no sample of the design in this range")
    return sel.sort_values("sample_index").reset_index(drop=True)
