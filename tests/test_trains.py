"""The train library and the HSLM-A trains as moving forces on a simply supported girder.

(a) Every HSLM-A train's axles against EN 1991-2:2003 Annex E, Table E.1 (N, D, d, P typed
    below from the table) and Figure E.1 (power cars: axles at 0, 3, 14, 17 m; 3.525 m from a
    power car's last axle to the end coach's first axle): N, D, d and P are recovered from the
    axle list, and the number of axles 2N + 14 and the length 37.525 + (N + 2) D follow.
(a') The real trains against their sources (section (a') below: IAPF-07 Appendix C.2 tables,
    the AVE S-103 car description, and independent car dimensions).
(b) ttbpipe's structure model (Craig-Bampton girder, Zhai explicit step) under HSLM-A trains on a
    bare 32 m girder (n0 = 4 Hz, 1 % damping) against an independent modal superposition of
    moving constant forces: w(x, t) = sum_n q_n(t) sin(n pi x/L) with
    q_n'' + 2 zeta w_n q_n' + w_n^2 q_n = (2/(m L)) sum_k P_k sin(n pi x_k(t)/L) for the axles
    k on the span, w_n = (n pi/L)^2 sqrt(EI/m), integrated exactly for a force linear within
    each step (Duhamel's integral in recurrence form: Nigam & Jennings 1969; Chopra, Dynamics of
    Structures, 4th ed., section 5.2), the modes below the structure model's cut-off (120 Hz:
    n = 1..5). Peak midspan deflection and acceleration at every speed within 5 %.
(c) Resonance at V = n0 D / i (i = 1, 2) and cancellation: the first-mode response of a train of
    loads at spacing lambda = V/n0 carries the factor
    A(L/lambda) = |cos(pi L/lambda)| 2 (2L/lambda) / |(2L/lambda)^2 - 1|
    (ERRI D 214/RP 9 (1999), DER method, written there as A(K) = K/(1-K^2) sqrt(2(1+cos(pi/K)))
    with K = lambda/(2L); Fryba, Dynamics of Railway Bridges, 1996): at resonance, lambda = D,
    the response vanishes where L/D = i + 1/2 (i >= 1) and the resonant peak acceleration is
    proportional to A(L/D)/L at equal n0, m and damping.
"""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lfilter

from ttbpipe.cli import main
from ttbpipe.simulation.config import load_case
from ttbpipe.simulation.moving_load_case import run_moving_loads
from ttbpipe.structure import build_structure
from ttbpipe.structure.moving_loads import build_loads, simulate
from ttbpipe.trains import get_train, train_names

CONFIG = Path(__file__).resolve().parents[1] / "config" / "validation"

#: EN 1991-2:2003, Annex E, Table E.1: N intermediate coaches, coach length D (m), bogie axle
#: spacing d (m), point force P (kN).
TABLE_E1 = {
    "HSLM-A1": (18, 18.0, 2.0, 170.0),
    "HSLM-A2": (17, 19.0, 3.5, 200.0),
    "HSLM-A3": (16, 20.0, 2.0, 180.0),
    "HSLM-A4": (15, 21.0, 3.0, 190.0),
    "HSLM-A5": (14, 22.0, 2.0, 170.0),
    "HSLM-A6": (13, 23.0, 2.0, 180.0),
    "HSLM-A7": (13, 24.0, 2.0, 190.0),
    "HSLM-A8": (12, 25.0, 2.5, 190.0),
    "HSLM-A9": (11, 26.0, 2.0, 210.0),
    "HSLM-A10": (11, 27.0, 2.0, 210.0),
}
#: EN 1991-2:2003, Figure E.1: power car axles, gap power car - end coach (m).
POWER_CAR = [0.0, 3.0, 14.0, 17.0]
GAP = 3.525

# The girder of (b) and (c): 32 m, m = 2.0e4 kg/m, n0 = 4 Hz, 1 % damping.
L, E, MU, N0, ZETA = 32.0, 3.45e10, 2.0e4, 4.0, 0.01
DT = 5.0e-4
MONITOR = [{"name": "mid", "kind": "girder", "span": 0, "position": 0.5, "directions": ["z"],
            "quantities": ["displacement", "acceleration"]}]


def girder_EI(span, n0=N0, mu=MU):
    """EI giving first frequency n0 = pi/(2 L^2) sqrt(EI/m)."""
    return mu * (2.0 * n0 * span ** 2 / np.pi) ** 2


def girder_model(span=L):
    return build_structure({
        "layout": {"approach_length_m": 0.0, "spans_m": [span], "bridge_track": "none"},
        "girder": {"damping_ratio": ZETA, "mass_kg_m": MU, "Iy_m4": girder_EI(span) / E},
        "bearing": {"rigid": True}})


def ttbpipe_peaks(model, name, speed_kmh, span=L, dt=DT):
    """(peak downward midspan deflection m, peak |acceleration| m/s^2) from ttbpipe's model."""
    train = get_train(name)
    v = speed_kmh / 3.6
    loads = build_loads({"target": "girder",
                         "axle_train": {"train": name, "front_x0_m": 0.0, "speed_kmh": speed_kmh}},
                        model)
    table, _ = simulate(model, loads, dt, (train.length_m + span) / v + 1.0, MONITOR,
                        output_every=1)
    return float(-table["mid_z_disp_mm"].min() / 1e3), float(table["mid_z_acc_m_s2"].abs().max())


def modal_reference(positions, loads, v, span=L, n_modes=5, zeta=ZETA, dt=DT, x=None):
    """Midspan (or x) deflection (m, downward +) and acceleration histories of a simply supported
    Euler-Bernoulli girder under constant forces ``loads`` (N, downward) at ``positions`` behind
    the first (which enters at t = 0), speed v: modal superposition, each mode integrated exactly
    for a force linear within each step (Nigam-Jennings recurrence, run as a 2nd-order IIR
    filter: zero initial state, same recursion)."""
    x = span / 2 if x is None else x
    EI = girder_EI(span)
    t = np.arange(0.0, (positions[-1] + span) / v + 1.0 + dt, dt)
    n = np.arange(1, n_modes + 1)
    w_n = (n * np.pi / span) ** 2 * np.sqrt(EI / MU)
    force = np.zeros((n_modes, t.size))
    for xk, pk in zip(positions, loads):
        s = v * t - xk
        on = (s >= 0.0) & (s <= span)
        force[:, on] += pk * np.sin(np.outer(n, np.pi * s[on] / span))
    force *= 2.0 / (MU * span)
    phi_x = np.sin(n * np.pi * x / span)
    w_hist = np.zeros(t.size)
    a_hist = np.zeros(t.size)
    for j, w in enumerate(w_n):
        wd = w * np.sqrt(1 - zeta ** 2)
        e, s, c = np.exp(-zeta * w * dt), np.sin(wd * dt), np.cos(wd * dt)
        r = zeta / np.sqrt(1 - zeta ** 2)
        # q_k = A q + B q' + C F_{k-1} + D F_k;  q'_k = A1 q + B1 q' + C1 F_{k-1} + D1 F_k
        A, B = e * (r * s + c), e * s / wd
        C = (2 * zeta / (w * dt) + e * (((1 - 2 * zeta ** 2) / (wd * dt) - r) * s
                                        - (1 + 2 * zeta / (w * dt)) * c)) / w ** 2
        D = (1 - 2 * zeta / (w * dt) + e * ((2 * zeta ** 2 - 1) / (wd * dt) * s
                                            + 2 * zeta / (w * dt) * c)) / w ** 2
        A1, B1 = -e * w / np.sqrt(1 - zeta ** 2) * s, e * (c - r * s)
        C1 = (-1 / dt + e * ((w / np.sqrt(1 - zeta ** 2) + zeta / (dt * np.sqrt(1 - zeta ** 2))) * s
                             + c / dt)) / w ** 2
        D1 = (1 - e * (r * s + c)) / (w ** 2 * dt)
        den = [1.0, -(A + B1), A * B1 - B * A1]
        q = lfilter([D, C - B1 * D + B * D1, -B1 * C + B * C1], den, force[j])
        qd = lfilter([D1, A1 * D + C1 - A * D1, A1 * C - A * C1], den, force[j])
        qdd = force[j] - 2 * zeta * w * qd - w ** 2 * q
        w_hist += phi_x[j] * q
        a_hist += phi_x[j] * qdd
    return t, w_hist, a_hist


def reference_peaks(name, speed_kmh, span=L):
    train = get_train(name)
    _, w, a = modal_reference(train.positions_m, train.axle_loads_N, speed_kmh / 3.6, span)
    return float(w.max()), float(np.abs(a).max())


# --- (a) the axles against Table E.1 and Figure E.1 ------------------------------------------------

@pytest.mark.parametrize("name", list(TABLE_E1))
def test_hslm_axles_match_table_e1(name):
    N, D, d, P_kN = TABLE_E1[name]
    train = get_train(name)
    x, p = train.positions_m, train.axle_loads_N
    assert np.all(np.diff(x) > 0) and x[0] == 0.0
    assert np.all(p == P_kN * 1e3)                                   # P on every axle, in N
    np.testing.assert_allclose(x[:4], POWER_CAR, atol=1e-12)         # leading power car
    np.testing.assert_allclose(x[-1] - x[::-1][:4], POWER_CAR, atol=1e-9)   # trailing, mirrored
    assert x[4] - x[3] == pytest.approx(GAP)
    assert x[5] - x[4] == pytest.approx(d)                            # end coach bogie
    pairs = x[6:-6].reshape(-1, 2)                                   # articulated bogies
    np.testing.assert_allclose(pairs[:, 1] - pairs[:, 0], d, atol=1e-9)
    centres = pairs.mean(axis=1)
    np.testing.assert_allclose(np.diff(centres), D, atol=1e-9)       # coach length
    assert centres.size - 1 == N                                     # intermediate coaches
    assert centres[0] - (x[3] + GAP / 2) == pytest.approx(D)          # end coach, coupling to bogie
    assert train.n_axles == 2 * N + 14
    assert train.length_m == pytest.approx(2 * (17.0 + GAP / 2) + (N + 2) * D)
    assert train.mass_kg == pytest.approx((2 * N + 14) * P_kN * 1e3 / 9.80665)


def test_library_names_and_errors():
    assert train_names() == list(TABLE_E1) + list(REAL_TRAINS)
    assert get_train("hslm-a7").name == "HSLM-A7"
    with pytest.raises(ValueError, match="HSLM-A1, HSLM-A2.*HSLM-A10"):
        get_train("HSLM-B1")


def test_cli_list_and_axles(tmp_path, capsys):
    assert main(["trains", "--list"]) == 0
    out = capsys.readouterr().out
    for name, (N, D, d, P) in TABLE_E1.items():
        assert any(line.split()[:2] == [name, str(2 * N + 14)] for line in out.splitlines())
    for name, n_axles in REAL_TRAINS.items():
        assert any(line.split()[:2] == [name, str(n_axles)] for line in out.splitlines())
    path = tmp_path / "ice2.csv"
    assert main(["trains", "ICE2", "--out", str(path)]) == 0
    table = pd.read_csv(path)
    assert len(table) == 56 and table["axle_load_kN"].iloc[[0, -1]].eq(195.0).all()
    assert table["position_m"].iloc[-1] == pytest.approx(350.52)
    path = tmp_path / "a2.csv"
    assert main(["trains", "HSLM-A2", "--out", str(path)]) == 0
    table = pd.read_csv(path)
    assert list(table.columns) == ["axle", "position_m", "axle_load_kN"]
    assert len(table) == 48 and table["axle_load_kN"].eq(200.0).all()
    np.testing.assert_allclose(table["position_m"], get_train("HSLM-A2").positions_m, atol=1e-4)
    assert main(["trains", "ICE-Z"]) == 1
    assert "HSLM-A10" in capsys.readouterr().err


# --- (a') real trains against their sources ---------------------------------------------------
#
# ICE2 and Talgo350: the axle tables of IAPF-07 Apendice C.2 (real_trains.yaml). Checked here
# against the compositions the source describes (power cars, coaches, their pitch) and, for the
# ICE 2 coaches, an independent source: coach length 26 400 mm (bahn-seminar.info, Baureihe 402
# (ICE 2), "Laenge der Mittelwagen/Steuerwagen"). The table's positions are given to 0.01 m:
# tolerance 0.011 m on every position.
# AVE-S103-8/-16: the car description of Goicolea (2014). Checked against an independent
# source of the same car bodies (ICE 3 / Velaro family, de.wikipedia "ICE 3": end car 25 835 mm,
# middle car 24 775 mm, bogie centre distance 17 375 mm), and the axle loads against the mass
# of every car (body + 2 bogies + 4 wheelsets: the loads must carry the whole mass).

REAL_TRAINS = {"ICE2": 56, "Talgo350": 40, "AVE-S103-8": 32, "AVE-S103-16": 64}
POS_TOL = 0.011


def test_ice2_against_iapf_composition():
    t = get_train("ICE2")
    x, P = t.positions_m, t.axle_loads_N / 1e3
    assert t.n_axles == 56 and t.length_m == pytest.approx(350.52)
    power = [0.0, 3.0, 11.46, 14.46]
    np.testing.assert_allclose(x[:4], power, atol=POS_TOL)
    np.testing.assert_allclose(x[-4:], t.length_m - np.array(power[::-1]), atol=POS_TOL)
    assert np.all(P[:4] == 195.0) and np.all(P[-4:] == 195.0) and np.all(P[4:-4] == 112.0)
    coach_axles = x[4:-4].reshape(12, 4)                      # 12 coaches of 4 axles
    np.testing.assert_allclose(coach_axles - coach_axles[:, :1], np.tile([0, 2.5, 19.0, 21.5],
                                                                         (12, 1)), atol=POS_TOL)
    pitch = np.diff(coach_axles[:, 0])
    np.testing.assert_allclose(pitch, 26.40, atol=POS_TOL)   # = the coach length, 26 400 mm
    assert t.parameters["D_m"] == pytest.approx(26.40)
    assert t.mass_kg == pytest.approx((8 * 195.0 + 48 * 112.0) * 1e3 / 9.80665)


def test_talgo350_against_iapf_composition():
    t = get_train("Talgo350")
    x, P = t.positions_m, t.axle_loads_N / 1e3
    assert t.n_axles == 40 and t.length_m == pytest.approx(356.05)
    assert np.all(P == 170.0)
    units = x.reshape(2, 20) - x.reshape(2, 20)[:, :1]        # two identical units of 20 axles
    np.testing.assert_allclose(units[1], units[0], atol=POS_TOL)
    u = units[0]
    np.testing.assert_allclose(u[:4], [0.0, 2.65, 11.0, 13.65], atol=POS_TOL)       # power car
    np.testing.assert_allclose(u[-4:] - u[-4], [0.0, 2.65, 11.0, 13.65], atol=POS_TOL)
    np.testing.assert_allclose(np.diff(u[5:15]), 13.14, atol=POS_TOL)  # single-axle coaches
    np.testing.assert_allclose(u[::-1][0] - u[::-1], u, atol=POS_TOL)  # symmetric unit
    assert t.parameters["D_m"] == pytest.approx(13.14)


def test_ave_s103_against_the_car_description_and_ice3_dimensions():
    from ttbpipe.trains.library import _read_yaml

    cars = _read_yaml("real_trains.yaml")["trains"]["AVE-S103-8"]["cars"]
    lengths = [c["front_m"] + c["bogie_centres_m"] + c["rear_m"] for c in cars]
    np.testing.assert_allclose(lengths, [25.835] + 6 * [24.775] + [25.835], atol=1e-9)
    assert all(c["bogie_centres_m"] == 17.375 for c in cars)
    t8, t16 = get_train("AVE-S103-8"), get_train("AVE-S103-16")
    x = t8.positions_m
    assert t8.n_axles == 32 and t16.n_axles == 64
    # first to last axle: the car lengths less each end's nose-to-first-axle distance
    assert t8.length_m == pytest.approx(sum(lengths) - 2 * (4.76 - 1.25))
    np.testing.assert_allclose(np.diff(x.reshape(8, 4), axis=1), np.tile([2.5, 14.875, 2.5],
                                                                          (8, 1)), atol=1e-9)
    np.testing.assert_allclose(np.diff(x[::4])[1:-1], 24.775, atol=1e-9)
    car_kg = [c["body_kg"] + 2 * c["bogie_kg"] + 4 * c["wheelset_kg"] for c in cars]
    assert t8.mass_kg == pytest.approx(sum(car_kg), rel=1e-12)
    np.testing.assert_allclose(t8.axle_loads_N.reshape(8, 4).sum(axis=1) / 9.80665, car_kg,
                               rtol=1e-12)
    # 16 cars: the second unit is the first, one train length (200.32 m over couplers) behind
    np.testing.assert_allclose(t16.positions_m[32:] - t16.positions_m[:32], sum(lengths),
                               atol=1e-9)
    np.testing.assert_allclose(t16.axle_loads_N, np.tile(t8.axle_loads_N, 2))


def test_real_train_on_the_structure_by_name():
    loads = build_loads({"target": "girder", "axle_train": {"train": "AVE-S103-16",
                                                            "speed_kmh": 300.0}}, girder_model())
    assert loads.n == 2 * 64
    assert -loads.F0[:, 0].sum() == pytest.approx(get_train("AVE-S103-16").total_load_N)


# --- (b) moving forces on the 32 m girder against the modal superposition -------------------------

def test_case_selects_train_by_name():
    """The shipped case: HSLM-A1 by name at V = n0 D = 259.2 km/h; whole histories."""
    case = load_case(CONFIG / "hslm_a1_girder_32m.yaml")
    model = build_structure(case["structure"])
    loads = build_loads(case["loads"], model)
    train = get_train("HSLM-A1")
    assert loads.n == 2 * train.n_axles                              # a wheel on each rail
    assert -loads.F0[:, 0].sum() == pytest.approx(train.total_load_N)
    table, summary = run_moving_loads(case)
    t = table["time_s"].to_numpy()
    w = -table["girder_mid_z_disp_mm"].to_numpy() / 1e3
    a = -table["girder_mid_z_acc_m_s2"].to_numpy()                  # downward positive
    t_ref, w_ref, a_ref = modal_reference(train.positions_m, train.axle_loads_N, 72.0)
    n = min(t.size, t_ref.size)
    np.testing.assert_allclose(t[:n], t_ref[:n], atol=1e-9)
    assert abs(w.max() - w_ref.max()) <= 0.05 * w_ref.max()
    assert abs(np.abs(a).max() - np.abs(a_ref).max()) <= 0.05 * np.abs(a_ref).max()
    assert np.max(np.abs(w[:n] - w_ref[:n])) <= 0.02 * w_ref.max()
    assert np.max(np.abs(a[:n] - a_ref[:n])) <= 0.05 * np.abs(a_ref).max()


def test_case_train_errors():
    model = girder_model()
    with pytest.raises(ValueError, match=r"loads.axle_train.train: unknown train 'X'.*HSLM-A10"):
        build_loads({"target": "girder", "axle_train": {"train": "X", "speed_kmh": 100}}, model)
    with pytest.raises(ValueError, match="remove wheel_load_N"):
        build_loads({"target": "girder", "axle_train": {"train": "HSLM-A1", "speed_kmh": 100,
                                                        "wheel_load_N": 8.5e4}}, model)


SWEEP_KMH = np.arange(120.0, 421.0, 15.0)


@pytest.mark.parametrize("name", ["HSLM-A1", "HSLM-A2", "HSLM-A4", "HSLM-A8", "HSLM-A10"])
def test_speed_sweep_against_modal_superposition(name):
    N, D, d, P = TABLE_E1[name]
    resonances = [N0 * D / i * 3.6 for i in (1, 2) if 120.0 <= N0 * D / i * 3.6 <= 420.0]
    speeds = np.sort(np.concatenate([SWEEP_KMH, resonances]))
    model = girder_model()
    rows = []
    for vk in speeds:
        w, a = ttbpipe_peaks(model, name, vk)
        w_ref, a_ref = reference_peaks(name, vk)
        rows.append((vk, w, w_ref, a, a_ref))
    r = np.array(rows)
    np.testing.assert_array_less(np.abs(r[:, 1] - r[:, 2]), 0.05 * r[:, 2])
    np.testing.assert_array_less(np.abs(r[:, 3] - r[:, 4]), 0.05 * r[:, 4])
    # the envelope's maximum is at a resonance speed n0 D / i (for HSLM-A4, L/D = 1.52, the
    # first mode's i = 1 resonance nearly cancels, (c), and i = 2 governs), well above the rest
    assert min(abs(r[np.argmax(r[:, 3]), 0] - v) for v in resonances) < 1e-9
    assert r[:, 3].max() > 2.0 * np.median(r[:, 3])


# --- (c) resonance and cancellation -----------------------------------------------------------

@pytest.mark.parametrize("name,i", [("HSLM-A1", 1), ("HSLM-A1", 2), ("HSLM-A10", 1),
                                    ("HSLM-A10", 2)])
def test_resonance_at_n0_D_over_i(name, i):
    """Over speeds 0.94-1.06 V_i (0.5 % steps) the peak acceleration is largest within 1.5 % of
    V_i = n0 D / i. Measured: at 1.000 V_1 for A1 and A10, 0.990 / 1.010 V_2 (A1 / A10): near
    the weaker i = 2 resonance the envelope is flat-topped over +-1 % (the finite train, the
    quasi-static part and the other harmonics add to the resonant build-up)."""
    D = TABLE_E1[name][1]
    v_res = N0 * D / i * 3.6
    model = girder_model()
    factors = np.linspace(0.94, 1.06, 25)
    acc = np.array([ttbpipe_peaks(model, name, f * v_res)[1] for f in factors])
    assert factors[np.argmax(acc)] == pytest.approx(1.0, abs=0.0151)
    assert acc.max() > 1.3 * max(acc[0], acc[-1])     # measured 1.47 (A10, i = 2) to 2.8


def dynamic_factor(ratio):
    """ERRI D 214 A(L/lambda) (see the module docstring)."""
    k = 2.0 * ratio
    return abs(np.cos(np.pi * ratio)) * 2.0 * k / abs(k * k - 1.0)


def test_cancellation_at_L_over_D_i_plus_half():
    """HSLM-A3 (D = 20 m) at V = n0 D = 80 m/s on girders of L = r D, n0 = 4 Hz, m, zeta fixed."""
    name, D = "HSLM-A3", TABLE_E1["HSLM-A3"][1]
    ratios = [1.0, 1.25, 1.5, 1.75, 2.0, 2.5]
    peak = {}
    for r in ratios:
        span = r * D
        peak[r] = ttbpipe_peaks(girder_model(span), name, N0 * D * 3.6, span=span)[1]
    # cancellation: L/D = 1.5 and 2.5 against their neighbours and the L = D resonance
    assert peak[1.5] < 0.2 * min(peak[1.25], peak[1.75])
    assert peak[2.5] < 0.1 * peak[2.0]
    assert peak[1.5] < 0.05 * peak[1.0]
    # elsewhere the resonant peak follows A(L/D)/L within 10 %
    scaled = [peak[r] * r * D / dynamic_factor(r) for r in (1.0, 1.25, 1.75, 2.0)]
    assert max(scaled) / min(scaled) < 1.10
