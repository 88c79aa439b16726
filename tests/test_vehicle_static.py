"""Static equilibrium and perfect-track runs of the train (ttbpipe.vehicle.static + coupled loop)."""

from pathlib import Path

import numpy as np
import pytest

from ttbpipe.simulation.config import load_case
from ttbpipe.simulation.coupled import integrate, prepare, results_table, run_coupled
from ttbpipe.vehicle.contact import build_geometry
from ttbpipe.vehicle.model import PITCH, ROLL, YAW, Y, build_train_model
from ttbpipe.vehicle.parameters import GRAVITY, TrainParameters
from ttbpipe.vehicle.static import solve_vehicle_static

ROOT = Path(__file__).resolve().parents[1]


def test_shipped_case_files_pass_the_case_schema():
    """The reference case and the vehicle validation cases are valid `ttbpipe simulate` inputs
    (the case JSON schema) and have a train: section (dispatch to run_coupled)."""
    paths = [ROOT / "config" / "reference_case.yaml", ROOT / "config" / "curved_bridge.yaml",
             *sorted((ROOT / "config" / "validation").glob("vehicle_*.yaml"))]
    assert len(paths) >= 5
    for path in paths:
        assert "train" in load_case(path), path


def _weight_distribution(train):
    """Per-wheel static load from the weight distribution of a symmetric car:
    g (M_c/8 + M_t/4 + M_w/2)."""
    return np.array([GRAVITY * (c.car_mass / 8 + c.bogie_mass / 4 + c.wheelset_mass / 2)
                     for c in train.cars for _ in range(4)])


def test_vehicle_static_newton_matches_weight_distribution():
    """Newton static solve on a perfect rigid track: every wheel carries its share of the car's
    weight (closed form above) to 1e-9, and the lateral DOFs stay exactly at rest."""
    train = TrainParameters()
    model = build_train_model(train)
    q, wheel, v = solve_vehicle_static(model, build_geometry(train.contact), 80.0)
    p_ref = _weight_distribution(train)
    assert np.allclose(wheel[:, 0, 2], p_ref, rtol=1e-9)
    assert np.allclose(wheel[:, 1, 2], p_ref, rtol=1e-9)
    lateral = np.concatenate([q[Y::5], q[ROLL::5], q[YAW::5]])
    assert np.max(np.abs(lateral)) < 1e-12
    assert np.max(np.abs(v)) < 1e-12   # perfect rigid track: nominal rolling, no spin correction
    # total vertical contact force = total weight (equilibrium, 1e-9)
    total = sum(c.total_mass for c in train.cars) * GRAVITY
    assert wheel[:, :, 2].sum() == pytest.approx(total, rel=1e-9)


def test_rigid_track_low_speed_keeps_static_loads():
    """Perfect rigid track at 36 km/h for 2 s: wheel loads equal the weight distribution within
    0.5 % at every output step (project requirement), the t = 0 loads equal the static solution
    (no initial transient, 1e-9), and there is no lateral response (|y| < 1e-12 m, H < 1e-6 N)."""
    case = load_case(ROOT / "config" / "validation" / "vehicle_static_rigid.yaml")
    table, summary = run_coupled(case)
    train = TrainParameters()
    p_ref = _weight_distribution(train)
    loads = table[[c for c in table.columns if c.endswith("_P_N")]].to_numpy()
    ref = np.repeat(p_ref, 2)
    assert np.max(np.abs(loads / ref - 1)) < 5e-3
    assert np.allclose(loads[0], ref, rtol=1e-9)
    ys = table[[c for c in table.columns if c.endswith("_y_mm")]].to_numpy()
    assert np.max(np.abs(ys)) < 1e-9
    hs = table[[c for c in table.columns if c.endswith("_H_N")]].to_numpy()
    assert np.max(np.abs(hs)) < 1e-6
    lat = table[[c for c in table.columns if c.endswith("_ay_m_s2")]].to_numpy()
    assert np.max(np.abs(lat)) < 1e-9
    assert summary["max_wheel_unloading_ratio"] < 5e-3


def test_vertical_excitation_only_gives_no_lateral_response():
    """Straight track with a vertical profile only (no alignment, cross-level or gauge) at 300
    km/h: the train's left-right symmetry means no lateral motion at all (|y| < 1e-9 mm,
    |a_y| < 1e-9 m/s^2), while the vertical response is non-trivial (P varies by > 1 %)."""
    case = {"simulation": {"track": "rigid", "speed_kmh": 300.0, "rigid_length_m": 120.0,
                           "time_step_s": 1e-4},
            "irregularity": {"source": "synthetic", "seed": 7, "channels": ["vertical"]}}
    table, summary = run_coupled(case)
    ys = table[[c for c in table.columns if c.endswith("_y_mm")]].to_numpy()
    lat = table[[c for c in table.columns if c.endswith("_ay_m_s2")]].to_numpy()
    assert np.max(np.abs(ys)) < 1e-9 and np.max(np.abs(lat)) < 1e-9
    assert summary["max_lateral_wheelset_force_N"] < 1e-6
    assert summary["max_wheel_unloading_ratio"] > 0.01


def test_time_step_check_names_the_remedy():
    """A step above the contact limit is refused with the setting to change: with the explicit
    lateral creep law, the low-speed creep damping on the rail head (f22/V) limits the step;
    with the default semi-implicit law (unconditionally stable for that damper,
    docs/performance.md) the Hertz contact mode still does (limit ~2e-4 s)."""
    case = {"train": {"composition": ["motor"]},
            "structure": {"layout": {"approach_length_m": 40.0, "spans_m": [32.0],
                                     "approach_track": "rigid"}},
            "simulation": {"track": "structure", "speed_kmh": 36.0, "time_step_s": 4e-5,
                           "lateral_creep": "explicit"},
            "irregularity": {"source": "none"}}
    with pytest.raises(ValueError, match="time_step_s"):
        prepare(case)
    case["simulation"].update(lateral_creep="semi_implicit", time_step_s=4e-4,
                              check_time_step=False)
    with pytest.raises(ValueError, match="Hertz"):
        prepare(case)


def test_structure_static_state_and_low_speed_run():
    """Train on the flexible track-bridge (one 32 m span, rigid-ground approaches): the
    train-structure static fixed point gives wheel loads within 0.5 % of the weight distribution
    (the bridge's quasi-static deflection redistributes little load), and a low-speed run starts
    without transient (t = 0 loads equal the static loads, 1e-6) and keeps them within 0.5 %.
    At low speed the lateral creep force is a stiff damper (f22/V) on the light rail head, so the
    explicit step must be small (checked by prepare): 36 km/h with dt = 6.25e-6 s. (At 72 km/h
    the fastener-passing excitation, V/0.63 m = 32 Hz on the discretely supported rail, already
    moves the loads by ~0.6 %: physical, not a start transient.)"""
    case = {"train": {"composition": ["motor", "trailer"]},
            "structure": {"layout": {"approach_length_m": 60.0, "spans_m": [32.0],
                                     "approach_track": "rigid"}},
            "simulation": {"track": "structure", "speed_kmh": 36.0, "time_step_s": 6.25e-6,
                           "end_x_m": 53.0},
            "irregularity": {"source": "none"}}
    setup = prepare(case)
    p_ref = _weight_distribution(setup.train)
    assert np.allclose(setup.static_wheel[:, 0, 2], p_ref, rtol=5e-3)
    assert setup.static_iterations <= 10
    raw = integrate(setup)
    table = results_table(setup, raw)
    loads = table[[c for c in table.columns if c.endswith("_P_N")]].to_numpy()
    # the state at t = 0 itself (the table's histories are low-passed before decimation, and a
    # zero-phase filter at t = 0 reaches into the first steps)
    assert np.allclose(raw.wheel[0, :, :, 2].ravel(), setup.static_wheel[:, :, 2].ravel(),
                       rtol=1e-6)
    # steady rolling at t = 0: every vehicle acceleration (incl. the wheelset spins, whose
    # steady rates are part of the static solution) vanishes
    assert np.max(np.abs(raw.a[0])) < 1e-9
    assert np.max(np.abs(loads / np.repeat(p_ref, 2) - 1)) < 5e-3


def test_tabulated_profile_option_runs_from_static_state():
    """The tabulated-profile option (demonstration worn table, worn-tread Hertz constant) gives
    the same static wheel loads (weight distribution, 1e-9: statics do not depend on the tread
    shape on a perfect track) and a finite, bounded run on TB/T irregularities at 300 km/h
    (wheelset lateral displacement inside the flange clearance, 9.1 mm)."""
    case = {"train": {"contact": {"profile": "table"}},
            "simulation": {"track": "rigid", "speed_kmh": 300.0, "rigid_length_m": 80.0,
                           "time_step_s": 1e-4},
            "irregularity": {"source": "synthetic", "seed": 5}}
    setup = prepare(case)
    assert "worn" in setup.geom.description
    p_ref = _weight_distribution(setup.train)
    assert np.allclose(setup.static_wheel[:, 0, 2], p_ref, rtol=1e-9)
    table, summary = run_coupled(case)
    ys = table[[c for c in table.columns if c.endswith("_y_mm")]].to_numpy()
    assert np.all(np.isfinite(ys)) and np.max(np.abs(ys)) < 9.1
    assert 0.0 < summary["max_derailment_coefficient"] < 0.8
