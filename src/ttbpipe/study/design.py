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

import logging
import zlib
from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd

from .. import streams
from ..configuration import section_defaults, validate_section
from ..dates import add_months

log = logging.getLogger(__name__)

#: Stream id of the study's samples in the study's seed tree
#: (:data:`ttbpipe.streams.SIMULATION`).
STREAM_ID = streams.SIMULATION

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


def resolve_subset(config: Mapping[str, Any]) -> dict[str, Any]:
    """``study.scenarios.subset`` of a study configuration validated, defaults filled in (the
    rare-event scenario, :mod:`ttbpipe.reliability.study`)."""
    return resolve_scenarios(config.get("study"))["subset"]


def scenario_key(label: str) -> int:
    """Stable 32-bit integer of a scenario label (CRC-32; part of the sample seed)."""
    return zlib.crc32(str(label).encode())


def sample_seed_sequence(study_seed: int, scenario: str, sample_index: int) -> np.random.SeedSequence:
    """The sample's SeedSequence: [study_seed, STREAM_ID, scenario_key(scenario), sample_index]."""
    if int(sample_index) < 0:
        raise ValueError(f"sample index must be >= 0, got {sample_index}")
    return np.random.SeedSequence([int(study_seed), STREAM_ID, scenario_key(scenario),
                                   int(sample_index)])


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


def scenario_kind(labels: Mapping[str, list[str]], label: str) -> str:
    """The kind of scenario ``label`` (``labels``: :func:`scenario_labels`)."""
    for kind, names in labels.items():
        if label in names:
            return kind
    raise ValueError(f"unknown study scenario {label!r}; the configured ones are "
                     f"{sorted(n for names in labels.values() for n in names)}")


def scenario_design(study: Mapping[str, Any], label: str, *, latest_campaign: str,
                    tipm_weights: pd.DataFrame | None = None,
                    forecast_states: pd.DataFrame | None = None,
                    horizons_months: Iterable[float] = (),
                    n_population_sections: int | None = None, kind: str | None = None,
                    expected_samples: int | None = None) -> pd.DataFrame:
    """The samples of one scenario (:data:`DESIGN_COLUMNS`), sorted by index.

    ``tipm_weights``: the latest campaign's ``results/tipm/selection/<date>.weights.parquet``
    (``sample_index``, ``weight``; scenario ``irregularity``); ``forecast_states``:
    ``results/tipm/forecast_states.parquet`` (``profile_index``, ``target_date``, ``level``,
    ``sample_index``, ``weight``; scenarios ``forecast``); ``n_population_sections``: sections
    of the latest campaign's pooled PSD population (scenario ``irregularity_mc``:
    ``profile_index`` = the drawn section). Each scenario's design depends only on its own
    inputs, so the workflow writes one file per scenario and a new inspection campaign leaves
    the designs (and batches) of the fields and single-excitation scenarios untouched.
    ``kind``: the scenario's kind when known (else found from the labels of ``study``);
    ``expected_samples``: the count the workflow planned its batches for
    (ttbpipe.study.plan.sample_counts), checked here.
    """
    sc = resolve_scenarios(study)
    seed = int(study["seed"])
    if kind is None:
        kind = scenario_kind(scenario_labels(study, latest_campaign, horizons_months), label)
    if kind == "irregularity":
        if tipm_weights is None:
            raise ValueError("scenario irregularity needs the TIPM weights table of campaign "
                             f"{latest_campaign}")
        w = tipm_weights.sort_values("sample_index")
        block = _rows(label, "irregularity", w["sample_index"], w["weight"], w["sample_index"],
                      "nominal", seed)
    elif kind == SINGLE:
        block = _rows(SINGLE, SINGLE, [0], [1.0], [-1], "nominal", seed)
    elif kind == "forecast":
        if forecast_states is None:
            raise ValueError("scenario forecast needs results/tipm/forecast_states.parquet")
        target, level = parse_forecast_label(label)
        level = float(sc["forecast"]["level"]) if level is None else level
        states = forecast_states[np.isclose(forecast_states["level"].to_numpy(float), level)]
        states = states[states["target_date"].astype(str) == target].sort_values("sample_index")
        if states.empty:
            raise ValueError(f"forecast_states has no state for target date {target} at level "
                             f"{level}; study.scenarios.forecast.level must be one of "
                             f"tipm.forecast.levels {sorted(forecast_states['level'].unique())}")
        block = _rows(label, "forecast", states["sample_index"], states["weight"],
                      states["profile_index"], "nominal", seed)
    elif kind in ("fields", "fields_mc"):
        n = int(sc[kind]["samples"])
        condition = label if kind == "fields" else label[:-len("_mc")]
        block = _rows(label, kind, np.arange(n), np.ones(n), np.full(n, -1), condition, seed)
    else:   # irregularity_mc
        if n_population_sections is None:
            raise ValueError("scenario irregularity_mc needs the number of sections of the "
                             f"population of campaign {latest_campaign}")
        n = int(sc["irregularity_mc"]["samples"])
        sections = [mc_section(seed, i, n_population_sections) for i in range(n)]
        block = _rows(MC_IRREGULARITY, "irregularity_mc", np.arange(n), np.ones(n), sections,
                      "nominal", seed)
    if (block["weight"] <= 0).any() or not np.isfinite(block["weight"]).all():
        bad = block[(block["weight"] <= 0) | ~np.isfinite(block["weight"])].iloc[0]
        raise ValueError(f"sample {bad['scenario']}/{bad['sample_index']}: weight {bad['weight']} "
                         "is not a positive finite number")
    if block.duplicated(["scenario", "sample_index"]).any():
        dup = block[block.duplicated(["scenario", "sample_index"])].iloc[0]
        raise ValueError(f"sample ({dup['scenario']}, {dup['sample_index']}) appears twice")
    if expected_samples is not None and (
            len(block) != int(expected_samples)
            or not np.array_equal(np.sort(block["sample_index"].to_numpy()), np.arange(len(block)))):
        raise ValueError(
            f"scenario {label}: the design has {len(block)} samples (indices "
            f"{block['sample_index'].min()}..{block['sample_index'].max()}) but the workflow "
            f"planned {expected_samples} (0..{int(expected_samples) - 1}) from the campaigns' "
            "chainage when it started (ttbpipe.study.plan): a campaign file changed during the "
            "run, or its cleaning changed its number of sections; rerun snakemake")
    return block.reset_index(drop=True)


def build_design(study: Mapping[str, Any], *, latest_campaign: str,
                 tipm_weights: pd.DataFrame | None = None,
                 forecast_states: pd.DataFrame | None = None,
                 horizons_months: Iterable[float] = (),
                 n_population_sections: int | None = None) -> pd.DataFrame:
    """Every sample of the study (:data:`DESIGN_COLUMNS`), sorted by scenario and index: the
    :func:`scenario_design` of every configured scenario."""
    labels = scenario_labels(study, latest_campaign, horizons_months)
    order = [label for kind in (*SCENARIO_KINDS[:1], SINGLE, *SCENARIO_KINDS[1:])
             for label in labels.get(kind, [])]
    if not order:
        raise ValueError("study.scenarios: every scenario is disabled; enable at least one")
    design = pd.concat([scenario_design(study, label, latest_campaign=latest_campaign,
                                        tipm_weights=tipm_weights, forecast_states=forecast_states,
                                        horizons_months=horizons_months,
                                        n_population_sections=n_population_sections)
                        for label in order], ignore_index=True)
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
