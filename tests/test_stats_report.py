"""Report first page (reStructuredText, ttbpipe.study.report_pages), figures of ttbpipe.stats and
the `ttbpipe stats-report` command.

References: docutils (the parser the Snakemake report uses) must accept the page without warnings;
figures are checked for units on the axes and for the plotted data (PDF area 1 within 2 %, the
KDE grid covers the data plus 4 bandwidths).
"""

import io as _io

import numpy as np
import pandas as pd
import pytest

from ttbpipe import io
from ttbpipe.stats import streaming as A
from ttbpipe.stats import tables as T
from ttbpipe.stats import limits as L
from ttbpipe.stats import plots as P
from ttbpipe.stats.reliability import ReliabilitySettings, assess_limits, convergence_curve
from ttbpipe.study.report_pages import first_page_rst, write_first_page
from ttbpipe.stats.schema import example_extremes, example_histories


@pytest.fixture()
def extremes():
    full = example_extremes(range(400), "full", seed=1, spread=0.35)
    single = example_extremes([0], "single", seed=2, spread=0.0)
    return pd.concat([full, single], ignore_index=True)


def _docutils_messages(text):
    from docutils.core import publish_doctree

    stream = _io.StringIO()
    publish_doctree(text, settings_overrides={"warning_stream": stream, "report_level": 2,
                                              "halt_level": 5})
    return stream.getvalue()


def test_first_page_lists_exceeded_limits_and_verdicts(extremes, tmp_path):
    """The page names every exceeded limit with its probability and CI, flags insufficient
    sample sizes, lists limits that could not be evaluated, and parses cleanly in docutils."""
    limits, ctx = L.limits_from_config({"thresholds": {"derailment_coefficient": 0.35}})
    table = assess_limits(extremes.drop(columns=["max_deck_lateral_acc_m_s2"]), limits, ctx,
                          ReliabilitySettings())
    text = first_page_rst(table, study="demo")
    assert _docutils_messages(text) == ""
    row = table[(table.scenario == "full") & (table.limit == "derailment_coefficient")].iloc[0]
    assert row.n_exceed > 0
    assert f"{row.probability:.3g}" in text and f"[{row.ci_low:.3g}, {row.ci_high:.3g}]" in text
    assert "Did the number of samples suffice?" in text and "No, for" in text
    assert "Not evaluated" in text and "max_deck_lateral_acc_m_s2" in text
    path = write_first_page(table, tmp_path / "summary.rst", study="demo")
    assert path.read_text() == text


def test_first_page_when_nothing_exceeds():
    """No exceedance: the page says so and judges sample size by the one-sided bound."""
    ext = example_extremes(range(400), "C1", seed=3, spread=0.05)
    limits = [lim for lim in L.default_limits() if lim.name == "deck_vertical_acc"]
    text = first_page_rst(assess_limits(ext, limits))
    assert "No sample exceeded any evaluated limit" in text
    assert "Yes, for all 1" in text  # 1 - 0.05^(1/400) = 0.0075 <= 0.01
    assert _docutils_messages(text) == ""


def test_figures_have_units_and_data(extremes, tmp_path):
    """Convergence, PDF, history statistics and forecast envelope figures: axes labelled with
    units, data drawn, files written atomically."""
    limit = L.ConstantLimit("qp", "max_derailment_coefficient", 0.35, "1", "test", "Q/P")
    curve = convergence_curve(extremes, limit, scenario="full")
    fig = P.plot_exceedance_convergence([curve, curve])
    ax = fig.axes[0]
    assert "number of samples" in ax.get_xlabel() and "P(" in ax.get_ylabel()
    assert io.save_figure(fig, tmp_path / "conv.png").stat().st_size > 10_000

    fig = P.plot_extreme_pdfs(extremes, "max_deck_vertical_acc_m_s2", threshold=5.0)
    ax = fig.axes[0]
    assert ax.get_xlabel() == "max. deck vertical acceleration (m/s²)"
    assert ax.get_ylabel() == "probability density (1/(m/s²))"
    (x, y), = [line.get_data() for line in ax.get_lines() if "full" in line.get_label()]
    assert np.trapezoid(y, x) == pytest.approx(1.0, abs=0.02)
    assert any("single value" in line.get_label() for line in ax.get_lines())

    paths = []
    for seed, scenario in enumerate(("C1", "C2")):
        df = example_histories(range(30), scenario, n_points=60, seed=seed)
        paths.append(io.write_table(df, tmp_path / f"h_{scenario}.parquet"))
    stats = A.aggregate_histories(paths)
    fig = P.plot_history_statistics(stats, "rail_vertical_acc_m_s2")
    assert fig.axes[1].get_xlabel() == "time (s)"
    assert "(m/s²)" in fig.axes[0].get_ylabel() and "standard deviation" in fig.axes[1].get_ylabel()
    assert len(fig.axes[0].get_lines()) == 2

    dated = pd.concat([example_extremes(range(50), d, seed=i, spread=0.2 + 0.05 * i)
                       for i, d in enumerate(["2024-01-15", "2024-07-15", "2025-01-15"])])
    env = T.forecast_envelope(dated, "max_wheel_lateral_force_N")
    fig = P.plot_forecast_envelope(env)
    assert fig.axes[0].get_ylabel() == "max. wheel-rail lateral force (kN)"  # displayed in kN
    (x, y), = [line.get_data() for line in fig.axes[0].get_lines() if line.get_label() == "weighted mean"]
    np.testing.assert_allclose(y, env["mean"] / 1e3, rtol=1e-12)
    assert io.save_figure(fig, tmp_path / "env.pdf").exists()


def test_stats_report_cli_end_to_end(tmp_path):
    """`ttbpipe stats-report` on two dated scenarios writes the tables, the pages and the figures
    the workflow writes (ttbpipe.study.outputs.STUDY_FILES); the reliability table read back
    equals assess_limits on the same data."""
    from ttbpipe.cli import main
    from ttbpipe.stats.limits import default_limits

    keep = ["sample_index", "scenario", "weight", "seed_entropy", "train_speed_m_s",
            "static_wheel_load_N", "max_derailment_coefficient", "max_deck_vertical_acc_m_s2"]
    ext, hist = [], []
    for i, date in enumerate(["2024-01-15", "2024-07-15"]):
        for b in range(2):
            index = range(50 * b, 50 * b + 50)
            ext.append(io.write_table(example_extremes(index, date, seed=i)[keep],
                                      tmp_path / f"e_{date}_{b}.parquet"))
            hist.append(io.write_table(example_histories(index, date, seed=i, n_points=40),
                                       tmp_path / f"h_{date}_{b}.parquet"))
    out = tmp_path / "out"
    argv = ["stats-report", "--extremes", *map(str, ext), "--histories", *map(str, hist),
            "--out", str(out)]
    assert main(argv) == 0
    table = io.read_table(out / "reliability.parquet")
    expected = assess_limits(A.read_extremes(ext), default_limits())
    pd.testing.assert_series_equal(table["probability"], expected["probability"])
    assert (out / "summary.rst").read_text().startswith("**Limits exceeded")
    assert "Reliability summary: study" in (out / "report" / "summary.html").read_text()
    names = sorted(p.relative_to(out / "figures").as_posix() for p in (out / "figures").rglob("*"))
    assert "pdf/irregularity_max_derailment_coefficient.png" in names
    assert "envelope/max_deck_vertical_acc_m_s2.png" in names
    assert "history/irregularity_rail_vertical_acc_m_s2.png" in names
    assert "convergence/2024-01-15.png" in names
    assert set(io.read_table(out / "table1_std.parquet").columns) == {"index", "2024-01-15",
                                                                     "2024-07-15"}


def test_first_page_when_nothing_can_be_evaluated():
    """Only 'not evaluated' rows: the page says so instead of failing."""
    ext = example_extremes(range(20), "C1").drop(columns=["train_speed_m_s"])
    limits = [lim for lim in L.default_limits() if lim.name == "wheel_unloading_ratio"]
    text = first_page_rst(assess_limits(ext, limits))
    assert "No limit could be evaluated" in text and "train_speed_m_s" in text
    assert _docutils_messages(text) == ""
