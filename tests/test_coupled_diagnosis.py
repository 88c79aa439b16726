"""Bad inputs get their own message: step proposals, rough irregularities, loss of contact.

* A refused step in a study sample proposes a number (not ``auto``: every sample of a study must
  share one time grid), and that number passes; ``ttbpipe simulate`` (one case) also offers
  ``auto``.
* A rough irregularity that makes wheels lose contact (FRA class 5 at 300 km/h: its curvature
  asks the wheels for 1.6 times the downward acceleration contact can give) is a result:
  ``ttbpipe simulate`` exits 0 with a finite table, the in-contact flags, Q/P = 0 off the rail,
  and the loss of contact as its own index. The loop's every-step counters are checked against
  a second method, the runs of the table's in-contact flag with output at every step.
* Runs that stop because of the input name the input, not the step: FRA class 4 at 300 km/h
  (every wheel off the rail: "too rough for 300 km/h", with the speed at which contact holds),
  FRA class 1 x 3 (118 mm in the 3-25 m band, beyond the plausible 30 mm: "check the scale /
  units"), a factor 1000 (mm vs m). A run that diverges because its step exceeds the structure's
  limit (``check_time_step: false``) names the step with a number that passes every limit.
Thresholds and their calibration: ttbpipe.simulation.diagnosis (module docstring).
"""

import re

import numpy as np
import pandas as pd
import pytest
import yaml

from ttbpipe.cli import main
from ttbpipe.io import read_provenance, read_table
from ttbpipe.simulation.coupled import SimulationStopped, prepare, run_coupled
from ttbpipe.stats.schema import validate_extremes
from ttbpipe.study import samples as study_samples

STRUCTURE = {"layout": {"approach_length_m": 30.0, "spans_m": [32.0],
                        "approach_track": "ballasted", "bridge_track": "slab"}}
RIGID = {"track": "rigid", "speed_kmh": 300.0, "time_step_s": 1e-4, "rigid_length_m": 200.0}


def rigid_case(irregularity, **sim):
    return {"train": {"composition": ["trailer"]}, "simulation": {**RIGID, **sim},
            "irregularity": {"source": "synthetic", "seed": 1, **irregularity}}


def proposed(message):
    m = re.search(r"set simulation\.time_step_s <= ([0-9.eE+-]+)", message)
    assert m, message
    return float(m.group(1))


def test_study_sample_proposes_a_number_not_auto():
    sim = study_samples.resolve_simulation({"train": {"composition": ["trailer"]},
                                            "time_step_s": 3e-4, "end_x_m": 40.0})
    row = {"kind": "single", "sample_index": 0, "scenario": "single", "weight": 1.0,
           "seed_entropy": "1"}
    with pytest.raises(RuntimeError, match="sample \\(single, 0\\)") as err:
        study_samples.run_sample(row, study_seed=5, sim=sim, structure=STRUCTURE, fields=None,
                                 profiles={})
    msg = str(err.value)
    assert "auto" not in msg
    assert "coupled rail-contact stability limit" in msg and "Hertz" in msg
    dt = proposed(msg)
    # the proposal passes every limit of that sample
    case = study_samples.build_case({**sim, "time_step_s": dt}, STRUCTURE,
                                    irregularity={"source": "none"})
    setup = prepare(case)
    assert setup.dt == dt <= min(setup.dt_limits[k] for k in (
        "dt_structure_s", "dt_coupled_s", "dt_hertz_s", "dt_creep_spin_s", "dt_vehicle_s"))


def test_simulate_offers_auto_and_the_summary_carries_every_limit(tmp_path, capsys):
    case = {"train": {"composition": ["trailer"]}, "structure": STRUCTURE,
            "simulation": {"speed_kmh": 300.0, "time_step_s": 3e-4, "end_x_m": 40.0},
            "irregularity": {"source": "none"}}
    cfg = tmp_path / "case.yaml"
    cfg.write_text(yaml.safe_dump(case))
    out = tmp_path / "res.parquet"
    assert main(["simulate", str(cfg), "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert "or time_step_s: auto" in err and not out.exists()
    case["simulation"]["time_step_s"] = proposed(err)
    cfg.write_text(yaml.safe_dump(case))
    assert main(["simulate", str(cfg), "--out", str(out)]) == 0
    limits = read_provenance(out)["summary"]["dt_limits"]
    for key in ("dt_structure_s", "dt_coupled_s", "dt_hertz_s", "dt_creep_spin_s",
                "dt_creep_lateral_s", "dt_vehicle_s", "dt_vehicle_limit_s", "vehicle_mode"):
        assert key in limits, key


def test_rough_irregularity_completes_with_finite_results_and_a_contact_loss_index(tmp_path):
    cfg = tmp_path / "rough.yaml"
    cfg.write_text(yaml.safe_dump(rigid_case({"spectrum": "fra_class5"})))
    out = tmp_path / "rough.parquet"
    assert main(["simulate", str(cfg), "--out", str(out)]) == 0
    table = read_table(out)
    summary = read_provenance(out)["summary"]
    assert np.isfinite(table.to_numpy(float)).all()
    flags = [c for c in table.columns if c.endswith("_in_contact")]
    assert len(flags) == 8 and set(np.unique(table[flags].to_numpy())) == {0, 1}
    for flag in flags:
        off = table[flag].to_numpy() == 0
        wheel = flag[: -len("_in_contact")]
        assert (table.loc[off, f"{wheel}_QP"] == 0).all()
        # the table's P is the anti-aliased (band-limited) force history, which near a lift-off
        # is not 0 at the output step itself: the flag carries the contact state there
    assert summary["contact_loss_count"] > 0 and summary["contact_loss_max_s"] > 0
    assert summary["contact_loss_total_s"] >= summary["contact_loss_max_s"]
    assert sum(w["count"] for w in summary["contact_loss_per_wheel"].values()) == \
        summary["contact_loss_count"]
    assert np.isfinite(summary["max_derailment_coefficient"])
    # the loop's peak Q/P is over every step in contact: at least the table's maximum
    qp = table[[c for c in table.columns if c.endswith("_QP")]].to_numpy()
    assert summary["max_derailment_coefficient"] >= qp.max()
    assert summary["irregularity"]["contact_demand_ratio"] > 1.0
    # the study's extremes carry the index and follow the schema
    ext = study_samples.extremes_from_run(summary)
    assert ext["contact_loss_count"] == summary["contact_loss_count"] > 0
    assert ext["contact_loss_max_duration_s"] == summary["contact_loss_max_s"]
    row = pd.DataFrame([{"sample_index": 0, "scenario": "rough", "weight": 1.0,
                         "seed_entropy": "1", **ext}])
    row["scenario"] = row["scenario"].astype("string")
    row["seed_entropy"] = row["seed_entropy"].astype("string")
    validate_extremes(row)


def test_contact_loss_counters_equal_the_runs_of_the_per_step_flag():
    """Second method: output at every step, count the runs of in_contact == 0 per wheel."""
    case = rigid_case({"spectrum": "fra_class5"}, rigid_length_m=100.0, output_every=1)
    table, summary = run_coupled(case)
    dt = summary["time_step_s"]
    n_events = 0
    for wheel, stats in summary["contact_loss_per_wheel"].items():
        off = np.r_[0, (table[f"{wheel}_in_contact"].to_numpy() == 0).astype(int), 0]
        starts, ends = np.flatnonzero(np.diff(off) == 1), np.flatnonzero(np.diff(off) == -1)
        lengths = ends - starts
        assert stats["count"] == lengths.size, wheel
        assert stats["total_s"] == pytest.approx(lengths.sum() * dt, rel=1e-12, abs=1e-15)
        assert stats["max_s"] == pytest.approx(lengths.max() * dt if lengths.size else 0.0,
                                               rel=1e-12, abs=1e-15)
        n_events += lengths.size
    assert n_events == summary["contact_loss_count"] > 0


def test_too_rough_for_the_speed_blames_the_irregularity_not_the_step():
    with pytest.raises(SimulationStopped) as err:
        run_coupled(rigid_case({"spectrum": "fra_class4"}))
    exc, msg = err.value, str(err.value)
    assert exc.status == 2 and exc.cause == "irregularity_rough"
    assert "too rough for 300 km/h" in msg and "contact would hold below about" in msg
    assert "0.0001 s is within every stability limit" in msg and "not the cause" in msg
    assert "set simulation.time_step_s" not in msg
    assert exc.contact_loss["contact_loss_count"] > 0      # wheels lifted before the stop
    assert "wheel-rail contact before the stop" in msg


def test_implausible_scale_blames_the_scale(tmp_path, capsys):
    cfg = tmp_path / "scale3.yaml"
    cfg.write_text(yaml.safe_dump(rigid_case({"spectrum": "fra_class1", "scale": 3})))
    assert main(["simulate", str(cfg), "--out", str(tmp_path / "x.parquet")]) == 1
    err = capsys.readouterr().err
    assert "irregularity.scale 3 of spectrum fra_class1 gives 118 mm peak lateral" in err
    assert "beyond the plausible 30 mm" in err and "check the scale / units" in err
    assert "not the cause" in err and "Traceback" not in err
    # a factor 1000 (mm vs m) is named as such
    with pytest.raises(SimulationStopped, match="mm vs m"):
        run_coupled(rigid_case({"spectrum": "tbt3352", "scale": 1000.0}))


def test_step_above_the_structure_limit_is_named_when_the_check_is_off():
    case = {"structure": {"layout": {"approach_length_m": 60.0, "spans_m": [24.0]},
                          "girder": {"element_length_m": 2.0}},
            "train": {"composition": ["trailer"]},
            "simulation": {"speed_kmh": 300.0, "time_step_s": 1.9e-4, "duration_s": 0.3,
                           "check_time_step": False},
            "irregularity": {"source": "synthetic", "seed": 1}}
    with pytest.raises(SimulationStopped) as err:
        run_coupled(case)
    assert err.value.cause == "time_step"
    msg = str(err.value)
    assert "likely cause: the time step 0.00019 s, above the stability limit(s) structure" in msg
    case["simulation"].update(time_step_s=proposed(msg), duration_s=0.05)
    run_coupled(case)


def test_non_finite_values_are_stopped_with_the_column_and_the_cause():
    from ttbpipe.simulation.coupled import check_finite, integrate, results_table, summarise

    setup = prepare(rigid_case({"spectrum": "tbt3352"}, rigid_length_m=10.0))
    raw = integrate(setup)
    table = results_table(setup, raw)
    summary = summarise(setup, raw, table)
    check_finite(setup, table, summary)                      # a clean run passes
    bad = table.copy()
    bad.loc[3, "car1_ws2_left_QP"] = np.inf
    with pytest.raises(ValueError, match=r"column\(s\) \['car1_ws2_left_QP'\].*x = ") as err:
        check_finite(setup, bad, summary)
    assert "within every stability limit" in str(err.value)
    with pytest.raises(ValueError, match="max_wheel_vertical_force_N"):
        check_finite(setup, table, {**summary, "max_wheel_vertical_force_N": float("nan")})
    with pytest.raises(RuntimeError, match=r"extremes column\(s\) \['max_derailment_coefficient'\]"):
        study_samples.extremes_from_run({**summary, "max_derailment_coefficient": np.inf})
    sim = {"history": {"span": 1, "wheel": "car1_ws2_left", "carbody_point": "car1_body_front"}}
    for name in ("girder_span1_mid_z_acc_m_s2", "girder_span1_mid_y_acc_m_s2",
                 "girder_span1_mid_z_disp_mm", "rail_left_span1_mid_z_acc_m_s2",
                 "rail_left_span1_mid_y_acc_m_s2"):
        bad[name] = 0.0                                        # a rigid run has no monitors
    with pytest.raises(ValueError, match="car1_ws2_left_QP"):
        study_samples.history_from_run(bad, sim, 1)
