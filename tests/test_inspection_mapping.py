"""Files of inspection cars with their own column names and units, read through a mapping.

A file with its own names (``KM``, ``LPROF``, ...) in kilometres and centimetres, read with
``inspections.columns`` / ``inspections.units``, must give the same cleaned table as the original
file in ttbpipe's names and units (within the round-off of writing the converted values to CSV
with 10 significant digits); every rename and conversion is logged and reported. Configuration
mistakes are clear errors. The schema's unit and column lists are the package's.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from ttbpipe.channels import INSPECTION_COLUMNS
from ttbpipe.cli import main
from ttbpipe.inspection import InspectionError, check_campaign, clean_campaign, read_campaign
from ttbpipe.inspection.format import (CHAINAGE_UNITS_TO_M, CHANNEL_UNITS_TO_MM,
                                       REQUIRED_COLUMNS, check_mapping)
from ttbpipe.inspection.synthetic import synthetic_campaign_series
from ttbpipe.inspection.validate import CLEANING_DEFAULTS

REPO = Path(__file__).resolve().parents[1]

OWN_NAMES = {"KM": "chainage_m", "LPROF": "vertical_left_mm", "RPROF": "vertical_right_mm",
             "LALIGN": "alignment_left_mm", "RALIGN": "alignment_right_mm",
             "XLEVEL": "cross_level_mm", "GAUGE": "gauge_mm"}
UNITS = {"chainage": "km", "channels": "cm"}


@pytest.fixture(scope="module")
def original() -> pd.DataFrame:
    """A valid synthetic campaign (with noise, dropouts and spikes), in ttbpipe's format."""
    return next(synthetic_campaign_series(["2023-01-15"], length_km=1.0, seed=9)).table


def own_format(frame: pd.DataFrame) -> pd.DataFrame:
    """The campaign as a car writing km and cm under its own names would."""
    own = frame.rename(columns={v: k for k, v in OWN_NAMES.items()})
    own["KM"] = own["KM"] / 1000.0
    for name in OWN_NAMES:
        if name != "KM":
            own[name] = own[name] / 10.0
    return own


def write(frame: pd.DataFrame, path: Path) -> Path:
    frame.to_csv(path, index=False, float_format="%.10g")
    return path


def test_mapped_file_cleans_to_the_original(original, tmp_path, caplog):
    reference, reference_report = check_campaign(write(original, tmp_path / "2023-01-15.csv"))
    path = write(own_format(original), tmp_path / "2023-01-16.csv")
    with caplog.at_level(logging.INFO, logger="ttbpipe.inspection"):
        clean, report = check_campaign(path, columns=OWN_NAMES, units=UNITS)
    assert list(clean.columns) == list(REQUIRED_COLUMNS)
    pd.testing.assert_frame_equal(clean, reference, check_exact=False, rtol=0, atol=1e-9)
    assert report.repairs == reference_report.repairs
    assert report.renamed_columns == OWN_NAMES
    assert report.unit_conversions == {"chainage_m": {"unit": "km", "factor": 1000.0},
                                       **{c: {"unit": "cm", "factor": 10.0}
                                          for c in INSPECTION_COLUMNS}}
    assert "column 'KM' read as 'chainage_m'" in caplog.text
    assert "gauge_mm converted from centimetres to millimetres (x 10" in caplog.text
    assert "columns mapped (inspections.columns): KM -> chainage_m" in report.summary()
    assert any("converted from cm" in note for note in report.notes)
    doc = json.loads(json.dumps(report.to_dict()))
    assert doc["unit_conversions"]["chainage_m"]["unit"] == "km"


def test_read_campaign_maps_and_clean_campaign_maps_in_memory(original, tmp_path):
    path = write(own_format(original), tmp_path / "2023-01-15.csv")
    raw = read_campaign(path, columns=OWN_NAMES, units=UNITS)
    assert list(raw.columns) == list(REQUIRED_COLUMNS)
    np.testing.assert_allclose(raw["chainage_m"], original["chainage_m"], rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match="already applied"):
        clean_campaign(raw, path, columns=OWN_NAMES, units=UNITS)
    in_memory, _ = clean_campaign(own_format(original), "x/2023-01-15.csv", columns=OWN_NAMES,
                                  units=UNITS)
    from_file, _ = clean_campaign(raw, path)
    pd.testing.assert_frame_equal(in_memory, from_file, check_exact=False, rtol=0, atol=1e-9)


def test_per_column_unit_overrides_channels(original, tmp_path):
    frame = original.copy()
    frame["gauge_mm"] = frame["gauge_mm"] / 25.4  # this one column in inches
    path = write(frame, tmp_path / "2023-01-15.csv")
    clean, report = check_campaign(path, units={"gauge_mm": "in"})
    assert report.unit_conversions == {"gauge_mm": {"unit": "in", "factor": 25.4}}
    reference, _ = clean_campaign(original, path)
    np.testing.assert_allclose(clean["gauge_mm"], reference["gauge_mm"], rtol=0, atol=1e-8)


def test_without_the_mapping_the_file_is_rejected(original, tmp_path):
    path = write(own_format(original), tmp_path / "2023-01-15.csv")
    with pytest.raises(InspectionError, match="missing column 'chainage_m'"):
        check_campaign(path)


def test_errors_name_the_files_own_column(original, tmp_path):
    frame = own_format(original)
    frame.loc[300:319, "GAUGE"] = np.nan  # rows 301-320: 5 m > max_gap_m
    path = write(frame, tmp_path / "2023-01-15.csv")
    with pytest.raises(InspectionError) as info:
        check_campaign(path, columns=OWN_NAMES, units=UNITS)
    err = info.value
    assert err.row == 301 and err.column == "GAUGE (read as gauge_mm)"
    assert "values converted from cm by inspections.units" in str(err)
    frame = own_format(original).astype({"LPROF": object})
    frame.loc[41, "LPROF"] = "n.a."  # data row 42
    path = write(frame, tmp_path / "2023-01-16.csv")
    with pytest.raises(InspectionError) as info:
        check_campaign(path, columns=OWN_NAMES, units=UNITS)
    assert (info.value.row, info.value.column) == (42, "LPROF")
    assert "text 'n.a.' in a number column" in str(info.value)


def test_mapping_problems_in_the_file(original, tmp_path):
    own = own_format(original)
    path = write(own.drop(columns="GAUGE"), tmp_path / "2023-01-15.csv")
    with pytest.raises(InspectionError) as info:
        check_campaign(path, columns=OWN_NAMES, units=UNITS)
    assert info.value.column == "GAUGE" and str(path) in str(info.value)
    assert "mapped to 'gauge_mm' by inspections.columns) is not in the file" in str(info.value)
    both = own.assign(gauge_mm=own["GAUGE"])
    path = write(both, tmp_path / "2023-01-16.csv")
    with pytest.raises(InspectionError, match="has both 'GAUGE'"):
        check_campaign(path, columns=OWN_NAMES, units=UNITS)
    # a mapped column absent while the file already has ttbpipe's name: nothing to rename
    path = write(original, tmp_path / "2023-01-17.csv")
    _, report = check_campaign(path, columns={"GAUGE": "gauge_mm"})
    assert report.renamed_columns == {}


def test_unit_suffix_error_points_to_the_mapping(original, tmp_path):
    frame = original.rename(columns={"vertical_left_mm": "vertical_left_cm"})
    path = write(frame, tmp_path / "2023-01-15.csv")
    with pytest.raises(InspectionError, match=r"inspections.columns: \{vertical_left_cm: "
                                              r"vertical_left_mm\}, inspections.units: "
                                              r"\{vertical_left_mm: cm\}"):
        check_campaign(path)


@pytest.mark.parametrize("columns, units, words", [
    ({"KM": "chainage_km"}, None, "not a ttbpipe column"),
    ({"A": "gauge_mm", "B": "gauge_mm"}, None, "both map to 'gauge_mm'"),
    (None, {"chainage": "mi"}, "chainage unit 'mi' is not one of m, km, ft"),
    (None, {"channels": "ft"}, "channels unit 'ft' is not one of mm, cm, m, in, um"),
    (None, {"speed": "km"}, "unknown key 'speed'"),
    (None, {"chainage": "km", "chainage_m": "m"}, "not both"),
])
def test_bad_mapping_is_a_clear_error(columns, units, words):
    with pytest.raises(ValueError, match=words):
        check_mapping(columns, units)


def test_cli_mapping_options_and_config(original, tmp_path, capsys):
    path = write(own_format(original), tmp_path / "2023-01-15.csv")
    assert main(["check-inspection", str(path)]) == 1
    assert "missing column 'chainage_m'" in capsys.readouterr().err
    columns = ",".join(f"{k}={v}" for k, v in OWN_NAMES.items())
    report_path = tmp_path / "repairs.json"
    assert main(["check-inspection", str(path), "--columns", columns, "--units",
                 "chainage=km,channels=cm", "--report", str(report_path)]) == 0
    out = capsys.readouterr().out
    assert "units converted (inspections.units)" in out and out.rstrip().endswith("OK")
    assert json.loads(report_path.read_text())["renamed_columns"] == OWN_NAMES
    config = tmp_path / "study.yaml"
    config.write_text(yaml.safe_dump({"inspections": {
        "directory": "x", "columns": OWN_NAMES, "units": UNITS,
        "cleaning": {"max_constant_run_m": 30.0}}}))
    clean_path = tmp_path / "clean.parquet"
    assert main(["check-inspection", str(path), "--config", str(config), "--out",
                 str(clean_path), "--report", str(report_path)]) == 0
    settings = json.loads(report_path.read_text())["settings"]
    assert settings["max_constant_run_m"] == 30.0  # from --config
    assert settings["band_rms_margin"] == CLEANING_DEFAULTS["band_rms_margin"]  # package default
    assert main(["check-inspection", str(path), "--config", str(config),
                 "--max-constant-run-m", "40", "--report", str(report_path)]) == 0
    assert json.loads(report_path.read_text())["settings"]["max_constant_run_m"] == 40.0
    capsys.readouterr()
    assert main(["check-inspection", str(path), "--units", "channels=furlong"]) == 2
    assert "channels unit 'furlong'" in capsys.readouterr().err


def test_schema_lists_are_the_packages():
    """study.schema.yaml repeats the package's unit and column names: they must agree."""
    schema = yaml.safe_load((REPO / "src/ttbpipe/schemas/study.schema.yaml").read_text())
    section = schema["properties"]["inspections"]["properties"]
    assert section["columns"]["additionalProperties"]["enum"] == list(REQUIRED_COLUMNS)
    units = section["units"]["properties"]
    assert set(units) == {"chainage", "channels", *REQUIRED_COLUMNS}
    for key, spec in units.items():
        expected = CHAINAGE_UNITS_TO_M if key in ("chainage", "chainage_m") else CHANNEL_UNITS_TO_MM
        assert sorted(spec["enum"]) == sorted(expected), key
    cleaning = set(section["cleaning"]["properties"])
    assert cleaning <= set(CLEANING_DEFAULTS)
    assert {"band_rms_margin", "max_constant_run_m"} <= cleaning


def test_config_with_a_mapping_validates():
    from ttbpipe.configuration import ConfigurationError, validate_study_config

    config = yaml.safe_load((REPO / "config/config.yaml").read_text())
    assert config["inspections"]["columns"] == {} and config["inspections"]["units"] == {}
    config["inspections"]["columns"] = dict(OWN_NAMES)
    config["inspections"]["units"] = dict(UNITS)
    config["inspections"]["cleaning"]["band_rms_margin"] = 4.0
    validate_study_config(config, "config.yaml")
    config["inspections"]["units"] = {"channels": "furlong"}
    with pytest.raises(ConfigurationError):
        validate_study_config(config, "config.yaml")


def test_documented_defaults_are_the_packages():
    """The options table of docs/inspection_format.md shows CLEANING_DEFAULTS."""
    import re

    doc = (REPO / "docs" / "inspection_format.md").read_text()
    rows = dict(re.findall(r"^\| `(\w+)` \| ([\w.]+) \|", doc, flags=re.M))
    documented = {k: v for k, v in rows.items() if k in CLEANING_DEFAULTS}
    assert set(documented) == set(CLEANING_DEFAULTS) - {"sampling_tolerance", "max_jitter"}
    for key, text in documented.items():
        default = CLEANING_DEFAULTS[key]
        assert (text == default) if isinstance(default, str) else float(text) == default, key
