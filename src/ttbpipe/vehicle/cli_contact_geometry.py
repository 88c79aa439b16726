"""``ttbpipe contact-geometry --wheel s1002 --rail 60e1 --out TABLE.parquet``: contact geometry table.

One row per wheelset lateral displacement (``lateral_displacement_mm``, + left) with the
wheelset roll and height change and, for each wheel, rolling radius, contact angle, contact
positions on wheel, rail and in the track, the transverse radii of wheel and rail and the
wheel's rolling-direction radius, and the second (two-point) contact; column units in the names
(docs/contact_geometry.md). Prints the EN 15302 equivalent conicity at the amplitudes asked for
(default 3 mm). ``--wheel``/``--rail`` take a shipped reference profile name (s1002; 60e1 or
uic60) or a two-column y z file in mm (docs/contact_geometry.md, section 1).

Exit status 1, nothing written, on an unreadable profile or a pair that does not form a wheelset
on the track (message on stderr).
"""

from __future__ import annotations

import argparse
import logging
import sys

log = logging.getLogger(__name__)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from .contact_geometry import BENCHMARK_WHEEL_RADIUS, GAUGE_HEIGHT, STANDARD_FLANGE_BACK, STANDARD_GAUGE

    parser.add_argument("--wheel", required=True,
                        help="wheel profile: s1002, or a y z file (mm, y towards the field side,"
                             " z up, origin at the taping line)")
    parser.add_argument("--rail", required=True,
                        help="rail profile: 60e1 (alias uic60), or a y z file (mm, origin at the crown)")
    parser.add_argument("--wheel-right", default=None,
                        help="right wheel profile if it differs from --wheel (a measured pair)")
    parser.add_argument("--rail-right", default=None,
                        help="right rail profile if it differs from --rail")
    parser.add_argument("--inclination", default="1:40", help="rail inclination: 1:20, 1:40, none")
    parser.add_argument("--gauge-mm", type=float, default=STANDARD_GAUGE * 1e3,
                        help=f"track gauge, measured {GAUGE_HEIGHT * 1e3:g} mm below the rail top (mm)")
    parser.add_argument("--flange-back-mm", type=float, default=STANDARD_FLANGE_BACK * 1e3,
                        help="distance between the wheels' flange backs (mm)")
    parser.add_argument("--nominal-radius-mm", type=float, default=BENCHMARK_WHEEL_RADIUS * 1e3,
                        help="wheel radius at the taping line (mm)")
    parser.add_argument("--nominal-radius-right-mm", type=float, default=None,
                        help="right wheel radius at the taping line if it differs (mm)")
    parser.add_argument("--y-max-mm", type=float, default=10.0,
                        help="largest lateral displacement (mm); the table runs from -y_max to y_max")
    parser.add_argument("--step-mm", type=float, default=0.1, help="lateral displacement step (mm)")
    parser.add_argument("--yaw-mrad", type=float, default=0.0,
                        help="wheelset yaw relative to the track (mrad): the contact on the yawed "
                             "wheels' trace lines, columns contact_lead_*_mm (EN 15302's conicity "
                             "is defined at zero yaw)")
    parser.add_argument("--two-point-tol-mm", type=float, default=0.05,
                        help="gap within which a second local gap minimum is a second contact (mm)")
    parser.add_argument("--smoothing-mm", type=float, default=0.0,
                        help="rms deviation allowed to the smoothing spline through the profile"
                             " points (mm): about the measuring scatter for measured profiles"
                             " (e.g. 0.002); 0 interpolates (reference profiles)")
    parser.add_argument("--amplitude-mm", type=float, nargs="+", default=[3.0],
                        help="amplitudes of the equivalent conicity (mm)")
    parser.add_argument("--out", required=True, help="output Parquet table")


def _profile(text: str, kind: str):
    from .profiles import profile_by_name_or_path

    return profile_by_name_or_path(text, kind)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from ..io import write_table
    from .contact_geometry import ContactPair, equivalent_conicity, harmonic_conicity, parse_inclination
    from .profiles import MM

    try:
        wheel = _profile(args.wheel, "wheel")
        rail = _profile(args.rail, "rail")
        wheel_right = _profile(args.wheel_right, "wheel") if args.wheel_right else None
        rail_right = _profile(args.rail_right, "rail") if args.rail_right else None
        inclination = parse_inclination(args.inclination)
        if args.step_mm <= 0 or args.y_max_mm <= 0:
            raise ValueError("--step-mm and --y-max-mm must be positive")
        radius_right = None if args.nominal_radius_right_mm is None else args.nominal_radius_right_mm * MM
        pair = ContactPair(wheel, rail, wheel_right, rail_right, inclination=inclination,
                           gauge=args.gauge_mm * MM, nominal_radius_right=radius_right,
                           flange_back_distance=args.flange_back_mm * MM,
                           nominal_radius=args.nominal_radius_mm * MM,
                           two_point_tol=args.two_point_tol_mm * MM,
                           smoothing=args.smoothing_mm * MM)
        n = int(round(args.y_max_mm / args.step_mm))
        y = np.arange(-n, n + 1) * args.step_mm * MM
        table = pair.solve(y, yaw=args.yaw_mrad * 1e-3)
        yt = table["lateral_displacement_mm"].to_numpy() * MM
        dr = table["rolling_radius_difference_mm"].to_numpy() * MM
        conicity = {}
        for a in args.amplitude_mm:
            conicity[f"{a:g}"] = {"en15302_annex_b": equivalent_conicity(yt, dr, a * MM),
                                  "harmonic": harmonic_conicity(yt, dr, a * MM)}
    except (ValueError, OSError) as exc:
        print(f"ttbpipe contact-geometry: {exc}", file=sys.stderr)
        return 1
    config = {"wheel": args.wheel, "rail": args.rail, "wheel_right": args.wheel_right,
              "rail_right": args.rail_right,
              "nominal_radius_right_mm": args.nominal_radius_right_mm, "inclination": args.inclination,
              "gauge_mm": args.gauge_mm, "flange_back_mm": args.flange_back_mm,
              "nominal_radius_mm": args.nominal_radius_mm, "y_max_mm": args.y_max_mm,
              "step_mm": args.step_mm, "two_point_tol_mm": args.two_point_tol_mm,
              "smoothing_mm": args.smoothing_mm, "yaw_mrad": args.yaw_mrad}
    centred = table.attrs.get("centred", {})
    summary = {"equivalent_conicity": conicity,
               "centred_rolling_radius_left_mm": centred.get("rolling_radius_left_mm"),
               "centred_contact_position_wheel_left_mm": centred.get("contact_position_wheel_left_mm"),
               "wheel_source": wheel.source, "rail_source": rail.source}
    table.attrs = {}
    write_table(table, args.out, config=config, kind="contact_geometry", summary=summary)
    log.info("wrote %s (%d rows)", args.out, len(table))
    two = table["two_point_contact_left"].to_numpy() | table["two_point_contact_right"].to_numpy()
    if two.any():
        ys = table["lateral_displacement_mm"].to_numpy()[two]
        print(f"two-point contact at {two.sum()} of {len(table)} displacements "
              f"({ys.min():g} to {ys.max():g} mm)")
    for a, c in conicity.items():
        print(f"equivalent conicity at {a} mm amplitude: {c['en15302_annex_b']:.4f} "
              f"(EN 15302 Annex B); harmonic linearisation {c['harmonic']:.4f}")
    return 0
