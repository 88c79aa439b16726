"""Provenance metadata and atomic writes (ttbpipe.io)."""

import json
import os

import pandas as pd
import pytest

import ttbpipe
from ttbpipe import io


def test_write_table_carries_config_and_version(tmp_path):
    df = pd.DataFrame({"chainage_m": [0.0, 0.25], "vertical_left_mm": [0.1, -0.2]})
    config = {"study": {"seed": 3}, "psd": {"section_length_m": 1000.0}}
    path = io.write_table(df, tmp_path / "t.parquet", config=config, kind="test", campaign="2024-01-01")
    doc = io.read_provenance(path)
    assert doc["ttbpipe_version"] == ttbpipe.__version__
    assert doc["config"] == config
    assert doc["kind"] == "test" and doc["campaign"] == "2024-01-01"
    pd.testing.assert_frame_equal(io.read_table(path), df)


def test_failed_write_leaves_no_partial_output(tmp_path):
    target = tmp_path / "out.parquet"
    with pytest.raises(RuntimeError):
        with io.atomic_path(target) as tmp:
            tmp.write_text("half a table")
            raise RuntimeError("killed mid-write")
    assert not target.exists()
    assert os.listdir(tmp_path) == []  # the temporary file is gone too


def test_failed_write_keeps_previous_version(tmp_path):
    target = tmp_path / "out.txt"
    io.write_text("old", target)
    with pytest.raises(ValueError):
        with io.atomic_path(target) as tmp:
            tmp.write_text("new but broken")
            raise ValueError
    assert target.read_text() == "old"


def test_provenance_is_json_for_numpy_values(tmp_path):
    import numpy as np
    df = pd.DataFrame({"a": [1]})
    path = io.write_table(df, tmp_path / "n.parquet", config={"x": np.float64(1.5), "v": np.arange(3)})
    assert io.read_provenance(path)["config"] == {"x": 1.5, "v": [0, 1, 2]}
    json.dumps(io.read_provenance(path))


def test_missing_provenance_is_reported(tmp_path):
    path = tmp_path / "plain.parquet"
    pd.DataFrame({"a": [1]}).to_parquet(path)
    with pytest.raises(KeyError, match="no ttbpipe provenance"):
        io.read_provenance(path)


def test_jsonable_makes_numpy_values_and_paths_plain():
    """Every numpy scalar becomes the Python scalar of the same value, arrays nested lists, paths
    strings, keys strings; NaN stays NaN unless nan_as_none (strict JSON has no NaN)."""
    import math
    from pathlib import Path

    import numpy as np
    value = {"i": np.int32(3), "f": np.float32(0.5), "b": np.bool_(True), 2: (1, np.int64(2)),
             "p": Path("a/b.parquet"), "a": np.array([[1.0, np.nan]]), "n": float("nan"),
             "nested": [{"x": np.float64(np.inf)}]}
    plain = io.jsonable(value)
    assert plain["i"] == 3 and type(plain["i"]) is int
    assert plain["f"] == 0.5 and type(plain["f"]) is float
    assert plain["b"] is True
    assert plain["2"] == [1, 2] and type(plain["2"][1]) is int
    assert plain["p"] == "a/b.parquet"
    assert plain["a"][0][0] == 1.0 and math.isnan(plain["a"][0][1])
    assert math.isnan(plain["n"]) and plain["nested"][0]["x"] == math.inf
    strict = io.jsonable(value, nan_as_none=True)
    assert strict["a"] == [[1.0, None]] and strict["n"] is None
    assert strict["nested"] == [{"x": None}] and strict["i"] == 3
    json.dumps(strict, allow_nan=False)
