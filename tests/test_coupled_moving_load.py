"""Second method: the coupled train vs constant moving loads on the same structure."""

import numpy as np

from ttbpipe.simulation.coupled import integrate, prepare, results_table
from ttbpipe.structure import build_structure
from ttbpipe.structure.moving_loads import build_loads, simulate

STRUCTURE = {"layout": {"approach_length_m": 60.0, "spans_m": [32.0], "approach_track": "rigid"}}
MONITOR = [{"name": "deck", "kind": "girder", "span": 0, "position": 0.5, "directions": ["z"],
            "quantities": ["displacement"]}]


def test_girder_deflection_matches_moving_static_wheel_loads():
    """Two cars at 200 km/h on a perfect track over one 32 m span. The coupled loop transfers the
    contact forces to the rails; the structure's moving-load solver (same structure, same
    rail shape functions) moves constant forces equal to the coupled run's static contact forces
    (F_z, F_y, M_x per wheel) at the same positions and speed. On a perfect track the dynamic
    wheel-load variation is small, so the mid-span girder deflection histories agree: peak within
    1 %, RMS difference below 1 % of the peak (measured 0.2 % and 0.1 %; the residual is the
    coupled run's dynamic wheel-load variation, which the constant loads do not have).
    The leading wheelset starts 10 m before the span, so the girder is unloaded at t = 0 in both."""
    case = {"train": {"composition": ["motor", "trailer"]},
            "structure": STRUCTURE,
            "simulation": {"track": "structure", "speed_kmh": 200.0, "time_step_s": 4e-5,
                           "output_every": 25},
            "irregularity": {"source": "none"},
            "monitors": MONITOR}
    setup = prepare(case)
    raw = integrate(setup)
    coupled = results_table(setup, raw)
    h = setup.mesh.head_height
    point_loads = []
    for w, dx in enumerate(setup.model.wheelset_x):
        for k in range(2):
            fy_rail = -setup.static_wheel[w, k, 1]
            point_loads.append({"rail": k, "x0_m": float(setup.x_lead0 + dx),
                                "Fz_N": float(-setup.static_wheel[w, k, 2]),
                                "Fy_N": float(fy_rail), "Mx_Nm": float(-h * fy_rail)})
    model = build_structure(STRUCTURE)
    loads = build_loads({"speed_kmh": 200.0, "point_loads": point_loads}, model)
    duration = setup.n_steps * setup.dt
    moving, _ = simulate(model, loads, setup.dt, duration, MONITOR, output_every=25)
    z_c = coupled["deck_z_disp_mm"].to_numpy()
    z_m = moving["deck_z_disp_mm"].to_numpy()
    n = min(z_c.size, z_m.size)
    z_c, z_m = z_c[:n], z_m[:n]
    assert np.allclose(coupled["time_s"].to_numpy()[:n], moving["time_s"].to_numpy()[:n])
    peak_c, peak_m = np.abs(z_c).max(), np.abs(z_m).max()
    assert peak_m > 0.3   # the train really loads the span (mm)
    assert abs(peak_c / peak_m - 1) < 0.01, (peak_c, peak_m)
    assert np.sqrt(np.mean((z_c - z_m) ** 2)) < 0.01 * peak_m
