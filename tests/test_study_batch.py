"""Batch runner of the study stage (ttbpipe.study.samples / batch; docs/studies.md).

Real coupled runs on a tiny study (one 32 m span, one car, 15 m of run) so that the file stays
at a few tens of seconds. What is checked and against what:

* results do not depend on the batch size or on the executor (local loop vs a Dask LocalCluster):
  exact equality of every extremes and time-history value (the project's determinism rule,
  docs/dev/contributing.md; the runs are deterministic floating-point programs);
* an exception in the middle of a batch leaves no file, and a rerun redoes only the missing batch;
* the extremes are the documented reductions of the run (docs/results_schema.md mapping);
* the deck-acceleration low-pass (EN 1990 A2 A2.4.4.2.1, 30 Hz) against the Butterworth
  magnitude response |H(f)|^2 = 1/(1 + (f/fc)^8) of the forward-backward 4th-order filter;
* the fields scenarios' factors equal the fields stage's table (same seeds).
"""

import copy
import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from ttbpipe.fields import load_field_factors, sample_study
from ttbpipe.io import read_provenance
from ttbpipe.stats.streaming import read_extremes
from ttbpipe.study import samples as study_samples
from ttbpipe.study.batch import batch_paths, simulate_design
from ttbpipe.study.design import build_design

FIELDS = {
    "method": "kle", "kernel": "exponential", "correlation_length_m": 10.0,
    "variance_fraction": 0.9, "geometry": {"source": "structure"},
    "groups": {g: {"enabled": True, "distribution": "normal", "cov": 0.1,
                   "correlation": [[1.0, 0.7, 0.7, 0.7], [0.7, 1.0, 0.8, 0.8],
                                   [0.7, 0.8, 1.0, 0.9], [0.7, 0.8, 0.9, 1.0]]}
               for g in ("C1", "C2", "C3", "C4")},
}
CONFIG = {
    "study": {"name": "tiny", "seed": 5,
              "scenarios": {"irregularity": {"enabled": False}, "forecast": {"enabled": False},
                            "fields": {"conditions": ["C2"], "samples": 3}}},
    "structure": {"layout": {"approach_length_m": 30.0, "spans_m": [32.0],
                             "approach_track": "ballasted", "bridge_track": "slab"}},
    "simulation": {"train": {"composition": ["trailer"]}, "end_x_m": 40.0, "batch_size": 2},
    "fields": FIELDS,
    # a 0.18 s run is too short for the standards' filters (the assessment says so and stops):
    # these tests are about batching, the assessment in a study is tested in test_workflow.py
    "assessment": {"standard": []},
}


def tiny_design(config=CONFIG):
    return build_design(config["study"], latest_campaign="2025-12-15", horizons_months=[])


def read_all(root, design, batch_size):
    from ttbpipe.study.design import batches

    ext, hist = [], []
    for b in batches(design, batch_size):
        e, h = batch_paths(str(root), *b)
        ext.append(e)
        hist.append(pd.read_parquet(h))
    extremes = read_extremes(ext).sort_values(["scenario", "sample_index"]).reset_index(drop=True)
    histories = pd.concat(hist).sort_values(["scenario", "sample_index", "position_m"],
                                            kind="stable").reset_index(drop=True)
    return extremes, histories


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The tiny design simulated with batches of 2, locally."""
    root = tmp_path_factory.mktemp("batches_2")
    design = tiny_design()
    ran = simulate_design(design, CONFIG, {}, str(root), batch_size=2, executor="local")
    assert ran == [("C2", 0, 1), ("C2", 2, 2)]
    return design, root, *read_all(root, design, 2)


def test_extremes_follow_the_documented_mapping(reference):
    design, root, extremes, histories = reference
    assert len(extremes) == 3 and set(extremes["scenario"]) == {"C2"}
    for direction in ("vertical", "lateral"):
        per_car = [c for c in extremes.columns if c.startswith(f"sperling_{direction}_car")]
        assert per_car == [f"sperling_{direction}_car1"]
        np.testing.assert_array_equal(extremes[f"sperling_{direction}"], extremes[per_car[0]])
    # the deck maxima are the largest span maxima; the grid is shared by every sample
    np.testing.assert_array_equal(extremes["max_deck_vertical_acc_m_s2"],
                                  extremes["max_span1_vertical_acc_m_s2"])
    grids = [g["position_m"].to_numpy() for _, g in histories.groupby(["scenario", "sample_index"])]
    assert all(np.array_equal(grids[0], g) for g in grids)
    assert (extremes["train_speed_m_s"] == 300 / 3.6).all()
    # the C2 samples differ from one another (random pads), the design seeds are recorded
    assert extremes.loc[extremes["scenario"] == "C2", "max_wheel_vertical_force_N"].nunique() == 3
    assert list(extremes["seed_entropy"]) == list(design.sort_values(["scenario", "sample_index"])["seed_entropy"])
    meta = read_provenance(batch_paths(str(root), "C2", 0, 1)[0])
    assert meta["samples"] == [0, 1]


def test_results_do_not_depend_on_the_batch_size(reference, tmp_path):
    design, _, extremes, histories = reference
    simulate_design(design, CONFIG, {}, str(tmp_path), batch_size=3, executor="local")
    e3, h3 = read_all(tmp_path, design, 3)
    pd.testing.assert_frame_equal(extremes, e3, check_exact=True)
    pd.testing.assert_frame_equal(histories, h3, check_exact=True)


def test_dask_local_cluster_gives_identical_results(reference, tmp_path):
    design, _, extremes, histories = reference
    config = copy.deepcopy(CONFIG)
    config["simulation"]["dask"] = {"local_workers": 2}
    os.environ.pop("TTBPIPE_DASK_SCHEDULER", None)
    simulate_design(design, config, {}, str(tmp_path), batch_size=4, executor="dask")
    e4, h4 = read_all(tmp_path, design, 4)
    pd.testing.assert_frame_equal(extremes, e4, check_exact=True)
    pd.testing.assert_frame_equal(histories, h4, check_exact=True)


_THREADS_SCRIPT = """
import sys
sys.path.insert(0, {tests!r})
from test_study_batch import CONFIG, tiny_design
from ttbpipe.study.batch import simulate_design
design = tiny_design()
simulate_design(design[design["sample_index"] <= 1], CONFIG, {{}}, {root!r}, batch_size=2,
                executor="local")
"""


def test_results_do_not_depend_on_the_blas_thread_count(reference, tmp_path):
    """The same batch in two fresh processes, one started with every BLAS/OpenMP/numba pool at
    one thread, the other at two (OPENBLAS_NUM_THREADS etc.): bit-identical tables, and equal
    to the reference run of this module. Without ttbpipe.threads.single_threaded the static
    solve's multi-threaded BLAS changed the static wheel load in its last digits (1e-5)."""
    import subprocess
    import sys

    design, root, extremes, histories = reference
    tables = []
    for threads in ("1", "2"):
        out = tmp_path / f"threads_{threads}"
        env = {**os.environ, **{k: threads for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                                                        "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")}}
        subprocess.run([sys.executable, "-c", _THREADS_SCRIPT.format(
            tests=str(Path(__file__).parent), root=str(out))], env=env, check=True)
        e, h = batch_paths(str(out), "C2", 0, 1)
        tables.append((pd.read_parquet(e), pd.read_parquet(h)))
    for one, two in zip(*tables):
        pd.testing.assert_frame_equal(one, two, check_exact=True)
    e_ref, h_ref = batch_paths(str(root), "C2", 0, 1)
    pd.testing.assert_frame_equal(tables[0][0], pd.read_parquet(e_ref), check_exact=True)
    pd.testing.assert_frame_equal(tables[0][1], pd.read_parquet(h_ref), check_exact=True)


def test_interrupted_batch_writes_nothing_and_rerun_does_only_the_missing(reference, tmp_path):
    design, _, extremes, _ = reference
    c2 = design

    def failing(row, **kwargs):
        if int(row["sample_index"]) == 2:
            raise KeyboardInterrupt("simulated kill in the middle of a batch")
        return study_samples.run_sample(row, **kwargs)

    with pytest.raises(KeyboardInterrupt):
        simulate_design(c2, CONFIG, {}, str(tmp_path), batch_size=2, executor="local",
                        runner=failing)
    done = batch_paths(str(tmp_path), "C2", 0, 1)
    assert all(os.path.isfile(p) for p in done)
    files = sorted(p.name for p in (tmp_path / "C2").iterdir())
    assert files == ["extremes_00000-00001.parquet", "histories_00000-00001.parquet"], files
    stamp = [os.stat(p).st_mtime_ns for p in done]
    ran = simulate_design(c2, CONFIG, {}, str(tmp_path), batch_size=2, executor="local")
    assert ran == [("C2", 2, 2)]
    assert [os.stat(p).st_mtime_ns for p in done] == stamp
    e, _ = read_all(tmp_path, c2, 2)
    pd.testing.assert_frame_equal(e, extremes[extremes["scenario"] == "C2"].reset_index(drop=True),
                                  check_exact=True)


def test_deck_lowpass_keeps_10_hz_and_removes_100_hz():
    dt = 2e-3
    t = np.arange(0, 4.0, dt)
    signal = np.sin(2 * np.pi * 10 * t) + np.sin(2 * np.pi * 100 * t + 0.3)
    from ttbpipe.simulation.outputs import lowpass_peak

    peak = lowpass_peak(signal, dt, 30.0)
    # |H(10 Hz)|^2 = 0.99985, |H(100 Hz)|^2 = 6.5e-5 (filtfilt squares the magnitude); 1 %
    assert peak == pytest.approx(1.0, abs=0.01)
    assert np.max(np.abs(signal)) > 1.5


def test_deck_lowpass_of_many_columns_is_each_columns_own():
    """The deck peaks are filtered in one call over all columns: the same numbers, bit for bit,
    as each column filtered by itself (scipy's sosfiltfilt on a 1-D record), below and above
    the filter's 0.95 Nyquist cut-off."""
    from scipy import signal

    from ttbpipe.filters import butterworth_sos
    from ttbpipe.simulation.outputs import lowpass_peaks

    columns = np.cumsum(np.random.default_rng(3).standard_normal((1700, 7)), axis=0)
    for dt, cutoff in ((2e-3, 30.0), (2e-3, 240.0)):
        sos = butterworth_sos(4, cutoff, "lowpass", 1.0 / dt)
        each = [float(np.max(np.abs(signal.sosfiltfilt(sos, columns[:, j]))))
                if cutoff < 0.95 * 0.5 / dt else float(np.max(np.abs(columns[:, j])))
                for j in range(columns.shape[1])]
        assert lowpass_peaks(columns, dt, cutoff).tolist() == each


def test_fields_condition_factors_equal_the_fields_stage(tmp_path):
    structure = CONFIG["structure"]
    table = tmp_path / "samples.parquet"
    sample_study({"study": {"seed": 5}, "fields": FIELDS, "structure": structure}, table, n_samples=3)
    for i in range(3):
        stage = load_field_factors(table, i)
        alone = study_samples.field_factors(FIELDS, structure, 5, "C2", i)
        assert sorted(alone) == ["pad_cy", "pad_cz", "pad_ky", "pad_kz"]
        for name, values in alone.items():
            np.testing.assert_array_equal(values, stage[name])


def test_aggregation_tables_report_pages_and_missing_samples(reference, tmp_path):
    """Study outputs from the batch files; a forced exceedance (threshold below every sample:
    P = 1 exactly, binomial k = N) appears on the first page; a missing batch is an error."""
    from ttbpipe.study.outputs import aggregate_study
    from ttbpipe.study.design import batches

    design, root, extremes, _ = reference
    paths = [batch_paths(str(root), *b) for b in batches(design, 2)]
    config = {**CONFIG, "limits": {"thresholds": {"derailment_coefficient": 1e-4}}}
    out = aggregate_study([p[0] for p in paths], [p[1] for p in paths], design, config,
                          out=tmp_path / "study")
    table = pd.read_parquet(out["reliability"])
    dc = table[table["limit"] == "derailment_coefficient"].iloc[0]
    assert (dc["n_exceed"], dc["n_samples"], dc["probability"]) == (3, 3, 1.0)
    main = (tmp_path / "study" / "summary.rst").read_text()
    assert "derailment coefficient Q/P > 0.0001" in main and "P = 1 " in main
    assert "Did the samples suffice? No" in main
    pd.testing.assert_frame_equal(pd.read_parquet(out["extremes"]), extremes, check_dtype=False)
    table1 = pd.read_parquet(out["table1"])
    assert list(table1.columns) == ["index", "C2"]
    expected = extremes["max_wheel_vertical_force_N"].std(ddof=1)   # equal weights: numpy ddof=1
    got = table1.set_index("index").loc["max_wheel_vertical_force_N", "C2"]
    assert got == pytest.approx(expected, rel=1e-12)
    stats = pd.read_parquet(out["history"])
    assert set(stats["quantity"]) >= {"girder_vertical_acc_m_s2", "wheel_lateral_force_N"}
    for kind in ("convergence", "pdf", "history"):
        assert list((tmp_path / "study" / "figures" / kind).glob("*.png")), kind
    assert "<table" in (tmp_path / "study" / "report" / "summary.html").read_text()
    with pytest.raises(ValueError, match="C2/2"):
        aggregate_study([paths[0][0]], [paths[0][1]], design, config, out=tmp_path / "bad")


def test_aggregation_refuses_stale_and_unreadable_batches(reference, tmp_path):
    """ttbpipe.study.batch.verify_batches, which the workflow's aggregate step runs first: a
    batch made with other settings (here simulation.deck_filter_hz) is named with the setting
    that differs; a truncated file is named as unreadable instead of a raw pyarrow traceback;
    both errors end with the command that remakes the files."""
    import shutil

    from ttbpipe.study.batch import StaleBatchError, simulate_batch, verify_batches
    from ttbpipe.study.design import batch_rows
    from ttbpipe.study.plan import batch_settings, settings_digest

    design, _, _, _ = reference
    settings = batch_settings(CONFIG, "fields", "test-code")
    paths = batch_paths(str(tmp_path), "C2", 0, 1)
    simulate_batch(batch_rows(design, "C2", 0, 1), CONFIG, {}, *paths, scenario="C2", first=0,
                   last=1, settings=settings, settings_digest=settings_digest(settings))
    documents = verify_batches(paths, design[design["sample_index"] <= 1], {"C2": settings})
    assert set(documents) == set(map(str, paths))       # each provenance, read once, returned
    assert all(d == read_provenance(p) for p, d in documents.items())

    changed = copy.deepcopy(settings)
    changed["simulation"]["deck_filter_hz"] = 25.0
    with pytest.raises(StaleBatchError) as info:
        verify_batches(paths, design[design["sample_index"] <= 1], {"C2": changed})
    message = str(info.value)
    assert paths[0] in message and paths[1] in message
    assert "simulation.deck_filter_hz: 30.0 -> 25.0" in message
    assert "Remake them: snakemake --cores 2 --forcerun " in message

    truncated = tmp_path / "truncated.parquet"
    shutil.copy(paths[0], truncated)
    with open(truncated, "r+b") as f:
        f.truncate(truncated.stat().st_size // 2)
    with pytest.raises(StaleBatchError, match=rf"{truncated}: unreadable \(ArrowInvalid"):
        verify_batches([truncated], design, {"C2": settings})

    with pytest.raises(StaleBatchError, match=r"holds samples \[0, 1\] but the design of C2 has \[0\]"):
        verify_batches([paths[0]], design[design["sample_index"] == 0], {"C2": settings})


def test_a_batch_carries_the_assessment_of_each_sample_as_ttbpipe_assess_gives_it(tmp_path):
    """A study sample assessed in memory (assessment.standard: gb5599 and en1990, with the twist
    monitors) gives the same processed values and utilisations as the profiles applied to the
    same run by ttbpipe.assessment.assess (second path: the run repeated with run_coupled and
    assessed from its table; exact equality, the runs are deterministic), and the batch's
    provenance carries each row's clause and category for the report. The same batch given the
    study's EN 1990 span-frequency record (rule study_span_frequencies) instead of analysing the
    structure itself writes the same extremes (DataFrame.equals)."""
    from ttbpipe.assessment import assess
    from ttbpipe.assessment.api import assess_records
    from ttbpipe.assessment.run import RunData
    from ttbpipe.assessment.columns import (extreme_columns, row_metadata, utilisation_column,
                                            value_column)
    from ttbpipe.assessment.study import resolve_assessment, run_case
    from ttbpipe.simulation.coupled import run_coupled

    config = copy.deepcopy(CONFIG)
    config["study"]["scenarios"]["fields"]["samples"] = 1
    config["simulation"]["end_x_m"] = 90.0           # 0.8 s of run: the 2 m windows fit
    config["assessment"] = {"standard": ["gb5599", "en1990"]}
    design = build_design(config["study"], latest_campaign="2024-01-15", horizons_months=[])
    simulate_design(design, config, {}, str(tmp_path), batch_size=1)
    path = batch_paths(str(tmp_path), "C2", 0, 0)[0]
    extremes = pd.read_parquet(path)
    meta = read_provenance(path)["assessment"]
    assert {(m["profile"], m["index"]) for m in meta} >= {
        ("gb5599", "wheel_unloading_ratio"), ("en1990", "deck_twist_m")}
    assert not any(c.startswith(("en14363_", "en12299_")) for c in extremes.columns)

    import json

    from ttbpipe.assessment.modal import span_frequency_record
    from ttbpipe.study.batch import simulate_batch
    from ttbpipe.study.design import batch_rows

    record = tmp_path / "span_frequencies.json"
    record.write_text(json.dumps(span_frequency_record(config["structure"])))
    second = batch_paths(str(tmp_path / "with_record"), "C2", 0, 0)
    simulate_batch(batch_rows(design, "C2", 0, 0), config, {}, *second, span_frequencies=record)
    assert pd.read_parquet(second[0]).equals(extremes)

    # the same sample outside the study: its case, the field factors, run_coupled, assess
    sim = study_samples.resolve_simulation(config["simulation"])
    assessment = resolve_assessment(config["assessment"])
    irr = sim["irregularity"]
    case = run_case(study_samples.build_case(
        sim, config["structure"], irregularity={
            "source": "synthetic", "spectrum": irr["spectrum"], "dx_m": irr["dx_m"],
            "fade_in_m": irr["fade_in_m"],
            "seed": study_samples.mean_spectrum_seed(config["study"]["seed"])}), assessment)
    factors = study_samples.field_factors(FIELDS, config["structure"], config["study"]["seed"],
                                          "C2", 0)
    table, summary = run_coupled(case, factors=factors)
    for name in ("gb5599", "en1990"):
        rows = assess(table, summary, name, config=case)
        # the batch reads the records (assess_records), not the table: the same columns
        records = assess_records(RunData(table, summary, case), name)
        assert extreme_columns(records) == extreme_columns(rows)
        assert row_metadata(records) == row_metadata(rows)
        for row in rows.itertuples():
            assert extremes[value_column(name, row.index)].iloc[0] == row.processed_value
            if np.isfinite(row.limit):
                assert (extremes[utilisation_column(name, row.index)].iloc[0]
                        == row.utilisation)
    # the processed unloading ratio is below the raw maximum over every step (filtering)
    assert (extremes["gb5599_wheel_unloading_ratio"].iloc[0]
            < extremes["max_wheel_unloading_ratio"].iloc[0])
