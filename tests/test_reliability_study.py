"""The study's subset-simulation scenario on the coupled model (ttbpipe.reliability.study).

A tiny coupled configuration (one car, one 32 m span, 0.18 s of run) with a carbody limit low
enough that two or three levels reach it with N = 20 per level. Checked: the estimate's
structure (probability inside its interval, evaluations = N + (levels - 1) (N - Nc)), that a
run killed mid-level leaves no output and resumes to the same numbers bit for bit, that the
estimate does not depend on the number of worker processes, and that the rule exists in the
workflow. Accuracy of the estimator itself: tests/test_reliability_estimators.py (exact
references); on the coupled model against Monte Carlo: docs/reliability.md §11.
"""

from __future__ import annotations

import copy

import pandas as pd
import pytest

from ttbpipe.reliability.study import RESULT_COLUMNS, run_subset_limit

CONFIG = {
    "study": {"seed": 3, "scenarios": {"subset": {"enabled": True,
                                                  "limits": ["carbody_vertical_acc"],
                                                  "spectrum": "standard",
                                                  "n_per_level": 20}}},
    "structure": {"layout": {"approach_length_m": 30.0, "spans_m": [32.0],
                             "approach_track": "ballasted", "bridge_track": "slab"}},
    "simulation": {"train": {"composition": ["trailer"]}, "end_x_m": 40.0},
    # far below TB 10621's 1.275 m/s^2, so that a few levels reach it
    "limits": {"thresholds": {"carbody_vertical_acc": 0.12}},
}


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    out = tmp_path_factory.mktemp("subset") / "carbody_vertical_acc.parquet"
    row = run_subset_limit(copy.deepcopy(CONFIG), "carbody_vertical_acc", out, workers=1)
    return out, row


def test_estimate_row_and_levels(uninterrupted):
    out, row = uninterrupted
    assert list(row.columns) == list(RESULT_COLUMNS)
    r = row.iloc[0]
    assert r["threshold"] == 0.12 and r["column"] == "max_carbody_vertical_acc_m_s2"
    assert 0.0 < r["probability"] < 0.1
    assert r["ci_low"] < r["probability"] < r["ci_high"]
    assert r["n_evaluations"] == 20 + (r["n_levels"] - 1) * 18
    levels = pd.read_csv(out.with_suffix(".levels.csv"))
    assert len(levels) == r["n_levels"]
    pd.testing.assert_frame_equal(pd.read_parquet(out), row)


def test_killed_run_resumes_to_the_same_estimate(uninterrupted, tmp_path):
    _, reference = uninterrupted
    out = tmp_path / "carbody_vertical_acc.parquet"
    with pytest.raises(KeyboardInterrupt):
        run_subset_limit(copy.deepcopy(CONFIG), "carbody_vertical_acc", out, workers=1,
                         stop_after_evaluations=29)
    assert not out.exists()                      # no partial output
    assert len(list(tmp_path.glob("*.state.npz"))) == 1
    # resumed with two worker processes: neither the kill nor the process count changes a value
    row = run_subset_limit(copy.deepcopy(CONFIG), "carbody_vertical_acc", out, workers=2)
    columns = [c for c in RESULT_COLUMNS if c != "wall_time_s"]
    pd.testing.assert_frame_equal(row[columns], reference[columns], check_exact=True)


def test_plane_sampler_is_selected_by_the_study(uninterrupted, tmp_path):
    """study.scenarios.subset.sampler: plane reaches SubsetSettings: the method names the plane
    sampler and the state file has a digest of its own. Twenty points per level never make a
    plane of n_dims + 1 coefficients eligible (it needs twice as many points), so every level
    runs aCS with the same random numbers: the aCS estimate bit for bit
    (tests/test_reliability_subset_plane.py checks the fallback on exact limit states)."""
    from ttbpipe.configuration import ConfigurationError
    from ttbpipe.reliability.study import resolve_subset, settings_digest

    _, reference = uninterrupted
    config = copy.deepcopy(CONFIG)
    config["study"]["scenarios"]["subset"]["sampler"] = "plane"
    assert resolve_subset(CONFIG)["sampler"] == "acs"
    assert (settings_digest(config, "carbody_vertical_acc")
            != settings_digest(CONFIG, "carbody_vertical_acc"))
    row = run_subset_limit(config, "carbody_vertical_acc", tmp_path / "plane.parquet", workers=1)
    assert "plane sampler" in row.iloc[0]["method"]
    assert "aCS sampler" in reference.iloc[0]["method"]
    columns = [c for c in RESULT_COLUMNS if c not in ("wall_time_s", "method")]
    pd.testing.assert_frame_equal(row[columns], reference[columns], check_exact=True)
    config["study"]["scenarios"]["subset"]["sampler"] = "gibbs"
    with pytest.raises(ConfigurationError, match="sampler"):
        resolve_subset(config)


def test_unknown_or_disabled_limit_is_named():
    config = copy.deepcopy(CONFIG)
    config["limits"]["disabled"] = ["carbody_vertical_acc"]
    with pytest.raises(ValueError, match="carbody_vertical_acc"):
        run_subset_limit(config, "carbody_vertical_acc", "/nonexistent/x.parquet")


def test_population_spectrum_draws_the_level_from_the_fits(tmp_path):
    """spectrum: population: the inputs map fits the campaign's PSD population and adds one
    level dimension per channel; u = 0 gives the median level, a high level normal a rougher
    profile (the per-frequency quantile grows with the level), and the digest follows the data."""
    import numpy as np

    from ttbpipe.channels import SPECTRAL_CHANNELS
    from ttbpipe.irregularity.spectra import get_spectrum
    from ttbpipe.reliability.study import resolve_subset, settings_digest, subset_inputs
    from ttbpipe.tipm import synthetic_population

    freq = np.arange(5, 501, 5) / 1000.0
    spectrum = get_spectrum("tbt3352")
    mean = np.stack([spectrum.psd_mm2_m(c, freq) for c in SPECTRAL_CHANNELS], axis=1)
    pop = synthetic_population(60, freq, mean, np.random.default_rng(1), welch_dof=2.0)
    rows = []
    for s in range(pop.n_sections):
        for k, c in enumerate(pop.channels):
            rows.append(pd.DataFrame({"section": s, "section_start_m": 200.0 * s,
                                      "section_end_m": 200.0 * (s + 1), "channel": c,
                                      "spatial_frequency_per_m": pop.frequency_per_m,
                                      "psd_mm2_m": pop.psd_mm2_m[s, :, k]}))
    path = tmp_path / "2025-12-15.parquet"
    pd.concat(rows).to_parquet(path)
    config = copy.deepcopy(CONFIG)
    config["study"]["scenarios"]["subset"]["spectrum"] = "population"
    settings = resolve_subset(config)
    with pytest.raises(ValueError, match="spectrum: standard"):
        subset_inputs(config, settings, None)
    inputs = subset_inputs(config, settings, [str(path)])
    levels = {k: v for k, v in inputs.describe().items() if k.endswith("/level")}
    assert len(levels) == 4 and all(v == 1 for v in levels.values())
    u = np.zeros(inputs.n_dims)
    u[inputs.slices["irregularity/vertical/coefficients"]] = 1.0
    median = inputs.profile(u)["vertical_mm"].std()
    u[inputs.slices["irregularity/vertical/level"]] = 2.0
    assert inputs.profile(u)["vertical_mm"].std() > 1.2 * median
    digest = settings_digest(config, "carbody_vertical_acc", "v", [str(path)])
    pd.concat(rows[:-1] + [rows[-1].assign(psd_mm2_m=rows[-1]["psd_mm2_m"] * 2)]).to_parquet(path)
    assert settings_digest(config, "carbody_vertical_acc", "v", [str(path)]) != digest


def test_rare_event_table_gives_the_verdict_and_the_ordinary_estimates(uninterrupted):
    from ttbpipe.reliability.study import RARE_EVENT_COLUMNS, rare_event_table, rare_events_html
    from ttbpipe.stats.reliability import interval_verdict

    out, row = uninterrupted
    reliability = pd.DataFrame([{
        "scenario": "2025-12-15", "limit": "carbody_vertical_acc", "probability": 0.0,
        "ci_low": 0.0, "ci_high": 0.012, "n_samples": 300, "verdict_basis": "tail",
        "tail_probability": 2e-3, "tail_ci_low": 1e-4, "tail_ci_high": 0.02}])
    table = rare_event_table([out], reliability, {"target_probability": 1e-3})
    assert list(table.columns) == list(RARE_EVENT_COLUMNS)
    r = table.iloc[0]
    expected = interval_verdict(row.iloc[0]["probability"], row.iloc[0]["ci_low"],
                                row.iloc[0]["ci_high"], 1e-3,
                                f"subset simulation, {row.iloc[0]['n_evaluations']} runs")
    assert (r["target_verdict"], r["target_text"]) == expected
    assert r["ordinary_estimates"] == "2025-12-15: 0.002 [1.00e-04, 0.02] (tail), 300 runs"
    assert "Rare events" in rare_events_html(table)
    empty = rare_event_table([], reliability, None)
    assert empty.empty and list(empty.columns) == list(RARE_EVENT_COLUMNS)


def test_dask_executor_gives_the_same_estimate(uninterrupted, tmp_path):
    """simulation.executor: dask (a LocalCluster of two single-threaded workers): the same
    numbers as the local run, bit for bit."""
    pytest.importorskip("distributed")
    _, reference = uninterrupted
    config = copy.deepcopy(CONFIG)
    config["simulation"]["executor"] = "dask"
    config["simulation"]["dask"] = {"local_workers": 2}
    row = run_subset_limit(config, "carbody_vertical_acc", tmp_path / "c.parquet")
    columns = [c for c in RESULT_COLUMNS if c != "wall_time_s"]
    pd.testing.assert_frame_equal(row[columns], reference[columns], check_exact=True)
