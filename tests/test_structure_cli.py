"""``ttbpipe simulate`` end to end on a small case, and case-schema errors naming the key path."""

import numpy as np
import pytest
import yaml

from ttbpipe.cli import main
from ttbpipe.io import read_provenance, read_table
from ttbpipe.simulation.config import load_case

SMALL_CASE = {
    "name": "small",
    "structure": {"layout": {"approach_length_m": 10.0, "spans_m": [16.0],
                             "approach_track": "slab"}},
    "loads": {"speed_kmh": 250.0,
              "point_loads": [{"rail": 0, "x0_m": 2.0, "Fz_N": -7e4},
                              {"rail": 1, "x0_m": 2.0, "Fz_N": -7e4, "Fy_N": 5e3,
                               "harmonic": {"Fz_amplitude_N": 5e3, "frequency_hz": 30.0}}]},
    "simulation": {"time_step_s": 1e-4, "duration_s": 0.3, "output_every": 5},
    "monitors": [{"name": "girder_mid", "kind": "girder", "span": 0, "position": 0.5,
                  "directions": ["z", "y", "roll"]},
                 {"name": "rail_r", "kind": "rail", "rail": 1, "x_m": 18.0,
                  "quantities": ["displacement", "velocity", "acceleration"]}],
}


def test_simulate_cli_writes_table(tmp_path):
    cfg = tmp_path / "case.yaml"
    cfg.write_text(yaml.safe_dump(SMALL_CASE))
    out = tmp_path / "res.parquet"
    assert main(["simulate", str(cfg), "--out", str(out)]) == 0
    df = read_table(out)
    assert list(df.columns) == ["time_s", "girder_mid_z_disp_mm", "girder_mid_z_acc_m_s2",
                                "girder_mid_y_disp_mm", "girder_mid_y_acc_m_s2",
                                "girder_mid_roll_disp_mrad", "girder_mid_roll_acc_rad_s2",
                                "rail_r_z_disp_mm", "rail_r_z_vel_m_s", "rail_r_z_acc_m_s2"]
    assert len(df) == 601 and np.allclose(np.diff(df["time_s"]), 5e-4)
    # loads pass midspan (18 m) at ~0.23 s: the girder deflects downwards by a fraction of a mm
    assert -1.0 < df["girder_mid_z_disp_mm"].min() < -0.01
    prov = read_provenance(out)
    assert prov["kind"] == "simulation" and prov["config"]["name"] == "small"


def test_bad_case_names_key(tmp_path):
    bad = dict(SMALL_CASE, structure={"girder": {"damping_ratio": -0.1}})
    cfg = tmp_path / "bad.yaml"
    cfg.write_text(yaml.safe_dump(bad))
    with pytest.raises(ValueError, match=r"bad.yaml: structure.girder.damping_ratio"):
        load_case(cfg)
    assert main(["simulate", str(cfg), "--out", str(tmp_path / "x.parquet")]) == 1
    assert not (tmp_path / "x.parquet").exists()


def test_time_step_too_large_fails_with_remedy(tmp_path, capsys):
    case = dict(SMALL_CASE, simulation={"time_step_s": 5e-4, "duration_s": 0.01})
    cfg = tmp_path / "dt.yaml"
    cfg.write_text(yaml.safe_dump(case))
    assert main(["simulate", str(cfg), "--out", str(tmp_path / "y.parquet")]) == 1
    assert "simulation.time_step_s <=" in capsys.readouterr().err
    assert not (tmp_path / "y.parquet").exists()


def test_schema_covers_structure_defaults():
    from ttbpipe.simulation.config import schema
    from ttbpipe.structure.properties import DEFAULTS
    props = schema()["properties"]["structure"]["properties"]
    assert set(props) == set(DEFAULTS)
    for section, values in DEFAULTS.items():
        assert set(props[section]["properties"]) == set(values), section
