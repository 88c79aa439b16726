"""The paper cases' small variants, exactly as a user runs them:

    snakemake --cores 2 --configfile config/case<N>.yaml --config scale=small

each in a scratch copy of the repository, then the qualitative result the full case shows
(docs/validation.md) is checked on the small variant's own outputs under
results/case<N>_small/paper_comparison/. The thresholds are loose because the small variants
have tens of samples, not thousands; what must hold is the paper's conclusion, not its digits:

* case 1 (seed paper Fig. 8, eq. 55): the deck-acceleration peak of the sweep is the sweep speed
  nearest to this bridge's first vertical resonance 3.6 f1 d (d = 25 m, the car length);
* case 2 (Fig. 10, Table 1): MCM-KLE and plain MCM give the same girder-displacement standard
  deviation curve (correlation > 0.9, peak within 30 %), and the girder's randomness (C4)
  dominates the girder responses while the rail's (C1) dominates the rail acceleration;
* case 3 (Figs. 14-16): TIPM sets and plain Monte Carlo give the same standard-deviation curves
  (correlation > 0.9), and the single mean-spectrum excitation is exceeded by most full-
  excitation samples (the deterministic analysis is not conservative);
* case 4 (Fig. 17): at every horizon the upper limit (p = 0.95) is above the general state
  (p = 0.5), which is above the lower limit (p = 0.05), for the wheel force and deck acceleration.

Cases 2, 3 and 4 cost about 800, 600 and 430 CPU-seconds (112, 49 and 30 coupled runs): they
are marked ``validation`` and left out of the default run, which keeps the test suite within its
time budget; ``python -m pytest -m validation -n 2`` runs them (docs/validation.md). The default
run still drives the three cases' whole pipelines, configuration to comparison tables and
figures, at a few samples per scenario (tests/test_cases_tiny.py).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from test_workflow import _copy_repository

pytestmark = pytest.mark.slow


def run_case(tmp_path: Path, n: int, *, scale: str = "small", overlay: str | None = None,
             name: str | None = None) -> Path:
    """Run case n in a scratch copy, at ``scale`` or with an ``overlay`` configuration file (YAML
    text merged over the case file; it sets its own results_dir, ``results/<name>``); return its
    paper_comparison directory."""
    _copy_repository(tmp_path)
    command = [sys.executable, "-m", "snakemake", "--cores", "2", "--configfile",
               f"config/case{n}.yaml"]
    if overlay is not None:
        (tmp_path / "overlay.yaml").write_text(overlay)
        command.append("overlay.yaml")
    else:
        command += ["--config", f"scale={scale}"]
    proc = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True, timeout=1500)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    name = name or f"case{n}_{scale}"
    out = tmp_path / "results" / name / "paper_comparison"
    assert (out / "summary.md").stat().st_size > 200
    # the variant writes only under its own results_dir
    assert sorted(p.name for p in (tmp_path / "results").iterdir()) == [name]
    return out


def test_case1_small_resonance_peak_at_eq55(tmp_path):
    out = run_case(tmp_path, 1)
    sweep = pd.read_parquet(out / "sweep.parquet")
    assert sweep["speed_kmh"].tolist() == [200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0]
    resonance = pd.read_parquet(out / "resonance.parquet")
    first_vertical = resonance[(resonance["direction"] == "vertical") & (resonance["order"] == 1)]
    predicted_kmh = float(first_vertical["predicted_kmh"].iloc[0])
    # eq. 55, V = 3.6 f d / i, with this bridge's computed frequency and the 25 m car length
    assert (resonance["predicted_kmh"] == 3.6 * resonance["frequency_hz"] * 25.0
            / resonance["order"]).all()
    peak_kmh = float(sweep.loc[sweep["max_deck_vertical_acc_m_s2"].idxmax(), "speed_kmh"])
    nearest_kmh = float(sweep["speed_kmh"].iloc[(sweep["speed_kmh"] - predicted_kmh).abs().argmin()])
    assert peak_kmh == nearest_kmh, (peak_kmh, predicted_kmh)
    for name in ("fig06_rail_displacement_under_wheel.png", "fig07_girder_midspan.png",
                 "fig08_maxima_vs_speed.png"):
        assert (out / "figures" / name).stat().st_size > 1000


@pytest.mark.validation
def test_case2_small_kle_matches_mc_and_table1_dominance(tmp_path):
    out = run_case(tmp_path, 2)
    comparison = pd.read_parquet(out / "comparison.parquet")
    fig10 = comparison[(comparison["reference"] == "C4_mc") & (comparison["other"] == "C4")].iloc[0]
    assert fig10["quantity"] == "girder_vertical_disp_m"
    assert fig10["std_correlation"] > 0.9
    assert fig10["max_std_difference_rel"] < 0.3
    table1 = comparison[comparison["reference"] == "table1_history"].set_index("quantity")
    conditions = ["C1", "C2", "C3", "C4"]
    dominant = table1[conditions].astype(float).idxmax(axis=1)
    assert dominant["girder_vertical_disp_m"] == "C4"
    assert dominant["girder_vertical_acc_m_s2"] == "C4"
    assert dominant["rail_vertical_acc_m_s2"] == "C1"
    # the girder's own randomness moves its displacement by orders of magnitude more
    girder = table1.loc["girder_vertical_disp_m", conditions].astype(float)
    assert girder["C4"] > 50 * girder[["C1", "C2", "C3"]].max()


@pytest.mark.validation
def test_case3_small_tipm_matches_mc_and_single_excitation_is_exceeded(tmp_path):
    out = run_case(tmp_path, 3)
    comparison = pd.read_parquet(out / "comparison.parquet")
    curves = comparison[comparison["reference"] == "mc"].set_index("quantity")
    # the accelerations' std curves (Fig. 14); one wheel's force is driven by the irregularity
    # right under it and agrees less well at any size (docs/validation.md, case 3)
    for quantity in ("rail_vertical_acc_m_s2", "girder_vertical_acc_m_s2"):
        assert curves.loc[quantity, "std_correlation"] > 0.9, curves["std_correlation"]
    single = comparison[(comparison["other"] == "single")
                        & (comparison["quantity"] == "max_wheel_vertical_force_N")]
    assert len(single) == 2                      # TIPM sets and MC, each against the single run
    assert (single["p_exceed_single"] > 0.5).all()
    assert (single["mean"] > single["single"]).all()


@pytest.mark.validation
def test_case4_small_forecast_limits_are_ordered(tmp_path):
    out = run_case(tmp_path, 4)
    comparison = pd.read_parquet(out / "comparison.parquet")
    for quantity in ("max_wheel_vertical_force_N", "max_deck_vertical_acc_m_s2"):
        table = (comparison[comparison["quantity"] == quantity]
                 .pivot(index="months", columns="level", values="mean"))
        assert list(table.columns) == [0.05, 0.5, 0.95]
        assert len(table) == 2                   # the small variant's horizons: 6 and 12 months
        assert (table[0.95] > table[0.5]).all() and (table[0.5] > table[0.05]).all(), table
