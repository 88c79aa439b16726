"""Bounded-memory aggregation of batch files (ttbpipe.stats.streaming) and the tables over its
results (ttbpipe.stats.tables).

Reference: numpy on the same data held in memory (np.average, np.std(ddof=1), weighted
np.percentile(method='inverted_cdf')), and the closed-form weighted variance definitions.
"""

import tracemalloc

import numpy as np
import pandas as pd
import pytest

from ttbpipe import io
from ttbpipe.stats import streaming as A
from ttbpipe.stats import tables as T
from ttbpipe.stats.schema import ResultsSchemaError, example_extremes, example_histories

QUANTITIES = ["rail_vertical_acc_m_s2", "girder_vertical_disp_m"]


def _write_batches(folder, sizes, *, scenario="C1", weights=None, n_points=120, seed=0):
    """Write time-history batches of the given sizes; return paths and the in-memory frame."""
    paths, frames, start = [], [], 0
    for b, size in enumerate(sizes):
        index = np.arange(start, start + size)
        w = None if weights is None else weights[index]
        df = example_histories(index, scenario, n_points=n_points, seed=seed, weights=w)
        paths.append(io.write_table(df, folder / f"{scenario}_batch{b:03d}.parquet", kind="histories"))
        frames.append(df)
        start += size
    return paths, pd.concat(frames, ignore_index=True)


def _matrix(df, quantity, n_points):
    return df[quantity].to_numpy().reshape(-1, n_points)


def test_streaming_mean_std_equal_numpy_equal_weights(tmp_path):
    """Equal weights, 7 batches of unequal size: mean and std (ddof=1) equal numpy within
    1e-12 relative (Chan/West pairwise updates are exact up to rounding)."""
    paths, df = _write_batches(tmp_path, [13, 40, 1, 27, 8, 30, 21])
    res = A.aggregate_histories(paths)
    for q in QUANTITIES:
        x = _matrix(df, q, 120)
        r = res[("C1", q)]
        np.testing.assert_allclose(r.mean, x.mean(axis=0), rtol=1e-12, atol=1e-15 * np.abs(x).max())
        np.testing.assert_allclose(r.std, x.std(axis=0, ddof=1), rtol=1e-10)
        assert r.n_samples == 140 and r.n_effective == pytest.approx(140)


def test_streaming_weighted_moments_and_order_independence(tmp_path):
    """TIPM-like weights: mean = np.average(weights=w); population variance sum w (x-m)^2 / W;
    reliability variance sum w (x-m)^2 / (W - sum w^2/W) (tolerance 1e-10 relative). Reading the
    batches in another order changes nothing beyond rounding (1e-12)."""
    w = np.random.default_rng(4).dirichlet(np.ones(90))
    paths, df = _write_batches(tmp_path, [30, 25, 35], weights=w)
    x = _matrix(df, QUANTITIES[0], 120)
    mean = np.average(x, axis=0, weights=w)
    m2 = (w[:, None] * (x - mean) ** 2).sum(axis=0)
    W, W2 = w.sum(), (w * w).sum()
    for kind, denom in (("population", W), ("reliability", W - W2 / W)):
        r = A.aggregate_histories(paths, std_kind=kind)[("C1", QUANTITIES[0])]
        np.testing.assert_allclose(r.mean, mean, rtol=1e-10, atol=1e-13)
        np.testing.assert_allclose(r.std, np.sqrt(m2 / denom), rtol=1e-10)
    m_a, m_b = A.WeightedMoments(120), A.WeightedMoments(120)
    for part in np.array_split(np.arange(90), 3):
        m_a.update(x[part], w[part])
    for part in reversed(np.array_split(np.arange(90), 3)):
        m_b.update(x[part], w[part])
    np.testing.assert_allclose(m_a.mean, m_b.mean, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(m_a.m2, m_b.m2, rtol=1e-12)
    assert m_a.n_effective == pytest.approx(W * W / W2, rel=1e-12)


@pytest.mark.parametrize("weighted", [False, True])
def test_streaming_percentiles_within_bin_width(tmp_path, weighted):
    """Histogram percentiles differ from numpy's exact weighted inverted-CDF percentiles by at
    most one bin width per point (the bound documented in aggregate.py), with 64 bins."""
    n = 150
    w = np.random.default_rng(9).uniform(0.2, 3.0, n) if weighted else None
    paths, df = _write_batches(tmp_path, [50, 50, 50], weights=w, n_points=80)
    qs = (0.05, 0.25, 0.5, 0.9, 0.99)
    res = A.aggregate_histories(paths, quantiles=qs, n_bins=64)
    for q in QUANTITIES:
        x = _matrix(df, q, 80)
        weights = np.ones(n) if w is None else w
        exact = np.stack([np.percentile(x[:, j], 100 * np.array(qs), weights=weights,
                                        method="inverted_cdf") for j in range(80)], axis=1)
        r = res[("C1", q)]
        assert (r.bin_width > 0).all()
        for i, p in enumerate(qs):
            err = np.abs(r.quantiles[p] - exact[i])
            assert (err <= r.bin_width * (1 + 1e-9)).all(), (q, p, err.max(), r.bin_width.min())
        # The bound is attainable but the error is usually well inside it.
        assert np.median(np.abs(r.quantiles[0.5] - exact[2]) / r.bin_width) < 0.5


def test_memory_does_not_grow_with_number_of_batches(tmp_path):
    """Instrumentation, not timing: at most one batch is held at a time (max rows in memory =
    rows of the largest batch), the accumulator state has the same size for 4 and 32 batches,
    and the tracemalloc peak (numpy/pandas allocations) for 32 batches stays within 1.5x that
    for 4 batches (measured 1.1x; holding all batches would add 32 x 0.2 MB = 6.4 MB, ~10x)."""
    few, _ = _write_batches(tmp_path / "few", [20] * 4, n_points=250)
    many, _ = _write_batches(tmp_path / "many", [20] * 32, n_points=250)
    A.aggregate_histories(few, n_bins=64)  # warm-up: one-time allocations (imports, caches)
    peaks, traces = [], []
    for paths in (few, many):
        trace = A.AggregationTrace()
        tracemalloc.start()
        A.aggregate_histories(paths, n_bins=64, trace=trace)
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
        traces.append(trace)
    assert traces[0].max_rows_in_memory == traces[1].max_rows_in_memory == 20 * 250
    assert traces[0].state_nbytes == traces[1].state_nbytes
    assert traces[1].files_read == 2 * 32  # two passes, one file at a time
    assert traces[1].samples == {"C1": 640}
    assert peaks[1] < 1.5 * peaks[0], peaks


def test_duplicate_sample_and_grid_mismatch_name_the_file(tmp_path):
    """A sample in two files, or a scenario whose grid changes, is an error naming the file."""
    io.write_table(example_histories([0, 1], "C1"), tmp_path / "a.parquet")
    io.write_table(example_histories([1, 2], "C1"), tmp_path / "b.parquet")
    with pytest.raises(ResultsSchemaError, match=r"b\.parquet.*sample_index"):
        A.aggregate_histories([tmp_path / "a.parquet", tmp_path / "b.parquet"])
    io.write_table(example_histories([5], "C1", n_points=150), tmp_path / "c.parquet")
    with pytest.raises(ResultsSchemaError, match=r"c\.parquet.*time_s.*different grid"):
        A.aggregate_histories([tmp_path / "a.parquet", tmp_path / "c.parquet"])


def test_read_extremes_concatenates_and_rejects_duplicates(tmp_path):
    """All batches concatenated, sorted by (scenario, sample_index); a repeated sample names both
    files."""
    for b in range(3):
        io.write_table(example_extremes(range(10 * b, 10 * b + 10), "C1"), tmp_path / f"e{b}.parquet")
    table = A.read_extremes(sorted(tmp_path.glob("e*.parquet"), reverse=True))
    assert list(table["sample_index"]) == list(range(30))
    io.write_table(example_extremes([3], "C1"), tmp_path / "e9.parquet")
    with pytest.raises(ResultsSchemaError, match=r"e9\.parquet.*also in .*e0\.parquet"):
        A.read_extremes(tmp_path.glob("e*.parquet"))


def test_table1_and_forecast_envelope_match_numpy():
    """Table 1: std per scenario equals np.std(ddof=1) for equal weights (1e-12); forecast
    envelope: mean and quantiles equal np.average / weighted np.percentile (exact)."""
    a = example_extremes(range(100), "C1", seed=1)
    b = example_extremes(range(100), "C2", seed=2, spread=0.5)
    table = T.standard_deviation_table(pd.concat([a, b]), columns=["max_wheel_vertical_force_N",
                                                                   "sperling_lateral"])
    assert list(table.columns) == ["C1", "C2"]
    assert table.loc["sperling_lateral", "C2"] == pytest.approx(b["sperling_lateral"].std(ddof=1), rel=1e-12)
    w = np.random.default_rng(0).uniform(0.1, 1, 100)
    dated = pd.concat([example_extremes(range(100), "2024-01-15", weights=w),
                       example_extremes(range(100), "2023-06-15", seed=5, weights=w)])
    env = T.forecast_envelope(dated, "max_deck_vertical_acc_m_s2", lower=0.1, upper=0.9)
    assert list(env["scenario"]) == ["2023-06-15", "2024-01-15"]
    x = dated[dated.scenario == "2024-01-15"]["max_deck_vertical_acc_m_s2"].to_numpy()
    assert env["mean"].iloc[1] == pytest.approx(np.average(x, weights=w), rel=1e-12)
    assert env["upper"].iloc[1] == np.percentile(x, 90, weights=w, method="inverted_cdf")


def test_max_std_table_from_histories(tmp_path):
    """Table 1 as the paper reads it (maximum of the std curve) equals max over points of numpy's
    std (1e-10 relative)."""
    paths, df = _write_batches(tmp_path, [20, 20])
    table = T.max_std_table(A.aggregate_histories(paths))
    x = _matrix(df, QUANTITIES[1], 120)
    assert table.loc[QUANTITIES[1], "C1"] == pytest.approx(x.std(axis=0, ddof=1).max(), rel=1e-10)


def test_state_budget_and_moments_only(tmp_path):
    """A histogram state above max_state_mb stops before allocation with the remedies named;
    quantiles=() computes mean/std in one pass (equal to the two-pass result, exact)."""
    paths, _ = _write_batches(tmp_path, [10, 10], n_points=500)
    with pytest.raises(MemoryError, match="lower n_bins"):
        A.aggregate_histories(paths, n_bins=256, max_state_mb=1.0)  # needs 2 x 500 x 256 x 8 = 2 MB
    trace = A.AggregationTrace()
    only = A.aggregate_histories(paths, quantiles=(), trace=trace)
    full = A.aggregate_histories(paths)
    assert trace.files_read == 2
    key = ("C1", QUANTITIES[0])
    np.testing.assert_array_equal(only[key].std, full[key].std)


def test_results_bit_identical_across_batch_sizes(tmp_path):
    """Results must not depend on the batch size. Splitting the same 23 weighted samples
    into batches of 3 and of 7 (files named so that their lexicographic order is not the sample
    order) gives bit-identical means, standard deviations and percentiles (tolerance: none)."""
    rng = np.random.default_rng(5)
    weights = rng.uniform(0.2, 2.0, 23)

    def write(batch_size, folder):
        folder.mkdir()
        paths = []
        for start in range(0, 23, batch_size):
            index = np.arange(start, min(start + batch_size, 23))
            df = example_histories(index, "2025-12-15", n_points=64, seed=3, weights=weights[index])
            paths.append(io.write_table(df, folder / f"histories_{start}-{index[-1]}.parquet"))
        return paths

    small = A.aggregate_histories(write(3, tmp_path / "b3"))
    large = A.aggregate_histories(write(7, tmp_path / "b7"))
    assert small.keys() == large.keys()
    for key in small:
        a, b = small[key], large[key]
        assert np.array_equal(a.mean, b.mean) and np.array_equal(a.std, b.std)
        for p in a.quantiles:
            assert np.array_equal(a.quantiles[p], b.quantiles[p])
