"""Paper case studies: designs, seeds, the scale switch, eq. 55 and the comparisons.

Fast tests of ttbpipe.study.cases / design extensions; the coupled runs are in
test_cases_runs.py.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import yaml

from ttbpipe.study.cases import (apply_scale, compare_histories, forecast_limits,
                                 resonance_speeds, speed_batches, sweep_resonances, sweep_speeds,
                                 train_load_interval_m)
from ttbpipe.study.design import (build_design, forecast_label, mc_section, parse_forecast_label,
                                  scenario_labels)

SEED = 11


def _study(**scenarios):
    base = {"irregularity": {"enabled": False}, "forecast": {"enabled": False},
            "fields": {"enabled": False}}
    base.update(scenarios)
    return {"seed": SEED, "scenarios": base}


def test_eq55_reproduces_the_papers_resonance_speeds():
    """Seed paper section 5.1: f = 8.91 Hz (vertical), 3.98 Hz (lateral), L_g = 22.125 m give
    709 and 317 km/h by eq. 55 (i = 1). Tolerance 1 km/h (the paper rounds to integers)."""
    table = resonance_speeds({"vertical": 8.91, "lateral": 3.98}, 22.125, (200.0, 800.0))
    first = table[table["order"] == 1].set_index("direction")["speed_kmh"]
    assert first["vertical"] == pytest.approx(709.0, abs=1.0)
    assert first["lateral"] == pytest.approx(317.0, abs=1.0)
    # i = 2 of the vertical (355 km/h) is inside the range; i = 2 of the lateral (158) is not
    orders = set(map(tuple, table[["direction", "order"]].to_numpy()))
    assert ("vertical", 2) in orders and ("lateral", 2) not in orders


def test_load_interval_is_the_car_length():
    """Eq. 55's regular load interval for identical cars = car length (25 m, parameters.py)."""
    assert train_load_interval_m({"composition": ["motor", "trailer", "motor"]}) == 25.0


def test_sweep_speeds_and_batches():
    """200-800 km/h by 10 km/h is 61 speeds (the paper's sweep); batches cover each once."""
    speeds = sweep_speeds({"speeds_kmh": [200, 800, 10]})
    assert len(speeds) == 61 and speeds[0] == 200 and speeds[-1] == 800
    batches = speed_batches(speeds, 4)
    covered = [i for a, b in batches for i in range(a, b + 1)]
    assert covered == list(range(61))
    with pytest.raises(ValueError):
        sweep_speeds({"speeds_kmh": [800, 200, 10]})


def test_sweep_reaches_1p2_times_the_line_speed():
    """EN 1991-2 6.4.6.2(1): speeds up to 1.2 x the maximum line speed."""
    speeds = sweep_speeds({"speeds_kmh": [200, None, 10], "line_speed_kmh": 350})
    assert speeds[-1] == 420 and speeds[0] == 200 and len(speeds) == 23
    speeds = sweep_speeds({"speeds_kmh": [200, None, 15], "line_speed_kmh": 350})
    assert speeds[-1] == 425                       # the first step at or above 420
    assert sweep_speeds({"speeds_kmh": [200, 800, 10], "line_speed_kmh": 350})[-1] == 800
    with pytest.raises(ValueError, match="below 1.2 x the line speed 350 km/h = 420"):
        sweep_speeds({"speeds_kmh": [200, 400, 10], "line_speed_kmh": 350})
    with pytest.raises(ValueError, match="no line_speed_kmh"):
        sweep_speeds({"speeds_kmh": [200, None, 10]})


def test_sweep_resonance_finds_the_peak_near_the_prediction():
    """A synthetic response with a peak at 500 km/h: found at 500 within a +-40 km/h window."""
    v = np.arange(200.0, 801.0, 10.0)
    sweep = pd.DataFrame({"speed_kmh": v, "acc": 0.1 + np.exp(-((v - 500) / 15) ** 2)})
    found = sweep_resonances(sweep, "acc", [505.0, 253.0], 40.0)
    assert found.iloc[0]["peak_kmh"] == 500.0
    assert found.iloc[0]["ratio_to_median"] > 5


def test_scale_small_merges_the_overlay():
    """scale=small deep-merges small: (mappings merged, lists replaced); full drops it."""
    cfg = {"scale": "small", "a": {"b": 1, "c": [1, 2]}, "small": {"a": {"c": [3]}}}
    apply_scale(cfg)
    assert cfg == {"scale": "small", "a": {"b": 1, "c": [3]}}
    cfg = {"a": 1, "small": {"a": 2}}
    assert apply_scale(cfg) == {"a": 1}
    cfg = {"scale": "medium", "a": 1, "small": {"a": 2}, "medium": {"a": 3}}
    assert apply_scale(cfg) == {"scale": "medium", "a": 3}
    with pytest.raises(ValueError, match="no small"):
        apply_scale({"scale": "small"})


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_case_files_validate_against_the_schema(n):
    """Each config/case<N>.yaml, merged over config/config.yaml (as --configfile does), full and
    small, is valid against the study schema (ttbpipe.configuration: every section, strict)."""
    from pathlib import Path

    from ttbpipe.configuration import validate_study_config
    from ttbpipe.study.cases import _merge

    root = Path(__file__).resolve().parents[1]
    for scale in ("full", "medium", "small") if n in (2, 3) else ("full", "small"):
        cfg = yaml.safe_load((root / "config" / "config.yaml").read_text())
        _merge(cfg, yaml.safe_load((root / "config" / f"case{n}.yaml").read_text()))
        cfg["scale"] = scale
        apply_scale(cfg)
        validate_study_config(cfg, f"case{n}.yaml (scale {scale})")
        assert cfg["case"]["name"] == f"case{n}"


def test_fields_mc_and_irregularity_mc_designs():
    """fields_mc: label <condition>_mc, condition kept; irregularity_mc: sections drawn from the
    sample's own seed, so the first samples do not change when more are asked for."""
    study = _study(fields_mc={"enabled": True, "conditions": ["C4"], "samples": 5},
                   irregularity_mc={"enabled": True, "samples": 6})
    design = build_design(study, latest_campaign="2025-12-15", n_population_sections=180)
    mc = design[design["scenario"] == "C4_mc"]
    assert len(mc) == 5 and set(mc["kind"]) == {"fields_mc"} and set(mc["condition"]) == {"C4"}
    irr = design[design["scenario"] == "mc"]
    assert list(irr["profile_index"]) == [mc_section(SEED, i, 180) for i in range(6)]
    bigger = build_design({**study, "scenarios": {**study["scenarios"],
                                                 "irregularity_mc": {"enabled": True, "samples": 60}}},
                          latest_campaign="2025-12-15", n_population_sections=180)
    head = bigger[bigger["scenario"] == "mc"].iloc[:6]
    assert list(head["profile_index"]) == list(irr["profile_index"])
    assert list(head["seed_entropy"]) == list(irr["seed_entropy"])
    with pytest.raises(ValueError, match="sections"):
        build_design(study, latest_campaign="2025-12-15")


def test_mc_sections_are_uniform():
    """Equal-probability draw of whole sections: 4000 draws over 10 sections, chi-square test
    (scipy) does not reject uniformity at 0.1 %."""
    from scipy import stats

    draws = [mc_section(SEED, i, 10) for i in range(4000)]
    counts = np.bincount(draws, minlength=10)
    assert stats.chisquare(counts).pvalue > 1e-3


def test_forecast_levels_labels_and_design():
    """forecast.levels: one scenario per (target date, level), TIPM weights of that level."""
    study = _study(forecast={"enabled": True, "levels": [0.05, 0.5, 0.95], "horizons_months": [6]})
    labels = scenario_labels(study, "2025-12-15", [6, 12])
    assert labels["forecast"] == ["2026-06-15_p0.05", "2026-06-15_p0.5", "2026-06-15_p0.95"]
    assert parse_forecast_label(forecast_label("2026-06-15", 0.95)) == ("2026-06-15", 0.95)
    assert parse_forecast_label("2026-06-15") == ("2026-06-15", None)
    states = pd.DataFrame([{"profile_index": 10 * k + i, "target_date": "2026-06-15", "level": p,
                            "sample_index": i, "weight": 0.5}
                           for k, p in enumerate([0.05, 0.5, 0.95]) for i in range(2)])
    design = build_design(study, latest_campaign="2025-12-15", forecast_states=states,
                          horizons_months=[6, 12])
    upper = design[design["scenario"] == "2026-06-15_p0.95"]
    assert list(upper["profile_index"]) == [20, 21]


def test_compare_histories_scores_agreement():
    """Identical curves: zero differences, correlation 1; a 10 % larger std: 10 % difference."""
    x = np.linspace(0, 100, 51)
    base = pd.DataFrame({"position_m": x, "mean": np.sin(x / 10), "std": 1 + np.cos(x / 7) ** 2})
    stats = pd.concat([base.assign(scenario="a", quantity="q"),
                       base.assign(scenario="b", quantity="q"),
                       base.assign(scenario="c", quantity="q", std=1.1 * base["std"])])
    same = compare_histories(stats, "q", "a", "b")
    assert same["max_mean_difference_rel"] == 0 and same["std_correlation"] == pytest.approx(1)
    assert compare_histories(stats, "q", "a", "c")["max_std_difference_rel"] == pytest.approx(0.1)


def test_forecast_limits_weighted_means():
    """Fig. 17 limits: weighted mean per (horizon, level), months from the base date."""
    ext = pd.DataFrame({"scenario": ["2026-06-15_p0.05"] * 2 + ["2026-06-15_p0.95"] * 2,
                        "weight": [1.0, 3.0, 1.0, 1.0], "acc": [1.0, 2.0, 3.0, 5.0]})
    lim = forecast_limits(ext, "acc", "2025-12-15")
    assert list(lim["level"]) == [0.05, 0.95]
    assert lim["mean"].tolist() == pytest.approx([1.75, 4.0])
    assert lim["months"].iloc[0] == pytest.approx(6.0)
