"""Paper cases 2, 3 and 4 end to end at a few samples per scenario, in the default test run.

Their small variants (tests/test_cases_small.py, marker ``validation``) check the paper's
conclusions and take 4-15 min each; these runs check that each case's whole pipeline still goes
from its configuration file (config/case2.yaml, config/case3.yaml, config/case4.yaml) through
the study, the aggregation and the comparison rule to the tables, the summary and the paper's
figures, with the counts the configuration asks for and finite numbers. With 2-5 samples a
scenario the spreads themselves are noise, so no statistical conclusion is asserted here.

The cases' bridges and trains are shrunk (:data:`SHRUNK_MODEL`: one 32 m span, 40 m approaches, a
motor and a trailer car), which leaves every rule, scenario and figure of the pipeline in place
and makes a coupled run about a second instead of five to ten: the paper's layouts themselves run
in the small variants and in docs/validation.md.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from test_cases_small import run_case

pytestmark = pytest.mark.slow

#: Merged into each tiny case's overlay: one span and two cars, far below the paper's layouts.
SHRUNK_MODEL = """\
structure:
  layout:
    approach_length_m: 40.0
    spans_m: [32.0]
simulation:
  train:
    composition: [motor, trailer]
"""

CASE2_TINY = """\
results_dir: results/case2_tiny
logs_dir: logs/case2_tiny
study:
  scenarios:
    fields: {samples: 2}
    fields_mc: {samples: 3}
"""

CASE3_TINY = """\
results_dir: results/case3_tiny
logs_dir: logs/case3_tiny
inspections:
  synthetic:
    directory: resources/inspections/synthetic_case3_tiny
    campaigns: 3
    length_km: 10.0
study:
  scenarios:
    irregularity_mc: {samples: 3}
"""


CASE4_TINY = """\
results_dir: results/case4_tiny
logs_dir: logs/case4_tiny
inspections:
  synthetic:
    directory: resources/inspections/synthetic_case4_tiny
    campaigns: 6
    length_km: 3.0
tipm:
  selection: {min_samples: 2, max_samples: 2}
study:
  scenarios:
    forecast: {horizons_months: [6]}
"""


def _finite(frame: pd.DataFrame, columns: list[str]) -> bool:
    return bool(np.isfinite(frame[columns].to_numpy(dtype=float)).all())


def _figures_written(out, *names: str) -> bool:
    return all((out / "figures" / name).stat().st_size > 1000 for name in names)


def test_case2_pipeline_writes_fig10_table1_and_figures(tmp_path):
    out = run_case(tmp_path, 2, overlay=CASE2_TINY + SHRUNK_MODEL, name="case2_tiny")
    summary = (out / "summary.md").read_text()
    assert "Samples per scenario: C1 2, C2 2, C3 2, C4 2, C4_mc 3" in summary
    comparison = pd.read_parquet(out / "comparison.parquet")
    fig10 = comparison[(comparison["reference"] == "C4_mc") & (comparison["other"] == "C4")]
    assert fig10["quantity"].tolist() == ["girder_vertical_disp_m"]
    assert _finite(fig10, ["std_correlation", "max_std_difference_rel", "max_std_ref"])
    table1 = comparison[comparison["reference"] == "table1_history"]
    assert {"girder_vertical_disp_m", "girder_vertical_acc_m_s2",
            "rail_vertical_acc_m_s2"} <= set(table1["quantity"])
    assert _finite(table1, ["C1", "C2", "C3", "C4"])
    assert (table1[["C1", "C2", "C3", "C4"]].to_numpy(dtype=float) > 0).all()
    assert _figures_written(out, "fig09_girder_disp_spread_C4.png", "fig10_kle_vs_mc_girder_disp.png",
                            "fig11_girder_lateral_acc.png", "fig12_wheel_lateral_force.png",
                            "fig13_carbody_vertical_acc.png")


def test_case3_pipeline_writes_tipm_mc_single_comparison_and_figures(tmp_path):
    out = run_case(tmp_path, 3, overlay=CASE3_TINY + SHRUNK_MODEL, name="case3_tiny")
    summary = (out / "summary.md").read_text()
    # 3 campaigns x 10 one-kilometre sections: floor(0.1 x 30) = 3 TIPM sets, raised to the
    # configured minimum of 5 (tipm.selection.min_samples)
    counts = summary.split("Samples per scenario: ", 1)[1].split("\n", 1)[0]
    scenarios = dict(item.rsplit(" ", 1) for item in counts.split(", "))
    assert scenarios.pop("mc") == "3" and scenarios.pop("single") == "1"
    assert list(scenarios.values()) == ["5"]                  # the latest campaign's TIPM sets
    comparison = pd.read_parquet(out / "comparison.parquet")
    curves = comparison[(comparison["reference"] == "mc") & (comparison["other"] != "single")]
    assert set(curves["quantity"]) == {"rail_vertical_acc_m_s2", "girder_vertical_acc_m_s2",
                                       "wheel_vertical_force_N"}
    assert _finite(curves, ["std_correlation", "max_std_difference_rel"])
    single = comparison[comparison["other"] == "single"]
    assert len(single) == 8                  # 4 maxima, each for the TIPM sets and for MC
    assert _finite(single, ["mean", "single", "p_exceed_single"])
    assert _figures_written(out, "fig14_tipm_vs_mc_rail_acc.png", "fig15a_pdf_wheel_vertical_force.png",
                            "fig15b_pdf_wheel_lateral_force.png", "fig16a_pdf_rail_vertical_acc.png",
                            "fig16b_pdf_rail_lateral_acc.png")


def test_case4_pipeline_writes_forecast_levels_and_figure(tmp_path):
    out = run_case(tmp_path, 4, overlay=CASE4_TINY + SHRUNK_MODEL, name="case4_tiny")
    comparison = pd.read_parquet(out / "comparison.parquet")
    for quantity in ("max_wheel_vertical_force_N", "max_deck_vertical_acc_m_s2"):
        rows = comparison[comparison["quantity"] == quantity]
        assert sorted(rows["level"]) == [0.05, 0.5, 0.95]
        assert set(rows["months"]) == {6}
        assert _finite(rows, ["mean"]) and (rows["mean"] > 0).all()
    assert _figures_written(out, "fig17_forecast_limits.png")
