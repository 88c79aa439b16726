"""EN 1991-2 dynamic analysis (ttbpipe.en1991) against the standard's formulas and beam theory.

References (independent of the code under test):
* EN 1991-2:2003 Figure 6.10, eqs. 6.1-6.3: n0 upper limit 94.76 L^-0.748, lower limit 80/L
  (4-20 m) and 23.58 L^-0.592 (20-100 m); values typed from the formulas by hand;
* EN 1991-2 Figure 6.9: above 200 km/h a dynamic analysis is required;
* simply supported Euler-Bernoulli beam: n0 = (pi / (2 L^2)) sqrt(EI / m); midspan deflection
  under a point load P at a <= L/2: P a (3 L^2 - 4 a^2) / (48 EI) (Timoshenko & Gere);
* the moving-force modal superposition of tests/test_trains.py (``modal_reference``, an exact
  integration of the first five simply supported modes), for the dynamic peaks.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from test_trains import DT, MU, ZETA, girder_EI, modal_reference
from ttbpipe.en1991.dynamic import MONITOR_POSITIONS, span_model, sweep_train, track_mass_per_m
from ttbpipe.en1991.limits import dynamic_analysis_need, n0_limits_hz, resonance_speeds_kmh
from ttbpipe.en1991.study import run_train, settings, speeds_kmh, summarise
from ttbpipe.trains import get_train

SPAN = 32.0
#: the girder of tests/test_trains.py (n0 = 4.000 Hz, 1 % damping), no track
BARE = {"layout": {"approach_length_m": 0.0, "spans_m": [SPAN], "bridge_track": "none"},
        "girder": {"damping_ratio": ZETA, "mass_kg_m": MU, "Iy_m4": girder_EI(SPAN) / 3.45e10}}


def test_figure_6_10_limits():
    # hand values: 94.76 * 32^-0.748 = 7.0921, 23.58 * 32^-0.592 = 3.0304; 80/10 = 8,
    # 94.76 * 10^-0.748 = 16.929; 23.58 * 100^-0.592 = 1.5436
    assert n0_limits_hz(32.0) == pytest.approx((3.0304, 7.0921), rel=2e-4)
    assert n0_limits_hz(10.0) == pytest.approx((8.0, 16.929), rel=2e-4)
    assert n0_limits_hz(100.0)[0] == pytest.approx(1.5436, rel=2e-4)
    # continuous at 20 m within the rounding of the standard's coefficients (80/20 = 4.0)
    assert 23.58 * 20.0 ** -0.592 == pytest.approx(4.0, rel=0.01)
    with pytest.raises(ValueError, match="4 m <= L <= 100 m"):
        n0_limits_hz(120.0)


def test_figure_6_9_branches():
    assert dynamic_analysis_need(350, 32, 5.0).required is True
    assert "200 km/h" in dynamic_analysis_need(350, 32, 5.0).reason
    assert dynamic_analysis_need(160, 32, 9.0).required is True          # above the upper limit
    assert dynamic_analysis_need(160, 32, 5.0, torsion_hz=5.5).required is True   # < 1.2 n0
    open_case = dynamic_analysis_need(160, 32, 5.0, torsion_hz=12.0)
    assert open_case.required is None and "Annex F" in open_case.verdict
    assert dynamic_analysis_need(160, 120, 2.0).required is True         # outside Figure 6.10


def test_span_model_frequency_and_track_mass():
    span = span_model(BARE, SPAN)
    EI = girder_EI(SPAN)
    assert span.n0_hz == pytest.approx(np.pi / (2 * SPAN ** 2) * np.sqrt(EI / MU), rel=1e-3)
    assert span.n3_hz == pytest.approx(9 * span.n0_hz, rel=2e-3)
    assert span.damping_ratio == ZETA
    # with the default slab track its mass is added: slab 2500 x width x thickness + 2 rails
    slab = {"layout": {"spans_m": [SPAN], "bridge_track": "slab"}}
    from ttbpipe.structure import properties
    cfg = properties.resolve(slab)
    expected = (cfg["slab"]["density_kg_m3"] * cfg["slab"]["width_m"] * cfg["slab"]["thickness_m"]
                + 2 * cfg["rail"]["mass_kg_m"])
    assert track_mass_per_m(slab) == pytest.approx(expected)
    assert span_model(slab, SPAN).mass_kg_m == pytest.approx(cfg["girder"]["mass_kg_m"] + expected)


def _static_reference_mm(train, EI, L=SPAN, step=0.05):
    """Largest midspan deflection of the train standing anywhere (closed-form influence line)."""
    best = 0.0
    for front in np.arange(0.0, L + train.length_m + 1e-9, step):
        a = front - train.positions_m
        on = (a >= 0) & (a <= L)
        b = np.minimum(a[on], L - a[on])
        best = max(best, float(np.sum(train.axle_loads_N[on] * b * (3 * L ** 2 - 4 * b ** 2))
                               / (48 * EI)))
    return 1e3 * best


@pytest.mark.parametrize("name", ["HSLM-A1", "HSLM-A7"])
def test_sweep_against_modal_superposition_and_static_influence_line(name):
    """Peaks within 5 % of the modal reference (EN 1991-2 asks for the peak response; the
    reference's own cut-off of five modes is the model's 120 Hz), static deflection within
    0.5 % of the influence line (five-mode truncation of a point load: 0.07 %), the resonance
    at V = n0 D the largest acceleration of HSLM-A1."""
    span = span_model(BARE, SPAN)
    train = get_train(name)
    D = train.parameters["D_m"]
    v_res = resonance_speeds_kmh(span.n0_hz, D)[1]
    speeds = [200.0, v_res, 360.0]
    table = sweep_train(span, name, speeds, time_step_s=DT)
    static = _static_reference_mm(train, girder_EI(SPAN))
    assert table["static_deflection_mm"].iloc[0] == pytest.approx(static, rel=5e-3)
    for _, row in table.iterrows():
        v = row["speed_kmh"] / 3.6
        _, w_ref, _ = modal_reference(train.positions_m, train.axle_loads_N, v)
        a_ref = max(np.abs(modal_reference(train.positions_m, train.axle_loads_N, v,
                                           x=f * SPAN)[2]).max() for f in MONITOR_POSITIONS)
        assert row["deflection_mm"] == pytest.approx(1e3 * w_ref.max(), rel=0.05)
        assert row["deck_acc_raw_m_s2"] == pytest.approx(a_ref, rel=0.05)
        assert row["deck_acc_m_s2"] <= row["deck_acc_raw_m_s2"] + 1e-12   # the band only removes
        assert row["dynamic_amplification"] == pytest.approx(row["deflection_mm"] / static,
                                                             rel=5e-3)
    if name == "HSLM-A1":
        assert table["deck_acc_m_s2"].idxmax() == 1


def _static_end_rotation_reference_mrad(train, EI, L=SPAN, step=0.05):
    """Largest end rotation of the train standing anywhere: a point load P at a from A rotates
    the ends by P b (L^2 - b^2) / (6 L EI) at A (b = L - a) and P a (L^2 - a^2) / (6 L EI) at B
    (Timoshenko & Gere)."""
    best = 0.0
    for front in np.arange(0.0, L + train.length_m + 1e-9, step):
        a = front - train.positions_m
        on = (a >= 0) & (a <= L)
        a, P = a[on], train.axle_loads_N[on]
        b = L - a
        best = max(best, float(np.sum(P * b * (L ** 2 - b ** 2))) / (6 * L * EI),
                   float(np.sum(P * a * (L ** 2 - a ** 2))) / (6 * L * EI))
    return 1e3 * best


def test_quasi_static_crossing_matches_the_static_train():
    """At 10 km/h the train crosses slowly: y_dyn / y_stat within 2 % of 1 and the end rotation
    within 2 % of the static closed form (the remaining difference: the slow free vibration of
    1 % damping and the five-mode truncation)."""
    span = span_model(BARE, SPAN)
    train = get_train("HSLM-A5")
    row = sweep_train(span, "HSLM-A5", [10.0], time_step_s=2e-3).iloc[0]
    assert row["dynamic_amplification"] == pytest.approx(1.0, abs=0.02)
    assert row["end_rotation_mrad"] == pytest.approx(
        _static_end_rotation_reference_mrad(train, girder_EI(SPAN)), rel=0.02)


def test_speed_grid_and_summary_checks():
    config = {"structure": BARE, "en1991": {"trains": ["HSLM-A1", "HSLM-A4"],
                                            "line_speed_kmh": 250.0, "speed_min_kmh": 150.0,
                                            "speed_step_kmh": 25.0}}
    cfg = settings(config)
    grid = speeds_kmh(cfg, 4.0, cfg["trains"])
    assert grid[0] == 150.0 and grid[-1] == pytest.approx(300.0)     # 1.2 x 250
    assert np.any(np.isclose(grid, 3.6 * 4.0 * 18.0 / 1))            # HSLM-A1 i = 1: 259.2
    tables = [run_train(config, name) for name in cfg["trains"]]
    out = summarise(tables, config)
    checks = out["checks"].iloc[0]
    assert checks["need_for_dynamic_analysis"] == "dynamic analysis required"
    worst = pd.concat(tables)["deck_acc_m_s2"].max()
    assert checks["max_deck_acc_m_s2"] == worst
    assert checks["deck_acceleration_verdict"] == ("met" if worst <= 5.0 else "not met")
    env = out["envelope"]
    assert len(env) == len(grid)
    assert (env["deck_acc_m_s2"] >= tables[0].set_index("speed_kmh").loc[env["speed_kmh"],
                                                                          "deck_acc_m_s2"].values
            - 1e-12).all()
    assert "HSLM-A1" in out["summary"] and "Figure 6.9" in out["summary"]
    with pytest.raises(ValueError, match="unknown key"):
        settings({"en1991": {"speed": 3}})


@pytest.mark.slow
def test_en1991_study_runs_through_the_workflow(tmp_path):
    """`snakemake --configfile config/en1991.yaml` (two trains, a coarse grid) in a scratch copy:
    one job per train and one report job, the page and the tables under results/en1991/, and
    only the study's own outputs."""
    import subprocess
    import sys

    from test_workflow import _copy_repository

    _copy_repository(tmp_path)
    (tmp_path / "small.yaml").write_text(
        "en1991: {trains: [HSLM-A1, HSLM-A4], speed_min_kmh: 300.0, speed_step_kmh: 40.0}\n")
    proc = subprocess.run(
        [sys.executable, "-m", "snakemake", "--cores", "2", "--configfile", "config/en1991.yaml",
         "small.yaml"], cwd=tmp_path, capture_output=True, text=True, timeout=900)
    log = proc.stdout + proc.stderr
    assert proc.returncode == 0, log[-3000:]
    assert log.count("rule en1991_train:") == 2 and log.count("rule en1991_report:") == 1
    out = tmp_path / "results" / "en1991"
    summary = (out / "summary.md").read_text()
    assert "**dynamic analysis required**" in summary and "HSLM-A4" in summary
    checks = pd.read_parquet(out / "checks.parquet")
    assert list(checks["span_m"]) == [32.0]
    assert sorted(p.name for p in (tmp_path / "results").iterdir()) == ["en1991"]
    assert len(list((out / "figures").glob("*.png"))) == 3
