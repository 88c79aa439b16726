"""The quasi-static flange climb on S1002 / 60E1 (1:40) against the angle of attack, for both
creep laws, and the flank's lateral creep force of Polach's method against FASTSIM.

    PYTHONPATH=src python benchmarks/flange_climb_creep_laws.py

Prints (docs/contact_geometry.md section 7):
1. per creep law (``kalker_she``, ``polach``) and angle of attack, the climbing Q/P (the largest
   H of the quasi-static path of tests/test_two_point_contact.py) for the flanging wheel free to
   turn and for the solid wheelset, with H, the displacement and the tread's normal force there;
2. on the flank at the Polach climb (its normal force, ellipse and Kalker coefficients from the
   zone table, spin creepage sin(delta)/r0, lateral creepage yaw cos(delta)), the lateral creep
   force over mu N of Polach (``_polach_forces``) and of FASTSIM (tests/test_creep_law.py).
Runs in about a minute on one core.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from test_creep_law import fastsim  # noqa: E402
from test_two_point_contact import _climb_path, nadal  # noqa: E402

from ttbpipe.vehicle.contact import (COL_ABSUM, COL_C11, COL_C22, COL_C23, COL_DELTA,  # noqa: E402
                                     COL_M, COL_N, _polach_forces, build_geometry)
from ttbpipe.vehicle.parameters import ContactParameters  # noqa: E402

YAWS_MRAD = (0.0, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 40.0)


def main() -> None:
    climbs = {}
    for law in ("kalker_she", "polach"):
        geom = build_geometry(ContactParameters(profile="profiles", creep_law=law))
        print(f"creep law {law}: Nadal (70 deg, mu {geom.friction}) = "
              f"{nadal(np.radians(70.0), geom.friction):.4f}")
        for yaw in YAWS_MRAD:
            line = f"  {yaw:4.1f} mrad:"
            for spin in ("wheel", "axle"):
                path = _climb_path(geom, 1e-3 * yaw, spin)
                k = int(np.argmax(path[:, 1]))
                y, h, qp, tread, flange = path[k, :5]
                climbs[(law, yaw, spin)] = (y, flange)
                line += (f"  {spin}: Q/P {qp:.4f} H {h / 1e3:.1f} kN at y {1e3 * y:.2f} mm "
                         f"(tread {tread / 1e3:.1f} kN, flange {flange / 1e3:.1f} kN)")
            print(line, flush=True)
    geom = build_geometry(ContactParameters(profile="profiles", creep_law="polach"))
    y, normal = climbs[("polach", 10.0, "wheel")]
    zone = geom.zones[0]
    row = np.array([np.interp(y, zone[:, 0], zone[:, c]) for c in range(zone.shape[1])])
    c = (3.0 * normal * (1 - geom.poisson ** 2)
         / (2.0 * geom.youngs_modulus * row[COL_ABSUM])) ** (1.0 / 3.0)
    g = geom.shear_modulus
    e = {"a": row[COL_M] * c, "b": row[COL_N] * c, "c11": row[COL_C11], "c22": row[COL_C22],
         "c23": row[COL_C23]}
    e.update(f11=g * e["a"] * e["b"] * e["c11"], f22=g * e["a"] * e["b"] * e["c22"],
             f23=g * (e["a"] * e["b"]) ** 1.5 * e["c23"])
    delta = row[COL_DELTA]
    phi = np.sin(delta) / geom.wheel_radius
    print(f"flank at the Polach climb (10 mrad): N {normal / 1e3:.1f} kN, delta "
          f"{np.degrees(delta):.1f} deg, a {1e3 * e['a']:.2f} mm, b {1e3 * e['b']:.2f} mm "
          f"(a/b {e['a'] / e['b']:.1f}; Kalker's table ends at 10), spin {phi:.3f} rad/m, "
          f"spin x a {phi * e['a']:.4f}")
    lim = geom.friction * normal
    for yaw in YAWS_MRAD:
        eta = 1e-3 * yaw * np.cos(delta)
        _, fp, _ = _polach_forces(normal, 0.0, eta, phi, e["f11"], e["f22"], e["f23"], e["a"],
                                  e["b"], geom.friction, 20.0, 1.0, 1.0, 1.0, 0.0)
        _, ff = fastsim(e, 0.0, eta, phi, load=normal, nx=300, ny=60)
        print(f"  {yaw:4.1f} mrad (lateral creepage {eta:.5f}): lateral creep force / mu N "
              f"Polach {abs(fp) / lim:.3f}, FASTSIM {abs(ff) / lim:.3f}")


if __name__ == "__main__":
    main()
