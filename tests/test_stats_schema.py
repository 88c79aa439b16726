"""Results-table schemas and validators (ttbpipe.stats.schema, docs/results_schema.md).

Source of truth: the column lists in schema.py, which docs/results_schema.md documents; every
error must name the file, the column and, where one is at fault, the row.
"""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from ttbpipe import io
from ttbpipe.stats import schema as S


def test_documented_columns_and_units():
    """The brief's column list, dtypes and units; the doc lists every column."""
    assert [c.name for c in S.EXTREMES_KEY_COLUMNS] == ["sample_index", "scenario", "weight",
                                                       "seed_entropy"]
    assert S.EXTREMES_SPEC["max_lateral_wheelset_force_N"].unit == "N"
    assert S.EXTREMES_SPEC["max_deck_vertical_acc_m_s2"].unit == "m/s^2"
    assert S.EXTREMES_SPEC["sample_index"].dtype == "int64"
    assert S.unit_of("girder_midspan_lateral_acc_m_s2") == "m/s^2"
    assert S.unit_of("wheel1_lateral_force_N") == "N"
    assert S.unit_of("derailment_coefficient_car2") == "1"
    with pytest.raises(ValueError, match="carries no unit"):
        S.unit_of("lateral_force")
    doc = (Path(__file__).parents[1] / "docs" / "results_schema.md").read_text()
    for spec in S.EXTREMES_COLUMNS:
        assert f"`{spec.name}`" in doc, spec.name
    table = S.describe_extremes()
    assert len(table) == len(S.EXTREMES_COLUMNS) and table["description"].str.len().min() > 5


def test_example_tables_validate_and_round_trip(tmp_path):
    """Example tables follow the schema, also after a Parquet round trip via ttbpipe.io."""
    ext = S.example_extremes(range(20), "C3", weights=np.full(20, 0.05))
    hist = S.example_histories(range(3), "C3", n_points=50, abscissa="position_m")
    path_e = io.write_table(ext, tmp_path / "extremes.parquet", kind="extremes")
    path_h = io.write_table(hist, tmp_path / "histories.parquet", kind="histories")
    assert len(S.read_validated(path_e, "extremes")) == 20
    assert len(S.read_validated(path_h, "histories")) == 150


@pytest.mark.parametrize("mutate, column, row", [
    (lambda d: d.drop(columns=["weight"]), "weight", None),
    (lambda d: d.assign(sample_index=d["sample_index"].astype(float)), "sample_index", None),
    (lambda d: d.assign(weight=np.r_[1.0, 1.0, 0.0, np.ones(7)]), "weight", 2),
    (lambda d: d.assign(max_derailment_coefficient=np.r_[np.ones(5) * 0.2, np.nan, np.ones(4)]),
     "max_derailment_coefficient", 5),
    (lambda d: d.assign(max_wheel_unloading_ratio=np.r_[np.ones(3) * 0.2, 1.5, np.ones(6)]),
     "max_wheel_unloading_ratio", 3),
    (lambda d: d.assign(max_deck_vertical_acc_m_s2=np.r_[np.ones(8), -1.0, 1.0]),
     "max_deck_vertical_acc_m_s2", 8),
    (lambda d: d.assign(sample_index=np.r_[np.arange(9), 4]), "sample_index", 9),
    (lambda d: d.assign(lateral_force=np.ones(10)), "lateral_force", None),
])
def test_extremes_validator_names_file_column_row(tmp_path, mutate, column, row):
    """Each defect raises ResultsSchemaError naming the file path, the column and the row."""
    bad = mutate(S.example_extremes(range(10), "C1"))
    path = tmp_path / "batch_0007.parquet"
    bad.to_parquet(path)
    with pytest.raises(S.ResultsSchemaError) as err:
        S.read_validated(path, "extremes")
    message = str(err.value)
    assert str(path) in message and column in message
    if row is not None:
        assert f"row {row}" in message


@pytest.mark.parametrize("mutate, column", [
    (lambda d: d.assign(weight=np.where(np.arange(len(d)) == 7, 2.0, d["weight"])), "weight"),
    (lambda d: d.assign(time_s=np.where(np.arange(len(d)) == 60, 9.0, d["time_s"])), "time_s"),
    (lambda d: d.rename(columns={"girder_vertical_disp_m": "girder_disp"}), "girder_disp"),
    (lambda d: d.assign(position_m=d["time_s"]), "position_m"),
    (lambda d: d.assign(rail_vertical_acc_m_s2=np.where(np.arange(len(d)) == 3, np.inf,
                                                        d["rail_vertical_acc_m_s2"])),
     "rail_vertical_acc_m_s2"),
])
def test_histories_validator_names_file_and_column(tmp_path, mutate, column):
    """Time-history defects (weight changing within a sample, grid differing between samples,
    unit-less column, two abscissae, non-finite value) name the file and the column."""
    bad = mutate(S.example_histories(range(3), "C1", n_points=40))
    path = tmp_path / "hist_0003.parquet"
    bad.to_parquet(path)
    with pytest.raises(S.ResultsSchemaError) as err:
        S.read_validated(path, "histories")
    assert str(path) in str(err.value) and column in str(err.value)


def test_example_extremes_depend_only_on_seed_and_index():
    """Determinism rule of the brief: sample i's values depend on (seed, i) only, not batching."""
    whole = S.example_extremes(range(10), "C1", seed=4)
    part = S.example_extremes([6, 7], "C1", seed=4)
    pd.testing.assert_frame_equal(whole.iloc[6:8].reset_index(drop=True), part)
