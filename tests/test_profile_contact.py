"""The coupled model's contact table from real profiles (ttbpipe.vehicle.profile_contact).

References (independent of the code):
* a straight cone of slope lambda on a circular crown, wheelset level: the contact point stays
  at the crown point of slope lambda, so the wheel's contact radius changes by exactly lambda y,
  the gap by lambda y, and the contact angle is atan(lambda) (Klingel geometry);
* S1002 (EN 13715): flange angle 70 degrees; with gauge 1435 mm and flange-back spacing 1360 mm
  and the flange thickness 32.5 mm the flange clearance is (1435 - 1360 - 2 x 32.5) / 2 = 5 mm,
  so the tread-to-flange jump of the contact lies just beyond 5 mm.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml

from ttbpipe.vehicle.contact import COL_DELTA, COL_DZ, COL_R, build_geometry
from ttbpipe.vehicle.parameters import ContactParameters
from ttbpipe.vehicle.profiles import MM, cone_wheel_profile, crown_rail_profile

ROOT = Path(__file__).resolve().parents[1]


def _write(profile, path: Path) -> str:
    header = f"test profile {profile.name}"
    if profile.kind == "wheel":
        header += f"\nflange_back_mm: {profile.flange_back / MM:.6f}"
    np.savetxt(path, np.column_stack([profile.lateral / MM, profile.vertical / MM]), fmt="%.9f",
               header=header)
    return str(path)


def test_cone_pair_gives_the_cone_table(tmp_path):
    lam = 0.05
    p = ContactParameters(profile="profiles", rail_inclination="none",
                          wheel_profile=_write(cone_wheel_profile(lam), tmp_path / "cone.txt"),
                          rail_profile=_write(crown_rail_profile(10.0), tmp_path / "crown.txt"))
    geom = build_geometry(p)
    y = geom.table[:, 0]
    inside = np.abs(y) <= 5e-3
    np.testing.assert_allclose(geom.table[inside, COL_R], p.wheel_radius + lam * y[inside],
                               rtol=0, atol=2e-7)
    np.testing.assert_allclose(geom.table[inside, COL_DZ], lam * y[inside], rtol=0, atol=2e-7)
    np.testing.assert_allclose(geom.table[inside, COL_DELTA], np.arctan(lam), atol=1e-4)
    assert geom.flange_stiffness == 0.0          # no spring: the table holds the profile


def test_s1002_on_60e1_table_reaches_the_flange():
    geom = build_geometry(ContactParameters(profile="profiles"))
    y, delta, dz = geom.table[:, 0], geom.table[:, COL_DELTA], geom.table[:, COL_DZ]
    assert np.degrees(delta.max()) == pytest.approx(70.0, abs=0.5)
    jump = y[np.argmax(np.diff(delta)) + 1]
    assert 5.0e-3 < jump < 7.0e-3, jump
    # on the tread the contact angle is small and the gap changes little; on the flange the
    # gap's slope is the contact angle's tangent (the wheel climbs the flange)
    tread = np.abs(y) < 4e-3
    assert np.all(np.abs(delta[tread]) < 0.12)
    flange = (y > 7.5e-3) & (y < 9e-3)
    np.testing.assert_allclose(np.gradient(dz, y)[flange], np.tan(delta[flange]), rtol=0.05)
    assert "s1002 on 60e1" in geom.description


@pytest.mark.slow
def test_reference_train_runs_on_real_profiles():
    """One car of the reference case on S1002 / 60E1 (1:40) over the first span: the run
    completes from its static equilibrium, every wheel carries its static load at t = 0, and
    the safety indices stay in the range of a tangent track at 300 km/h."""
    from ttbpipe.simulation.coupled import integrate, prepare, run_coupled

    case = yaml.safe_load((ROOT / "config" / "reference_case.yaml").read_text())
    case = copy.deepcopy(case)
    case["train"]["composition"] = ["trailer"]
    case["train"]["contact"] = {"profile": "profiles", "wheel_profile": "s1002",
                                "rail_profile": "60e1", "rail_inclination": "1:40"}
    case["structure"]["layout"]["spans_m"] = [32.0]
    case["structure"]["layout"]["approach_length_m"] = 40.0
    # the worn-tread Hertz law of a profile pair is stiffer than the cone's: the coupled
    # rail-contact limit falls to 1.21e-4 s (the step check says so and proposes 1.2e-4 s)
    case["simulation"]["time_step_s"] = 1.0e-4
    table, s = run_coupled(case)
    finite = table.drop(columns=[c for c in table if c.endswith("_QP")]).to_numpy()
    assert np.all(np.isfinite(finite))
    assert 0.0 < s["max_derailment_coefficient"] < 0.8
    assert 0.0 < s["max_wheel_unloading_ratio"] < 0.8
    p0 = np.concatenate(list(s["static_wheel_load_N"].values()))
    short = {**case, "simulation": {**case["simulation"], "duration_s": 0.01}}
    first = integrate(prepare(short)).wheel[0, :, :, 2].ravel()
    assert np.allclose(first, p0, rtol=1e-6)
