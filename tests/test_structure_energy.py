"""Undamped free vibration: energy conservation of the structure under Zhai's method.

Reference: Zhai's scheme with psi = phi = 1/2 has amplification eigenvalues of modulus exactly 1
for omega dt < 2 (no numerical dissipation; Zhai 1996, physics.md section 5) and is second-order
accurate. Hence the energy E = (v^T M v + u^T K u)/2 of an undamped structure
(a) shows no secular growth or decay: the largest deviation in the last quarter of the run is
    within 20 % of that in the first quarter, and
(b) deviates from E_0 by an error of second order: halving dt divides the largest deviation by
    4 (accepted 3..5).
All damping is zeroed (config/validation/undamped_free_vibration.yaml); the initial state is the static deflection under a wheel pair, released.
"""

from pathlib import Path

import numpy as np
from scipy.sparse import linalg as splinalg

from ttbpipe.simulation.config import load_case
from ttbpipe.structure import build_structure
from ttbpipe.timestepping.limits import stable_time_step
from ttbpipe.structure.kernels import structure_accelerations as _structure_accelerations
from ttbpipe.structure.rail_mesh import add_rail_point_load, rail_mesh
from ttbpipe.timestepping.zhai import zhai_predict as _zhai_predict

CASE = Path(__file__).resolve().parents[1] / "config" / "validation" / "undamped_free_vibration.yaml"
UNDAMPED = load_case(CASE)["structure"]


def run_energy(m, M, K, dt, duration):
    """Relative energy deviation history of the released static deflection."""
    f = np.zeros(m.n_dof)
    for rail in (0, 1):
        add_rail_point_load(rail_mesh(m.packed, 0.0), rail, 14.0, -7e4, 2e3, 0.0, f)
    u = splinalg.spsolve(K.tocsc(), f)
    v = np.zeros(m.n_dof)
    a = np.zeros(m.n_dof)
    zero = np.zeros(m.n_dof)
    _structure_accelerations(m.packed, u, v, zero, a)
    ap = a.copy()
    e0 = 0.5 * (u @ (K @ u))
    n_steps = int(round(duration / dt))
    rel = np.empty(n_steps)
    for n in range(n_steps):
        psi = 0.0 if n == 0 else 0.5
        _zhai_predict(u, v, a, ap, dt, psi, psi)       # ap = a after it
        _structure_accelerations(m.packed, u, v, zero, a)
        rel[n] = 0.5 * (v @ (M @ v) + u @ (K @ u)) / e0 - 1
    return rel


def test_free_vibration_energy():
    m = build_structure(UNDAMPED)
    M, K, C = m.matrices()
    assert abs(C).max() == 0.0
    dt = stable_time_step(m, safety=0.5)["dt_s"]
    coarse = run_energy(m, M, K, dt, 0.06)
    fine = run_energy(m, M, K, dt / 2, 0.06)
    e1, e2 = np.abs(coarse).max(), np.abs(fine).max()
    q = coarse.size // 4
    first, last = np.abs(coarse[:q]).max(), np.abs(coarse[-q:]).max()
    print(f"dt {dt:.3e} s: max |dE/E0| {e1:.3e}; dt/2: {e2:.3e} (ratio {e1 / e2:.2f}); "
          f"first/last quarter {first:.3e} / {last:.3e}")
    assert np.all(np.isfinite(coarse)) and np.all(np.isfinite(fine))
    assert 3.0 <= e1 / e2 <= 5.0
    assert last <= 1.2 * first
