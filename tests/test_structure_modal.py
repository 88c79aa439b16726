"""Girder natural frequencies vs the Euler-Bernoulli closed form; the structure's first modes.

Closed forms (Blevins, Formulas for Natural Frequency and Mode Shape, 1979, tables 8-1 and 8-19):
simply supported bending f_j = j^2 pi/(2 L^2) sqrt(EI/m); torsion with fork supports
f_j = j/(2L) sqrt(GJ/(rho I_p)). Tolerance 0.1 % for the kept modes (32 elements per span).
The full-structure modal analysis (scipy eigsh on the assembled M, K) of a girder-only model with
pinned supports must give the same first vertical and lateral frequencies (0.1 %).
With track on top the first vertical frequency must drop below the bare girder's, by about the
added-mass ratio sqrt(m_g/(m_g + m_track)) (within 3 %: the track also adds a little stiffness).
"""

from pathlib import Path

import numpy as np
import pytest

from ttbpipe.simulation.config import load_case
from ttbpipe.simulation.moving_load_case import run_moving_loads
from ttbpipe.structure import build_structure
from ttbpipe.structure.modal import modal_analysis

CONFIG = Path(__file__).resolve().parents[1] / "config" / "validation"
L = 32.0
G = dict(E=3.45e10, nu=0.2, m=2.972e4, Iy=12.744, Iz=96.435, J=22.650, A=8.8889)


def bending(j, I):
    return j * j * np.pi / (2 * L * L) * np.sqrt(G["E"] * I / G["m"])


def torsion(j):
    GJ = G["E"] / (2 * (1 + G["nu"])) * G["J"]
    rho_ip = G["m"] / G["A"] * (G["Iy"] + G["Iz"])
    return j / (2 * L) * np.sqrt(GJ / rho_ip)


@pytest.fixture(scope="module")
def girder_only():
    return build_structure(load_case(CONFIG / "girder_modal.yaml")["structure"])


def test_span_modes_match_closed_form(girder_only):
    red = girder_only.spans[0]
    fv, fl, ft = red.mode_frequencies_hz
    assert fv.size >= 3 and fl.size >= 1 and ft.size >= 3
    for j, f in enumerate(fv, start=1):
        assert f == pytest.approx(bending(j, G["Iy"]), rel=1e-3)
    for j, f in enumerate(fl, start=1):
        assert f == pytest.approx(bending(j, G["Iz"]), rel=1e-3)
    for j, f in enumerate(ft, start=1):
        assert f == pytest.approx(torsion(j), rel=1e-3)


def test_global_modal_analysis_girder_only(girder_only):
    res = modal_analysis(girder_only, n_modes=6)
    assert res.first("girder_vertical", 0.9) == pytest.approx(bending(1, G["Iy"]), rel=1e-3)
    assert res.first("girder_lateral", 0.9) == pytest.approx(bending(1, G["Iz"]), rel=1e-3)


def test_first_frequencies_with_track_reported():
    """One span with slab track and bearings; report first vertical and lateral frequencies."""
    m = build_structure({"layout": {"approach_length_m": 20.0, "spans_m": [L]}})
    res = modal_analysis(m, n_modes=12)
    f_v = res.first("girder_vertical", 0.5)
    f_l = res.first("girder_lateral", 0.4)
    print(f"with track: first vertical {f_v:.3f} Hz, first lateral {f_l:.3f} Hz "
          f"(bare girder {bending(1, G['Iy']):.3f} / {bending(1, G['Iz']):.3f} Hz)")
    track_mass = 2 * 60.64 + 2.55 * 0.20 * 2500          # rails + slab per metre
    expected = bending(1, G["Iy"]) * np.sqrt(G["m"] / (G["m"] + track_mass))
    assert f_v < bending(1, G["Iy"])
    assert f_v == pytest.approx(expected, rel=0.03)
    assert 0 < f_l < bending(1, G["Iz"])   # bearings and sway-roll coupling soften the lateral mode


def test_girder_modal_case_quasi_static():
    """The shipped case: a 10 m/s force (alpha = 0.026) gives nearly the static midspan deflection
    P L^3/(48 EI) (dynamic amplification ~1/(1 - alpha) -> within 5 %)."""
    table, _ = run_moving_loads(load_case(CONFIG / "girder_modal.yaml"))
    peak = -table["girder_mid_z_disp_mm"].min() / 1e3
    static = 1e5 * L ** 3 / (48 * G["E"] * G["Iy"])
    assert peak == pytest.approx(static, rel=0.05)


def test_modal_analysis_depends_on_the_model_alone():
    """Bit-identical frequencies and shapes whatever eigen-solves ran before in the process
    (ARPACK's default start vector comes from a generator carried over between calls: without
    the fixed start the first frequencies differed by about 1e-12 Hz between two calls)."""
    model = build_structure({})
    first = modal_analysis(model, n_modes=10)
    modal_analysis(model, n_modes=6, sigma_hz=40.0)          # another solve in between
    again = modal_analysis(model, n_modes=10)
    assert np.array_equal(first.frequencies_hz, again.frequencies_hz)
    assert np.array_equal(first.shapes, again.shapes)
