"""Long rail on discrete fasteners on rigid ground vs the beam-on-elastic-foundation deflection.

Reference: Winkler foundation (Timoshenko 1926; Hetenyi, Beams on Elastic Foundation, 1946):
w0 = P beta/(2k), beta = (k/(4EI))^(1/4), with the discrete pads smeared, k = k_pad/spacing.
Tolerance 5 % (project requirement; discrete support spacing 0.63 m << pi/beta = 2.4 m).
Checked (a) by a static solve K u = f of the assembled structure with the load over a fastener
and mid-way between two, and (b) by the time loop of config/validation/boef_static.yaml, whose
damped response settles to the static deflection.
"""

from pathlib import Path

import numpy as np
import pytest
from scipy.sparse import linalg as splinalg

from ttbpipe.simulation.config import load_case
from ttbpipe.simulation.moving_load_case import run_moving_loads
from ttbpipe.structure import build_structure
from ttbpipe.structure.rail_mesh import add_rail_point_load, rail_mesh, rail_point_kinematics

CASE = Path(__file__).resolve().parents[1] / "config" / "validation" / "boef_static.yaml"
P = 1.0e5


def boef_w0(model):
    r, f = model.config["rail"], model.config["fastener"]
    k = f["kz_N_m"] / model.packed.rail_dx
    beta = (k / (4 * r["E_Pa"] * r["Iy_m4"])) ** 0.25
    return P * beta / (2 * k)


def test_static_deflection_matches_boef():
    case = load_case(CASE)
    model = build_structure(case["structure"])
    _, K, _ = model.matrices()
    solve = splinalg.factorized(K.tocsc())
    w0 = boef_w0(model)
    for x in (60.0, 60.0 + 0.5 * model.packed.rail_dx):   # near a fastener / between two
        f = np.zeros(model.n_dof)
        add_rail_point_load(rail_mesh(model.packed, 0.0), 0, x, -P, 0.0, 0.0, f)
        u = solve(f)
        z = rail_point_kinematics(rail_mesh(model.packed, 0.0), 0, x, u, u)[0]
        assert -z == pytest.approx(w0, rel=0.05)
        # the other rail is not loaded: no coupling through rigid ground
        assert abs(rail_point_kinematics(rail_mesh(model.packed, 0.0), 1, x, u, u)[0]) < 1e-12


def test_time_loop_settles_to_boef():
    table, _ = run_moving_loads(load_case(CASE))
    model = build_structure(load_case(CASE)["structure"])
    z_end = -table["rail_load_point_z_disp_mm"].to_numpy()[-1] / 1e3
    assert z_end == pytest.approx(boef_w0(model), rel=0.05)
