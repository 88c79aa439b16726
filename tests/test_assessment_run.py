"""RunData (ttbpipe.assessment.run): a run's histories read once and shared by the profiles.

EN 14363 and GB/T 5599 low-pass the same wheel forces with the same 20 Hz filter; a study
assesses each sample against both on one RunData, which filters each force once. Reference: each
profile on a RunData of its own (nothing shared), exact equality of every row, in either order;
and the columns as pandas gives them one by one."""

import numpy as np
import pytest

from assessment_synthetic import synthetic_run
from ttbpipe.assessment.api import assess_records
from ttbpipe.assessment.en14363 import DEFAULTS, force_filter
from ttbpipe.assessment.run import RunData

PROFILES = ("en14363", "gb5599", "en12299")


@pytest.fixture(scope="module")
def run_inputs():
    rng = np.random.default_rng(7)
    n = 3000
    columns = {}
    for ws in ("car1_ws1", "car1_ws2"):
        for side in ("left", "right"):
            columns[f"{ws}_{side}_P_N"] = 70e3 + 8e3 * rng.standard_normal(n)
            columns[f"{ws}_{side}_Q_N"] = 5e3 * rng.standard_normal(n)
    for point in ("front", "centre", "rear"):
        columns[f"car1_body_{point}_az_m_s2"] = 0.3 * rng.standard_normal(n)
        columns[f"car1_body_{point}_ay_m_s2"] = 0.2 * rng.standard_normal(n)
    return synthetic_run(columns, duration_s=3.0)


@pytest.mark.parametrize("order", [PROFILES, PROFILES[::-1]], ids=["forward", "reversed"])
def test_profiles_on_one_run_give_their_rows_on_runs_of_their_own(run_inputs, order):
    table, summary = run_inputs
    shared = RunData(table, summary)
    together = {name: assess_records(shared, name) for name in order}
    for name in PROFILES:
        alone = assess_records(RunData(table, summary), name)
        assert len(alone) == len(together[name])
        for a, b in zip(alone, together[name]):
            assert a.keys() == b.keys()
            for key in a:
                same = a[key] == b[key] or (isinstance(a[key], float) and np.isnan(a[key])
                                            and np.isnan(b[key]))
                assert same, (name, a["index"], key, a[key], b[key])
    assert len(shared._filtered) == 3          # P, Q and H through the one 20 Hz low-pass


def test_a_filtered_force_is_computed_once_and_cannot_be_written(run_inputs):
    run = RunData(*run_inputs)
    filt = force_filter(DEFAULTS)
    first = run.filtered(filt, "P_N")
    np.testing.assert_array_equal(first, filt.apply(run.P_N, run.dt_s))
    assert run.filtered(filt, "P_N") is first
    with pytest.raises(ValueError):
        first[0, 0] = 0.0


def test_columns_are_read_as_pandas_gives_them_one_by_one(run_inputs):
    table, summary = run_inputs
    run = RunData(table, summary)
    names = ["car1_ws2_right_Q_N", "time_s", "car1_ws1_left_in_contact", "car1_body_rear_az_m_s2"]
    got = run.read_columns(names)
    assert got.flags.f_contiguous and got.dtype == float
    for j, name in enumerate(names):
        np.testing.assert_array_equal(got[:, j], table[name].to_numpy(float))
    with pytest.raises(KeyError, match="car1_ws9_left_P_N"):
        run.read_columns(["car1_ws1_left_P_N", "car1_ws9_left_P_N"])


def test_another_cut_off_filters_anew(run_inputs):
    """GB/T 5599 at 15 Hz after EN 14363 at 20 Hz on one run: its own filtered forces."""
    table, summary = run_inputs
    shared = RunData(table, summary)
    assess_records(shared, "en14363")
    together = assess_records(shared, "gb5599", options={"cutoff_hz": 15.0})
    alone = assess_records(RunData(table, summary), "gb5599", options={"cutoff_hz": 15.0})
    assert [r["processed_value"] for r in together] == [r["processed_value"] for r in alone]
    default = assess_records(RunData(table, summary), "gb5599")
    assert together[1]["processed_value"] != default[1]["processed_value"]
    assert len(shared._filtered) == 6
