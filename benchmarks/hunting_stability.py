"""Hunting critical speeds of one car on rigid straight track: linear theory against the time loop.

Measurement for docs/vehicle.md section 10 (about 1 min on one core):

    NUMBA_NUM_THREADS=1 python benchmarks/hunting_stability.py [--quick] [--json OUT.json]

1. Linear critical speeds (ttbpipe.vehicle.hunting) of the default trailer car, whole car and
   one bogie under a fixed car body, on cones of conicity 0.04 (the default), 0.1, 0.2 and on
   S1002 / 60E1 at 1:40 (tangent slopes at y = 0, and quasi-linear slopes at amplitudes
   0.25-5 mm with the EN 15302 equivalent conicity).
2. Cones 0.04 and 0.2: the time loop's growth rate of a 0.5 mm disturbance of the leading
   wheelset (12 s, fitted over the second half) at speeds around the linear critical speed,
   against the linear least-damped eigenvalue; the speed where the growth rate changes sign.
3. S1002 / 60E1: the same with a 0.05 mm disturbance (stays on the tangent part of the table)
   around the tangent critical speed, and a stepwise ramp-down from a 2 mm disturbance at
   300 km/h (10 s per speed): the speed below which the limit cycle dies (the nonlinear
   critical speed) and the limit-cycle amplitudes, against the quasi-linear
   (equivalent-conicity) prediction.
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np
from scipy.optimize import minimize_scalar

from ttbpipe.simulation import hunting as sim
from ttbpipe.vehicle import hunting as lin
from ttbpipe.vehicle.contact import build_geometry
from ttbpipe.vehicle.model import build_train_model
from ttbpipe.vehicle.parameters import train_from_config

CONES = (0.04, 0.1, 0.2)
AMPLITUDES_MM = (0.25, 0.3, 0.35, 0.4, 0.45, 0.5, 0.6, 0.8, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0)


def statics(contact):
    train = train_from_config({"composition": ["trailer"], "contact": contact})
    model = build_train_model(train)
    return lin.car_statics(model, build_geometry(train.contact))


def linear(st, slopes, bodies=None, v_max=300.0):
    cs = lin.critical_speed(lambda v: lin.car_system(st, slopes, v, bodies=bodies), 5.0, v_max, 60)
    return {"speed_kmh": cs.speed_kmh, "frequency_hz": cs.frequency_hz,
            "mode": cs.mode.get("dominant_dofs")}


def growth_series(contact, st, slopes, speeds_kmh, duration_s, lateral_m):
    rows = []
    for v in speeds_kmh:
        run = sim.disturbed_run(sim.hunting_case(contact, v), duration_s, lateral_m)
        rate, freq = sim.growth_rate(run.time, run.lateral[:, 0], 0.5 * duration_s)
        mode = lin.least_damped(lin.car_system(st, slopes, v / 3.6), min_frequency_hz=1.0)
        rows.append({"speed_kmh": v, "sim_rate_1_s": rate, "sim_frequency_hz": freq,
                     "linear_rate_1_s": mode["real_1_s"],
                     "linear_frequency_hz": mode["frequency_hz"], "wall_s": run.wall_s})
    crossing = sim.zero_crossing([r["speed_kmh"] for r in rows], [r["sim_rate_1_s"] for r in rows])
    return rows, crossing


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="fewer speeds (about 1 min)")
    ap.add_argument("--json", help="write the results to this file")
    args = ap.parse_args()
    t0 = time.process_time()
    out = {"linear": {}, "cones": {}, "s1002": {}}

    print("1. linear critical speeds, one trailer car (km/h, Hz)")
    for lam in CONES:
        st = statics({"conicity": lam})
        sl = lin.contact_slopes(st.geom)
        car, bogie = linear(st, sl), linear(st, sl, bodies=(1, 3, 4))
        out["linear"][f"cone_{lam}"] = {"car": car, "bogie_fixed_body": bogie}
        print(f"  cone {lam}: car {car['speed_kmh']:.1f} ({car['frequency_hz']:.2f} Hz, "
              f"{car['mode']}); bogie, body fixed {bogie['speed_kmh']:.1f}")
    contact = {"profile": "profiles", "contact_points": 1}
    st = statics(contact)
    tangent = lin.contact_slopes(st.geom)
    res = {"amplitude_mm": None, "conicity": tangent.conicity,
           "contact_angle_slope_rad_m": tangent.contact_angle_slope,
           "car": linear(st, tangent), "bogie_fixed_body": linear(st, tangent, (1, 3, 4))}
    out["linear"]["s1002_tangent"] = res
    print(f"  S1002/60E1 tangent: lambda {tangent.conicity:.3f}, car {res['car']['speed_kmh']:.1f} "
          f"({res['car']['frequency_hz']:.2f} Hz); bogie {res['bogie_fixed_body']['speed_kmh']:.1f}")
    quasi = []
    for a in AMPLITUDES_MM:
        sl = lin.contact_slopes(st.geom, a * 1e-3)
        r = {"amplitude_mm": a, "conicity": sl.conicity,
             "contact_angle_slope_rad_m": sl.contact_angle_slope, "car": linear(st, sl),
             "bogie_fixed_body": linear(st, sl, (1, 3, 4))}
        quasi.append(r)
        print(f"  S1002/60E1 A = {a} mm: lambda_e {sl.conicity:.3f}, d delta/dy "
              f"{sl.contact_angle_slope:.1f}, car {r['car']['speed_kmh']:.1f} "
              f"({r['car']['frequency_hz']:.2f} Hz); bogie {r['bogie_fixed_body']['speed_kmh']:.1f}")
    out["linear"]["s1002_quasi_linear"] = quasi
    vmin = min(quasi, key=lambda r: r["car"]["speed_kmh"])
    best = minimize_scalar(
        lambda a: linear(st, lin.contact_slopes(st.geom, a * 1e-3))["speed_kmh"],
        bounds=(0.3, 0.45), method="bounded", options={"xatol": 1e-3})
    out["linear"]["s1002_quasi_linear_minimum"] = {"amplitude_mm": float(best.x),
                                                   "speed_kmh": float(best.fun)}
    print(f"  quasi-linear minimum: {best.fun:.1f} km/h at A = {best.x:.3f} mm")

    print("2. cones: time loop against linear theory (0.5 mm on the leading wheelset, 12 s)")
    for lam in (0.04, 0.2):
        st_c = statics({"conicity": lam})
        sl = lin.contact_slopes(st_c.geom)
        vc = out["linear"][f"cone_{lam}"]["car"]["speed_kmh"]
        factors = (0.97, 1.03) if args.quick else (0.95, 0.98, 1.0, 1.02, 1.05)
        rows, cross = growth_series({"conicity": lam}, st_c, sl,
                                    [round(f * vc, 1) for f in factors], 12.0, 5e-4)
        out["cones"][str(lam)] = {"linear_kmh": vc, "sim_crossing_kmh": cross, "rows": rows}
        for r in rows:
            print(f"  cone {lam} {r['speed_kmh']:.1f} km/h: growth rate {r['sim_rate_1_s']:+.4f} "
                  f"(linear {r['linear_rate_1_s']:+.4f}) 1/s, {r['sim_frequency_hz']:.3f} "
                  f"(linear {r['linear_frequency_hz']:.3f}) Hz")
        print(f"  cone {lam}: time loop crossing {cross:.1f} km/h, linear {vc:.1f} km/h "
              f"({100 * (cross / vc - 1):+.2f} %)")

    print("3. S1002/60E1 1:40")
    vt = res["car"]["speed_kmh"]
    factors = (0.98, 1.02) if args.quick else (0.96, 0.98, 1.0, 1.02, 1.04)
    rows, cross = growth_series(contact, st, tangent, [round(f * vt, 1) for f in factors], 12.0,
                                5e-5)
    out["s1002"]["small_disturbance"] = {"linear_kmh": vt, "sim_crossing_kmh": cross, "rows": rows}
    for r in rows:
        print(f"  {r['speed_kmh']:.1f} km/h, 0.05 mm: growth rate {r['sim_rate_1_s']:+.4f} (linear "
              f"{r['linear_rate_1_s']:+.4f}) 1/s")
    print(f"  small disturbance: time loop crossing {cross:.1f} km/h, tangent linear {vt:.1f} km/h")
    speeds = ([300, 260, 230, 220, 215, 210] if args.quick else
              [300, 280, 260, 250, 240, 230, 225, 222, 220, 219, 218, 217, 216, 215, 214, 213,
               212, 210, 205, 200])
    ramp = sim.ramp_down(contact, speeds, 10.0, 2e-3)
    out["s1002"]["ramp_down"] = ramp
    for r in ramp:
        # quasi-linear limit-cycle amplitude: the amplitude on the stable branch (above the
        # minimum) at which the quasi-linear critical speed equals this speed
        branch = [q for q in quasi if q["amplitude_mm"] >= vmin["amplitude_mm"]]
        ql = np.interp(r["speed_kmh"], [q["car"]["speed_kmh"] for q in branch],
                       [q["amplitude_mm"] for q in branch], left=np.nan)
        r["quasi_linear_amplitude_mm"] = float(ql)
        ws = 1e3 * np.asarray(r["wheelset_amplitudes_m"])
        print(f"  ramp-down {r['speed_kmh']:.0f} km/h: wheelset amplitudes "
              f"{' '.join(f'{a:.3f}' for a in ws)} mm (quasi-linear {ql:.2f} mm), "
              f"{r['frequency_hz']:.2f} Hz, rate {r['growth_rate_1_s']:+.2e} 1/s")
    alive = [r for r in ramp if r["amplitude_m"] >= 1e-5]
    dead = [r for r in ramp if r["amplitude_m"] < 1e-5]
    if alive and dead:
        out["s1002"]["nonlinear_critical_kmh"] = [dead[0]["speed_kmh"], alive[-1]["speed_kmh"]]
        print(f"  nonlinear critical speed between {dead[0]['speed_kmh']:.0f} and "
              f"{alive[-1]['speed_kmh']:.0f} km/h; quasi-linear minimum {best.fun:.1f} km/h")
    out["cpu_s"] = time.process_time() - t0
    print(f"CPU {out['cpu_s']:.0f} s")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=1, default=float)


if __name__ == "__main__":
    main()
