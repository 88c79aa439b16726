"""Piers of a given height (ttbpipe.structure.pier) against beam theory, and on the bridge.

References (independent of the code):
* top stiffness of a cantilever, fixed base, DOFs (y, dy/dz) at the top: EI/h^3 [[12, -6h],
  [-6h, 4h^2]] (Przemieniecki 1968, eq. 5.115 condensed), axial EA/h; with dy/dz = -roll
  (roll lifts the left side) the (y, roll) block is EI/h^3 [[12, 6h], [6h, 4h^2]];
* first bending frequency of a uniform cantilever with a tip mass M_t: the root of
  1 + cos(l) cosh(l) + (M_t / (m h)) l (cos(l) sinh(l) - sin(l) cosh(l)) = 0, omega =
  l^2 sqrt(EI / (m h^4)) (Blevins 1979, Formulas for Natural Frequency and Mode Shape, Table
  8-8); with a tip rotary inertia J as well, the exact Euler-Bernoulli solution
  y = A (cosh - cos)(bz) + B (sinh - sin)(bz) with the tip conditions EI y'' = omega^2 J y' and
  EI y''' = -omega^2 M_t y (from the Lagrangian), solved here for the root; it reduces to
  Blevins' equation at J = 0 (checked below).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from ttbpipe.structure import build_structure
from ttbpipe.structure.modal import modal_analysis
from ttbpipe.structure.pier import reduce_pier
from ttbpipe.structure.properties import PIER

E, I, A, M_PER_M = PIER["E_Pa"], PIER["I_lateral_m4"], PIER["area_m2"], PIER["mass_kg_m"]


def _tip_determinant(lam: float, h: float, tip_mass: float, tip_inertia: float) -> float:
    """Determinant of the two tip conditions for y = A (cosh - cos) + B (sinh - sin), scaled
    by h: zero at an eigenvalue lam = beta h."""
    b = lam / h
    w2 = lam ** 4 * E * I / (M_PER_M * h ** 4)
    ch, sh, c, s = np.cosh(lam), np.sinh(lam), np.cos(lam), np.sin(lam)
    # y, y', y'', y''' at the tip for the two shape functions (A: cosh - cos, B: sinh - sin)
    y = np.array([ch - c, sh - s])
    d1 = b * np.array([sh + s, ch - c])
    d2 = b ** 2 * np.array([ch + c, sh + s])
    d3 = b ** 3 * np.array([sh - s, ch + c])
    row1 = E * I * d2 - w2 * tip_inertia * d1
    row2 = E * I * d3 + w2 * tip_mass * y
    return float((row1[0] * row2[1] - row1[1] * row2[0]) / (E * I * b ** 3) ** 2 * 1e-3)


def _first_root(f, lo=0.3, hi=3.0) -> float:
    grid = np.linspace(lo, hi, 600)
    vals = [f(x) for x in grid]
    for a, b, fa, fb in zip(grid[:-1], grid[1:], vals[:-1], vals[1:]):
        if np.sign(fa) != np.sign(fb):
            return brentq(f, a, b, xtol=1e-13)
    raise AssertionError("no root")


def _cantilever_first_frequency_hz(h: float, tip_mass: float, tip_inertia: float) -> float:
    lam = _first_root(lambda x: _tip_determinant(x, h, tip_mass, tip_inertia))
    return lam ** 2 * np.sqrt(E * I / (M_PER_M * h ** 4)) / (2 * np.pi)


def test_exact_tip_conditions_reduce_to_blevins_tip_mass_equation():
    h, tip = 30.0, 1.0e5
    ratio = tip / (M_PER_M * h)
    lam_blevins = _first_root(lambda x: 1 + np.cos(x) * np.cosh(x)
                              + ratio * x * (np.cos(x) * np.sinh(x) - np.sin(x) * np.cosh(x)))
    lam = _first_root(lambda x: _tip_determinant(x, h, tip, 0.0))
    assert lam == pytest.approx(lam_blevins, rel=1e-10)
    assert _first_root(lambda x: 1 + np.cos(x) * np.cosh(x)) == pytest.approx(1.8751040687,
                                                                               rel=1e-9)


@pytest.mark.parametrize("height_m", [10.0, 20.0, 30.0, 40.0])
def test_pier_top_stiffness_is_the_cantilever_closed_form(height_m):
    red = reduce_pier(height_m, E, I, A, M_PER_M, 1.0e5, 9.0e5, 0.05)
    EI, h = E * I, height_m
    # static condensation of the reduced block to the top: the fixed-interface modes are
    # stiffness-orthogonal to the constraint modes, so the top block is the condensed one
    top = [0, 1, 2]
    K = red.K
    rest = np.arange(3, red.n)
    Kc = K[np.ix_(top, top)] - K[np.ix_(top, rest)] @ np.linalg.solve(K[np.ix_(rest, rest)],
                                                                         K[np.ix_(rest, top)])
    expected = np.array([[12 * EI / h ** 3, 0.0, 6 * EI / h ** 2],
                         [0.0, E * A / h, 0.0],
                         [6 * EI / h ** 2, 0.0, 4 * EI / h]])
    np.testing.assert_allclose(Kc, expected, rtol=1e-8, atol=1e-6 * np.abs(expected).max())


@pytest.mark.parametrize("height_m", [10.0, 20.0, 30.0, 40.0])
@pytest.mark.parametrize("tip_inertia", [0.0, 9.0e5])
def test_pier_first_sway_frequency_against_exact_cantilever(height_m, tip_inertia):
    """Free-topped reduced pier with its cap: first frequency within 0.1 % of the exact
    cantilever (1 m Hermite elements and the 120 Hz Craig-Bampton cut-off: both errors are
    far below that for the first mode)."""
    red = reduce_pier(height_m, E, I, A, M_PER_M, 1.0e5, tip_inertia, 0.05)
    expected = _cantilever_first_frequency_hz(height_m, 1.0e5, tip_inertia)
    assert red.frequencies_hz()[0] == pytest.approx(expected, rel=1e-3)


def _bridge(height_m):
    pier = {} if height_m is None else {"height_m": height_m}
    return build_structure({"layout": {"approach_length_m": 30.0, "spans_m": [32.0] * 3,
                                       "approach_track": "slab", "bridge_track": "slab"},
                            "pier": pier})


def test_taller_piers_lower_the_bridges_lateral_mode_and_the_model_stays_stable():
    """Three spans on two piers: the first mode with most kinetic energy in the girders'
    lateral coordinates falls with the pier height; the structure's stable step stays that of
    the rails (the pier blocks add no faster mode)."""
    freqs, steps = [], []
    for h in (10.0, 30.0, 50.0):
        model = _bridge(h)
        res = modal_analysis(model, n_modes=30)
        freqs.append(res.first("girder_lateral", 0.2))
        steps.append(model.stable_time_step())
    assert freqs[0] > freqs[1] > freqs[2], freqs
    base = _bridge(None).stable_time_step()
    assert min(steps) == pytest.approx(base, rel=0.02)
