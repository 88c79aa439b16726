"""The study's subset-simulation scenario: rare exceedances of the coupled model's limits.

``study.scenarios.subset`` (schema: ``study.schema.yaml``) runs, per configured limit, subset
simulation (:mod:`ttbpipe.reliability.subset`) of ``g(u) = 1 - index / limit`` with the study's
coupled model (train, structure, run settings of ``simulation:``), its random inputs a function
of standard normals (:class:`ttbpipe.reliability.inputs.StandardNormalInputs`: Gaussian
irregularity with its spectral level drawn from the latest campaign's PSD population, or the
standard spectrum of ``simulation.irregularity.spectrum``; the fields of ``condition``), seeded
by the study seed. Each chain step's points are evaluated in worker processes, or on the study's
Dask cluster (``simulation.executor: dask``); the estimator's state is saved after every ask
and every tell (temporary file + rename), so a killed run resumes where it stopped and gives the
same estimate as an uninterrupted one. The result is one row (:data:`RESULT_COLUMNS`) plus the
levels table; :func:`rare_event_table` adds the target verdicts for the report.

Runs outside Snakemake too::

    python -m ttbpipe.reliability.study --config config/config.yaml --limit wheel_unloading_ratio \
        --out results/study/subset/wheel_unloading_ratio.parquet --workers 2
"""

from __future__ import annotations

import argparse
import copy
import hashlib
import json
import logging
import os
import time
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from ..stats.limits import limits_from_config
from ..study.design import resolve_subset
from .coupled import CoupledLimitState
from .subset import SubsetSettings, SubsetSimulation

log = logging.getLogger(__name__)

__all__ = ["resolve_subset", "subset_inputs", "run_subset_limit", "rare_event_table",
           "rare_events_html", "RESULT_COLUMNS", "RARE_EVENT_COLUMNS", "SCENARIO_LABEL"]

#: Scenario label of the subset-simulation estimates in the reliability tables.
SCENARIO_LABEL = "subset"

RESULT_COLUMNS = ("scenario", "limit", "column", "threshold", "probability", "ci_low", "ci_high",
                  "cov", "reliability_index", "n_evaluations", "method", "confidence_level",
                  "n_dims", "n_levels", "wall_time_s")


def subset_inputs(config: Mapping[str, Any], settings: Mapping[str, Any],
                  population_paths: Sequence[str] | None = None):
    """The standard-normal input map of the scenario (no fields for ``condition: none``).

    ``spectrum: population`` needs the PSD tables of the latest campaign's population
    (``population_paths``): the levels are then drawn from its per-frequency fits with the
    cross-channel level correlation measured on its sections
    (:meth:`ttbpipe.irregularity.gaussian.GaussianIrregularityModel.from_population`)."""
    from .inputs import StandardNormalInputs

    spectrum = None
    if settings["spectrum"] == "population":
        if not population_paths:
            raise ValueError("study.scenarios.subset.spectrum: population needs the PSD tables of "
                             "the latest campaign's population; pass them, or set spectrum: "
                             "standard to use simulation.irregularity.spectrum")
        from ..tipm.population import pooled_population

        spectrum = pooled_population(list(population_paths), None)
    condition = settings["condition"]
    if condition == "none" or config.get("fields") is None:
        config = {k: v for k, v in config.items() if k != "fields"}
        condition = "all"
    return StandardNormalInputs(config, spectrum=spectrum, condition=condition)


def _case(config: Mapping[str, Any], inputs) -> dict[str, Any]:
    from ..study.samples import build_case, resolve_simulation

    sim = resolve_simulation(config.get("simulation"))
    return build_case(sim, config.get("structure") or {}, irregularity=inputs.irregularity_settings)


def _limit(config: Mapping[str, Any], name: str):
    limits, context = limits_from_config(config.get("limits"))
    by_name = {lim.name: lim for lim in limits}
    if name not in by_name:
        raise ValueError(f"study.scenarios.subset.limits: {name!r} is not an enabled limit of the "
                         f"limits: section; enabled: {sorted(by_name)}")
    limit = by_name[name]

    def threshold(row: Mapping[str, float]) -> float:
        return float(limit.thresholds(pd.DataFrame([dict(row)]), context)[0])

    return limit, threshold


def settings_digest(config: Mapping[str, Any], limit_name: str, model_version: str = "",
                    population_paths: Sequence[str] | None = None) -> str:
    """Digest of everything the estimate depends on, input files' contents included (the state
    file's name carries it: a state of other settings or data is never resumed)."""
    keys: dict[str, Any] = {k: config.get(k) for k in ("structure", "simulation", "fields",
                                                       "limits")}
    keys["population"] = [hashlib.sha256(Path(p).read_bytes()).hexdigest()
                          for p in sorted(population_paths or [])]
    keys["seed"] = int(config["study"]["seed"])
    keys["subset"] = resolve_subset(config)
    keys["limit"] = limit_name
    keys["model_version"] = model_version
    return hashlib.sha256(json.dumps(keys, sort_keys=True, default=str).encode()).hexdigest()[:12]


def run_subset_limit(config: Mapping[str, Any], limit_name: str, out: str | os.PathLike[str], *,
                     population_paths: Sequence[str] | None = None,
                     state_dir: str | os.PathLike[str] | None = None, workers: int = 1,
                     model_version: str = "", stop_after_evaluations: int | None = None
                     ) -> pd.DataFrame:
    """Subset simulation of one limit; writes ``out`` (one row, :data:`RESULT_COLUMNS`) and
    ``<out stem>.levels.csv``; returns the row.

    ``state_dir`` (default: beside ``out``) holds ``<limit>.<digest>.state.npz``, the resumable
    state. ``stop_after_evaluations`` stops (raising ``KeyboardInterrupt``, as a kill would)
    once that many model runs are done: for testing resumption.
    """
    out = Path(out)
    settings = resolve_subset(config)
    limit, threshold = _limit(config, limit_name)
    inputs = subset_inputs(config, settings, population_paths)
    digest = settings_digest(config, limit_name, model_version, population_paths)
    state_dir = Path(state_dir) if state_dir is not None else out.parent
    state_dir.mkdir(parents=True, exist_ok=True)
    state_path = state_dir / f"{limit_name}.{digest}.state.npz"
    sus_settings = SubsetSettings(n_per_level=settings["n_per_level"],
                                  level_probability=settings["level_probability"],
                                  max_levels=settings["max_levels"],
                                  sampler=settings["sampler"],
                                  confidence_level=float((config.get("limits") or {}).get(
                                      "confidence_level", 0.95)))
    if state_path.exists():
        sus = SubsetSimulation.load(state_path)
        log.info("%s: resuming subset simulation at level %d after %d runs (%s)", limit_name,
                 sus.level, sus.n_evaluations, state_path)
    else:
        sus = SubsetSimulation(inputs.n_dims, int(config["study"]["seed"]), sus_settings)
    log.info("%s: subset simulation in %d standard-normal dimensions (%s)", limit_name,
             inputs.n_dims, inputs.describe())
    t0 = time.time()
    from ..study.samples import resolve_simulation

    sim = resolve_simulation(config.get("simulation"))
    with CoupledLimitState(_case(config, inputs), inputs, limit.column, threshold, workers,
                           executor=sim["executor"], dask=sim.get("dask")) as g:
        while not sus.done:
            points = sus.ask()
            sus.save(state_path)
            sus.tell(g(points))
            sus.save(state_path)
            log.info("%s: level %d, %d runs", limit_name, sus.level, sus.n_evaluations)
            if stop_after_evaluations is not None and sus.n_evaluations >= stop_after_evaluations:
                raise KeyboardInterrupt(f"stopped after {sus.n_evaluations} runs (test)")
    result = sus.result()
    levels = result.details["levels"]
    row = {"scenario": SCENARIO_LABEL, "limit": limit.name, "column": limit.column,
           "threshold": threshold(g.evaluations[0]) if g.evaluations else float("nan"),
           **result.as_row(), "n_dims": inputs.n_dims, "n_levels": len(levels),
           "wall_time_s": time.time() - t0}
    table = pd.DataFrame([row], columns=list(RESULT_COLUMNS))
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".tmp")
    table.to_parquet(tmp)
    os.replace(tmp, out)
    levels_path = out.with_suffix(".levels.csv")
    levels.to_csv(levels_path.with_name(levels_path.name + ".tmp"), index=False)
    os.replace(levels_path.with_name(levels_path.name + ".tmp"), levels_path)
    log.info("%s: %s", limit_name, result)
    return table


RARE_EVENT_COLUMNS = (*RESULT_COLUMNS, "target_probability", "target_verdict", "target_text",
                      "ordinary_estimates")


def rare_event_table(subset_paths: Sequence[str | os.PathLike[str]],
                     reliability: pd.DataFrame | None = None,
                     limits_section: Mapping[str, Any] | None = None) -> pd.DataFrame:
    """The subset-simulation estimates with their target verdicts and, for the cross-check, the
    estimate each ordinary scenario of the reliability table states for the same limit (the
    counting one, or the tail model's when no sample exceeds; ``verdict_basis``)."""
    from ..stats.reliability import ReliabilitySettings, interval_verdict
    from ..study.report_pages import stated_cell

    target = ReliabilitySettings.from_config(limits_section).target_probability
    frames = [pd.read_parquet(p) for p in subset_paths]
    table = (pd.concat(frames, ignore_index=True) if frames
             else pd.DataFrame(columns=list(RESULT_COLUMNS)))
    rows = []
    for _, r in table.iterrows():
        verdict, text = interval_verdict(r["probability"], r["ci_low"], r["ci_high"], target,
                                         f"subset simulation, {int(r['n_evaluations'])} runs")
        others = []
        if reliability is not None and "verdict_basis" in reliability:
            same = reliability[(reliability["limit"] == r["limit"])
                               & reliability["probability"].notna()]
            others = [f"{o['scenario']}: {stated_cell(o)}, {int(o['n_samples'])} runs"
                      for _, o in same.iterrows()]
        rows.append({**r.to_dict(), "target_probability": target, "target_verdict": verdict,
                     "target_text": text, "ordinary_estimates": "; ".join(others)})
    return pd.DataFrame(rows, columns=list(RARE_EVENT_COLUMNS))


def rare_events_html(table: pd.DataFrame) -> str:
    """The report page of the subset-simulation estimates."""
    from ..study.report_pages import table_html

    shown = table[["limit", "threshold", "probability", "ci_low", "ci_high", "cov",
                   "reliability_index", "n_evaluations", "n_dims", "n_levels", "target_text",
                   "ordinary_estimates"]]
    note = ("Subset simulation of the coupled model (Au & Beck 2001) for each configured limit: "
            "probability per passage, its confidence interval (lognormal, Au & Beck c.o.v.), "
            "the reliability index beta = -Phi^-1(P), the number of coupled runs and the "
            "dimension of the standard-normal input; the verdict compares the interval with the "
            "target probability (limits.target_probability). The last column gives, for the "
            "cross-check, the estimate of every ordinary scenario for the same limit.")
    return table_html(shown, "Rare events: subset simulation", note)


def main(argv: list[str] | None = None) -> int:
    import yaml

    parser = argparse.ArgumentParser(description="subset simulation of one limit of a study")
    parser.add_argument("--config", required=True)
    parser.add_argument("--limit", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--population", nargs="*", default=None,
                        help="PSD tables (results/psd/<date>.parquet) of the population "
                             "(spectrum: population)")
    parser.add_argument("--workers", type=int, default=1)
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")
    with open(args.config) as fh:
        config = yaml.safe_load(fh)
    run_subset_limit(copy.deepcopy(config), args.limit, args.out, workers=args.workers,
                     population_paths=args.population)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
