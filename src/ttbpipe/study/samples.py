"""One sample of a study: its case configuration, the coupled run, its extremes and histories.

:func:`run_sample` is a pure function of (simulation settings, design row, input paths): it builds
the sample's case from the study's structure, train and run settings (config ``structure:`` and
``simulation:``), its irregularity profile and its parameter-field factors, runs
:func:`ttbpipe.simulation.coupled.run_coupled`, and reduces the run to one row of the extremes
table and a block of the time-history table (docs/results_schema.md). The profile and the
field factors go to the run in memory (no file between the design and the results); the function
has no side effect, so it runs the same in the batch loop and on a Dask worker.
"""

from __future__ import annotations

import copy
import functools
import json
import logging
from typing import Any, Mapping

import numpy as np
import pandas as pd

from .. import streams
from ..configuration import section_defaults, validate_section
from ..response_indices import PER_CAR, PER_SPAN
from ..stats.schema import RESPONSE_INDICES
from ..threads import pinned
from .design import STREAM_ID, scenario_key

log = logging.getLogger(__name__)

#: Defaults of the ``simulation:`` section: the study schema's (its only home).
SIMULATION_DEFAULTS: dict[str, Any] = section_defaults("simulation")

#: Key of the assessed rows' metadata in run_sample's extremes dict (not a table column).
ASSESSMENT_ROWS_KEY = "_assessment_rows"

PROFILE_CHANNELS = ("vertical_mm", "alignment_mm", "cross_level_mm", "gauge_mm")


def resolve_simulation(section: Mapping[str, Any] | None) -> dict[str, Any]:
    """``simulation:`` validated against the study schema, missing keys filled from its defaults
    (unknown keys are an error naming the closest valid key)."""
    return validate_section(section, "simulation")


def mean_spectrum_seed(study_seed: int) -> int:
    """Seed of the single deterministic irregularity of the fields scenarios (same for all)."""
    seq = np.random.SeedSequence([int(study_seed), STREAM_ID, scenario_key(streams.MEAN_SPECTRUM_LABEL)])
    return int(seq.generate_state(1)[0])


def mean_spectrum_irregularity(irregularity: Mapping[str, Any], study_seed: int) -> dict[str, Any]:
    """The case's ``irregularity:`` section of the single mean-spectrum profile (scenarios
    single, fields, fields_mc; case 1's sweep): ``simulation.irregularity``'s spectrum, step,
    fade-in and synthesis (``amplitudes``), seeded by :func:`mean_spectrum_seed`.
    ``irregularity``: the resolved ``simulation.irregularity`` section."""
    return {"source": "synthetic", "spectrum": irregularity["spectrum"],
            "dx_m": irregularity["dx_m"], "amplitudes": irregularity["amplitudes"],
            "fade_in_m": irregularity["fade_in_m"], "seed": mean_spectrum_seed(study_seed)}


def mc_fields_seed(study_seed: int) -> int:
    """Seed of the plain Monte Carlo fields scenarios (``fields_mc``, case 2's MCM reference):
    a stream of its own, so that MC sample i is independent of KLE sample i (the two estimates
    of Fig. 10 must not share their random numbers)."""
    seq = np.random.SeedSequence([int(study_seed), STREAM_ID, scenario_key(streams.MC_FIELDS_LABEL)])
    return int(seq.generate_state(1)[0])


#: Stream of the study's plain Monte Carlo irregularity profiles (ttbpipe.streams).
STREAM_MC_PROFILES = streams.STUDY_MC_PROFILES


@functools.lru_cache(maxsize=2)
def _mc_population(paths: tuple[str, ...], pooled_path: str | None,
                   band: tuple[float, float] | None):
    """Pooled PSD population of the Monte Carlo irregularity scenario (cached per process): the
    pooled table when given (the workflow's, one file; its sections read as the samples ask for
    them, :class:`~ttbpipe.tipm.population.PooledSections`), else the campaigns' PSD tables."""
    from ..tipm.population import PooledSections, pooled_population

    if pooled_path is not None:
        return PooledSections(pooled_path, band)
    return pooled_population(list(paths), band)


def mc_profile(population: Mapping[str, Any], study_seed: int, section: int,
               sample_index: int) -> pd.DataFrame:
    """Profile of Monte Carlo irregularity sample i: population section ``section``'s own PSD
    (all four channels, whole section: the cross-channel levels stay together) synthesised with
    random phases (or Gaussian coefficients, ``amplitudes``) from
    ``profile_rng(seed, date, STREAM_MC_PROFILES, i)``.

    ``population``: {"psd_paths": [...] (the campaigns' PSD tables) or "pooled_path" (their
    pooled table, :func:`ttbpipe.tipm.population.write_pooled_population`, pooled over the
    same band), "wavelength_band_m": [lo, hi], "length_m", "dx_m", "amplitudes"
    (``tipm.profiles.amplitudes``; missing: the default random phases), "date": the latest
    campaign}; the profile keys are :func:`ttbpipe.study.plan.mc_profile_settings`.
    """
    from ..irregularity.synthesis import DEFAULT_AMPLITUDES
    from ..tipm.profiles import profiles_from_psd_sets

    band = population.get("wavelength_band_m")
    pooled = population.get("pooled_path")
    pop = _mc_population(tuple(str(p) for p in population.get("psd_paths", ())),
                         None if pooled is None else str(pooled),
                         None if band is None else tuple(float(b) for b in band))
    if not 0 <= int(section) < pop.n_sections:
        raise ValueError(f"irregularity_mc sample {sample_index}: section {section} outside the "
                         f"population of {pop.n_sections} sections")
    if pooled is not None:
        pop, section = pop.section(int(section)), 0
    table = profiles_from_psd_sets(
        pop.psd_mm2_m[[int(section)]], pop.frequency_per_m, pop.channels, [int(sample_index)],
        length_m=float(population["length_m"]), dx_m=float(population["dx_m"]),
        study_seed=study_seed, date=str(population["date"]), stream=STREAM_MC_PROFILES,
        wavelength_band_m=tuple(band) if band is not None else (2.0, 200.0),
        amplitudes=str(population.get("amplitudes", DEFAULT_AMPLITUDES)))
    for channel in PROFILE_CHANNELS:   # a population without a channel: that channel is flat
        if channel not in table.columns:
            table[channel] = 0.0
    return table[["chainage_m", *PROFILE_CHANNELS]]


@functools.lru_cache(maxsize=8)
def _field_sampler(fields_json: str, structure_json: str, study_seed: int, condition: str):
    """FieldSampler of one randomness condition on the structure's carriers (cached per process:
    the KL bases and Nataf solves are computed once per batch/worker, not per sample)."""
    from ..fields.sampling import FieldSampler
    from ..simulation.setup import nominal_structure
    from ..structure import carrier_positions

    fields = json.loads(fields_json)
    if condition != "all":
        groups = fields.get("groups", {})
        if condition not in groups:
            raise ValueError(f"fields.groups has no group {condition} (randomness condition of "
                             "study.scenarios.fields.conditions)")
        fields["groups"] = {name: {**g, "enabled": name == condition} for name, g in groups.items()}
    # the carriers of the process's shared model of this structure (the runs' model: built
    # once per process; fields.sampling.positions_from_structure gives the same positions)
    model = nominal_structure({"structure": json.loads(structure_json)})
    positions = {k: np.asarray(v, dtype=float) for k, v in carrier_positions(model).items()}
    return FieldSampler(fields, study_seed, positions=positions)


def field_factors(fields: Mapping[str, Any], structure: Mapping[str, Any], study_seed: int,
                  condition: str, sample_index: int, method: str | None = None
                  ) -> dict[str, np.ndarray]:
    """Factors {parameter: array over the structure's carriers} of one fields sample.

    Group g's numbers come from ``sample_generator(seed, i, stream_g)`` whatever the other groups,
    so condition ``C2`` sample i equals the C2 columns of sample i of the fields stage
    (``results/fields/samples.parquet`` with ``fields.geometry.source: structure``).
    ``method``: override ``fields.method`` (``mc`` for the fields_mc scenarios, which also use
    their own seed, :func:`mc_fields_seed`).
    """
    if method is not None and method != fields.get("method", "kle"):
        fields = {**fields, "method": method}
    if method == "mc":
        study_seed = mc_fields_seed(study_seed)
    sampler = _field_sampler(json.dumps(fields, sort_keys=True, default=str),
                             json.dumps(structure, sort_keys=True, default=str), int(study_seed),
                             str(condition))
    return sampler.sample(int(sample_index))


def read_profile(path: str, id_column: str, profile_index: int) -> pd.DataFrame:
    """One profile (chainage_m + the four channels in mm) from a TIPM profiles table."""
    import pyarrow.parquet as pq

    table = pq.read_table(path, filters=[(id_column, "==", int(profile_index))]).to_pandas()
    if table.empty:
        raise KeyError(f"{path}: no profile with {id_column} = {profile_index}")
    missing = [c for c in ("chainage_m", *PROFILE_CHANNELS) if c not in table.columns]
    if missing:
        raise ValueError(f"{path}: missing column(s) {missing}")
    return table.sort_values("chainage_m")[["chainage_m", *PROFILE_CHANNELS]].reset_index(drop=True)


def build_case(sim: Mapping[str, Any], structure: Mapping[str, Any], *,
               irregularity: Mapping[str, Any], properties: Mapping[str, Any] | None = None
               ) -> dict[str, Any]:
    """Case configuration of :func:`run_coupled` from the study's simulation settings."""
    run = {"track": "structure", "speed_kmh": float(sim["speed_kmh"]),
           "time_step_s": sim["time_step_s"], "output_interval_s": float(sim["output_interval_s"]),
           "deck_filter_hz": float(sim["deck_filter_hz"])}
    if sim.get("end_x_m") is not None:
        run["end_x_m"] = float(sim["end_x_m"])
    if sim.get("track_window_m") is not None:
        run["track_window_m"] = float(sim["track_window_m"])
    case = {"structure": copy.deepcopy(dict(structure)), "train": copy.deepcopy(sim["train"]),
            "simulation": run, "irregularity": dict(irregularity)}
    if properties:
        case["properties"] = dict(properties)
    return case


def _history_columns(table: pd.DataFrame, sim: Mapping[str, Any], n_spans: int) -> dict[str, str]:
    """Map time-history quantity (schema name) -> column of the coupled run's table."""
    h = sim["history"]
    span = int(h["span"]) if h.get("span") else n_spans // 2 + 1   # middle span by default
    wheel, point = h["wheel"], h["carbody_point"]
    wanted = {
        "girder_vertical_acc_m_s2": f"girder_span{span}_mid_z_acc_m_s2",
        "girder_lateral_acc_m_s2": f"girder_span{span}_mid_y_acc_m_s2",
        "girder_vertical_disp_m": f"girder_span{span}_mid_z_disp_mm",
        "rail_vertical_acc_m_s2": f"rail_left_span{span}_mid_z_acc_m_s2",
        "rail_lateral_acc_m_s2": f"rail_left_span{span}_mid_y_acc_m_s2",
        "carbody_vertical_acc_m_s2": f"{point}_az_m_s2",
        "carbody_lateral_acc_m_s2": f"{point}_ay_m_s2",
        "wheel_vertical_force_N": f"{wheel}_P_N",
        "wheel_lateral_force_N": f"{wheel}_Q_N",
        "derailment_coefficient": f"{wheel}_QP",
    }
    missing = {k: v for k, v in wanted.items() if v not in table.columns}
    if missing:
        raise ValueError(f"simulation.history: the run has no column(s) {sorted(missing.values())}; "
                         "check history.span, history.wheel (e.g. car1_ws1_left) and "
                         "history.carbody_point (e.g. car1_body_front)")
    return wanted


def extremes_from_run(summary: Mapping[str, Any]) -> dict[str, float]:
    """One row of the extremes table from a run's summary: the context columns (train speed,
    smallest static wheel load), every response index of the registry the run computed (same
    names: ttbpipe.response_indices), the per-span and per-car indices, the contact-loss index."""
    out: dict[str, float] = {
        "train_speed_m_s": float(summary["speed_kmh"]) / 3.6,
        "static_wheel_load_N": float(min(min(v) for v in summary["static_wheel_load_N"].values())),
        "static_axle_load_N": float(min(sum(v) for v in summary["static_wheel_load_N"].values())),
    }
    for name in RESPONSE_INDICES:
        if name in summary:
            out[name] = float(summary[name])
    n_cars = len(summary.get("sperling", {})) // 2
    for car in range(1, n_cars + 1):
        for pattern in PER_CAR:
            out[pattern.format(car=car)] = float(summary[pattern.format(car=car)])
    for span in range(1, int(summary.get("n_spans", 0)) + 1):
        for pattern in PER_SPAN:
            if pattern.format(span=span) in summary:
                out[pattern.format(span=span)] = float(summary[pattern.format(span=span)])
    bad = {k: v for k, v in out.items() if not np.isfinite(v)}
    if bad:
        from ..simulation.diagnosis import explain

        _, cause = explain(float(summary["time_step_s"]), summary["dt_limits"],
                           summary.get("irregularity", {}), summary, None,
                           float(summary["speed_kmh"]) / 3.6, stopped=False)
        raise RuntimeError(f"non-finite response indices {bad} (extremes column(s) {sorted(bad)}); "
                           "the coupled run stops on a non-finite state and checks its table, so "
                           f"a non-finite index here is a defect of the reduction or its input; {cause}")
    return out


def _qp_history(table: pd.DataFrame, qp_column: str, values: np.ndarray) -> np.ndarray:
    """Q/P history of one wheel for the study's statistics: at output steps where the wheel is
    off the rail (``<wheel>_in_contact`` = 0; the run writes Q/P = 0 there, Q/P being defined
    in contact only) the wheel's largest in-contact Q/P of the run stands in. A lifted wheel is
    the worst state for derailment, so a 0 would understate the risk in the mean and spread
    curves; the largest in-contact value is finite and conservative. The loss itself is the
    extremes' ``contact_loss_*`` index."""
    flag = qp_column[:-len("_QP")] + "_in_contact"
    if flag not in table.columns:
        return values
    off = table[flag].to_numpy() == 0
    if not off.any():
        return values
    values = values.copy()
    values[off] = float(values[~off].max()) if (~off).any() else 0.0
    return values


def history_from_run(table: pd.DataFrame, sim: Mapping[str, Any], n_spans: int) -> pd.DataFrame:
    """Time-history block of one run against the leading wheelset's position (``position_m``).

    All samples of a study share speed, time step, output interval and start, so the grid
    x_lead(t) is the same for every sample (no resampling needed); units converted to SI.
    """
    columns = _history_columns(table, sim, n_spans)
    out = {"position_m": table["x_lead_m"].to_numpy(float)}
    bad = []
    for name, col in columns.items():
        values = table[col].to_numpy(float)
        if not np.isfinite(values).all():
            bad.append(col)
        if name == "derailment_coefficient":
            values = _qp_history(table, col, values)
        out[name] = values * 1e-3 if col.endswith("_mm") else values
    if bad:
        raise ValueError(f"time-history column(s) {bad} of the coupled run have non-finite values "
                         f"({[int((~np.isfinite(table[c].to_numpy(float))).sum()) for c in bad]} "
                         "values); the run checks its table before returning, so this table did "
                         "not come from ttbpipe.simulation.coupled.run_coupled unchanged")
    return pd.DataFrame(out)


@pinned
def run_sample(row: Mapping[str, Any], *, study_seed: int, sim: Mapping[str, Any],
               structure: Mapping[str, Any], fields: Mapping[str, Any] | None,
               profiles: Mapping[str, str], assessment: Mapping[str, Any] | None = None
               ) -> tuple[dict[str, Any], pd.DataFrame]:
    """Simulate one design row; returns (extremes row, history block) with the key columns.

    ``profiles``: {"irregularity": representative profiles path, "forecast": forecast profiles
    path} (only the one the row's kind needs). ``assessment``: the resolved ``assessment:``
    section (:func:`ttbpipe.assessment.study.resolve_assessment`; None: its defaults): the
    sample is assessed in memory and the extremes row gets the assessed columns
    (:mod:`ttbpipe.assessment.columns`) and, under :data:`ASSESSMENT_ROWS_KEY`, the rows'
    metadata (the batch moves it to its provenance).
    """
    from ..assessment.study import assess_sample, resolve_assessment, run_case

    if assessment is None:
        assessment = resolve_assessment(None)
    kind, index = str(row["kind"]), int(row["sample_index"])
    irr_cfg = sim["irregularity"]
    track, factors = None, None
    if kind == "irregularity_mc":
        track = mc_profile(profiles[kind], study_seed, int(row["profile_index"]), index)
    elif kind in ("irregularity", "forecast"):
        from ..tipm.profiles import PROFILE_ID_COLUMN

        track = read_profile(profiles[kind], PROFILE_ID_COLUMN[kind], int(row["profile_index"]))
    elif kind not in ("fields", "fields_mc", "single"):
        raise ValueError(f"design row {row['scenario']}/{index}: unknown kind {kind!r}")
    if track is not None:
        # the profile's chainage starts lead_in_m behind x = 0 of the structure so that it
        # covers the wheels of a train starting at the beginning of the rails
        track["chainage_m"] = track["chainage_m"] - track["chainage_m"].iloc[0] - float(irr_cfg["lead_in_m"])
        irregularity = {"fade_in_m": irr_cfg["fade_in_m"]}
    else:   # the single mean-spectrum irregularity of the fields and single scenarios
        irregularity = mean_spectrum_irregularity(irr_cfg, study_seed)
    if kind in ("fields", "fields_mc"):
        if fields is None:
            raise ValueError("scenario fields needs the fields: section of the configuration")
        factors = field_factors(fields, structure, study_seed, str(row["condition"]), index,
                                method="mc" if kind == "fields_mc" else None)
    case = run_case(build_case(sim, structure, irregularity=irregularity), assessment)
    from ..simulation.coupled import run_coupled

    try:
        table, summary = run_coupled(case, track=track, factors=factors)
    except Exception as exc:
        source = (f" (irregularity profile {row['profile_index']} of {profiles[kind]}, "
                  f"shifted to start {irr_cfg['lead_in_m']} m behind x = 0)"
                  if kind in profiles and kind != "irregularity_mc" else
                  f" (population section {row['profile_index']})" if kind == "irregularity_mc"
                  else "")
        raise RuntimeError(f"sample ({row['scenario']}, {index}){source} failed: {exc}") from exc
    n_spans = int(summary["n_spans"])
    keys = {"sample_index": index, "scenario": str(row["scenario"]), "weight": float(row["weight"]),
            "seed_entropy": str(row["seed_entropy"])}
    extremes = {**keys, **extremes_from_run(summary)}
    try:
        assessed, metadata = assess_sample(table, summary, case, assessment)
    except Exception as exc:
        raise RuntimeError(
            f"sample ({row['scenario']}, {index}): assessment {assessment['standard']} failed: "
            f"{exc}. The standards evaluate records of at least a few seconds: lengthen the run "
            "(simulation.end_x_m, structure.layout), or select fewer standards "
            "(assessment.standard; [] assesses nothing)") from exc
    extremes.update(assessed)
    extremes[ASSESSMENT_ROWS_KEY] = metadata
    history = history_from_run(table, sim, n_spans)
    for k in ("weight", "scenario", "sample_index"):   # history key columns (results_schema.md)
        history.insert(0, k, keys[k])
    return extremes, history
