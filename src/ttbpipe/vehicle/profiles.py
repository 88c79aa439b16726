"""Wheel and rail cross-section profiles: reference definitions, package data, measured files.

A :class:`Profile` is a polyline in its own profile coordinates, SI units (m):

* ``lateral`` -- positive towards the FIELD side (away from the track centre), the same for a
  left or a right wheel/rail, so one profile serves both sides;
* ``vertical`` -- positive UP, as mounted. A rail's head is at z <= 0 below its crown; a wheel's
  tread surface is z = -(r - r_nominal): the taping line (nominal rolling circle) at z = 0 and
  the flange, of larger radius, below it (S1002 flange tip at z = -28 mm).

Wheel profiles have their origin at the taping line and carry ``flange_back`` (m): the lateral
coordinate of the flange back face (-70 mm for S1002). Rail profiles have their origin at the
crown of the upright (not inclined) rail.

Reference profiles (analytic definitions in code; :func:`write_reference_profiles` writes the
point files shipped as package data, ``ttbpipe/data/profiles/*.txt``, which
:func:`reference_profile` reads back):

* **S1002** wheel (EN 13715, the profile of UIC 510-2), the piecewise definition in the
  standard's profile coordinates: a straight field-side section A, the tread polynomial of
  degree 8 (section B), the flange-root polynomial of degree 7 (C), and arcs/lines D-H over the
  flange. Coefficients and section bounds as distributed by H. Netter (DLR Oberpfaffenhofen)
  and reproduced widely in public railway and numerical-analysis codes; this implementation
  evaluates them independently. Checked against the Manchester contact benchmark's S1002 point
  file (Shackleton & Iwnicki 2008; ``MBench_S1002_v3.prw`` as distributed with CONTACT,
  github.com/eve70a/CONTACT, examples/): largest vertical difference 2e-6 mm over its 399
  points (docs/contact_geometry.md, section 1).
* **60E1** rail (EN 13674-1, formerly UIC 60), head only: crown arc R300 to |y| = 20.456/2 mm,
  tangent arc R80 to |y| = 52.053/2 mm, tangent corner arc R13 down to where the tangent is the
  1:20 head flank, then the flank line down to where its R3 fillet with the 1:2.75 underside of
  the head (the line through (0, -51) mm) begins, 35.3 mm below the crown: below any wheel
  contact. Head width 2 x 36.00 mm at the end of the R13 arcs (14.3 mm below the crown).
  Dimensions of EN 13674-1 as reproduced in the open EN13674 package (github.com/rohrbecka/
  EN13674, Profiles/P60E1.swift); checked against the benchmark's ``MBench_UIC60_v3.prr``
  (inclined 1:40; largest normal distance 0.023 mm, rms 0.013 mm).

Not shipped, for want of a citable geometric definition found so far: the Chinese LMA wheel
(TB/T 449) and the CHN60 rail (TB/T 2344, GB/T 2585); measured or drawn point files of them can be
read with :func:`read_profile`.

Measured profiles: :func:`read_profile` reads two-column ``y z`` text/CSV files (MiniProf-like
exports, in mm) with checks on monotonic lateral order, units and point count.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

MM = 1e-3  # metres per millimetre

#: Fewest points a profile may have: a cubic parametric spline through fewer is not a profile.
MIN_POINTS = 10
#: Lateral extent (m) above which a file in "mm" is taken to be in metres or the other way round:
#: a wheel or rail head profile is 60-160 mm wide, so a file whose lateral span is below 0.5 (in
#: its own numbers) was written in metres.
_MIN_SPAN_MM = 0.5


@dataclass(frozen=True)
class Profile:
    """A wheel or rail cross-section profile (see the module docstring for the coordinates)."""

    name: str
    kind: str                      # "wheel" or "rail"
    lateral: np.ndarray            # m, towards the field side
    vertical: np.ndarray           # m, up
    source: str = ""
    flange_back: float | None = None   # wheels: lateral coordinate of the flange back face (m)
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.kind not in ("wheel", "rail"):
            raise ValueError(f"profile {self.name!r}: kind must be 'wheel' or 'rail', got {self.kind!r}")
        y = np.asarray(self.lateral, float)
        z = np.asarray(self.vertical, float)
        if y.shape != z.shape or y.ndim != 1:
            raise ValueError(f"profile {self.name!r}: lateral and vertical must be 1-D of equal length")
        if y.size < MIN_POINTS:
            raise ValueError(f"profile {self.name!r}: {y.size} points, at least {MIN_POINTS} needed")
        if not (np.all(np.isfinite(y)) and np.all(np.isfinite(z))):
            raise ValueError(f"profile {self.name!r}: non-finite coordinate")
        object.__setattr__(self, "lateral", y)
        object.__setattr__(self, "vertical", z)
        if self.kind == "wheel" and self.flange_back is None:
            object.__setattr__(self, "flange_back", float(y.min()))


# ---------------------------------------------------------------------------------------------
# S1002 (EN 13715)
# ---------------------------------------------------------------------------------------------
# In the standard's coordinates: S (mm) lateral from the taping line, positive towards the outer
# (field-side) face, the flange back at S = -70; F(S) (mm) the radius increase over the taping
# line. Section bounds, from the field side to the flange back:
_S1002_BOUNDS = (60.0, 32.15796, -26.0, -35.0, -38.426669071, -39.764473993, -49.662510381,
                 -62.764705882, -70.0)
# Section B (tread) F = sum b_k S^k, k = 0..8, with the signs of the standard's definition.
_S1002_B = (0.0, -3.358537058e-02, 1.565681624e-03, -2.810427944e-05, 5.844240864e-08,
            -1.562379023e-08, 5.309217349e-15, -5.957839843e-12, 2.646656573e-13)
# Section C (flange root) F = -sum c_k S^k, k = 0..7.
_S1002_C = (4.320221063e+03, 1.038384026e+03, 1.065501873e+02, 6.051367875, 2.054332446e-01,
            4.169739389e-03, 4.687195829e-05, 2.252755540e-07)
# Section A: F = 1.364323640 - 0.066666667 S (a 1:15 straight); section E: F = -93.576667419
# - 2.747477419 S (a straight); arcs: D concave F = 16.446 - sqrt(13^2 - (S + 26.210665)^2),
# F, G, H convex F = a + sqrt(R^2 - (S + c)^2) with (a, R, c) below.
_S1002_A = (1.364323640, -0.066666667)
_S1002_E = (-93.576667419, -2.747477419)
_S1002_D = (16.446, 13.0, 26.210665)
_S1002_ARCS = {"F": (8.834924130, 20.0, 58.558326413), "G": (16.0, 12.0, 55.0),
               "H": (9.519259302, 20.5, 49.5)}


def s1002_radius_increase(s_mm: np.ndarray) -> np.ndarray:
    """S1002 radius increase F(S) (mm) over the taping line at lateral S (mm), -70 <= S <= 60."""
    s = np.atleast_1d(np.asarray(s_mm, float))
    b = _S1002_BOUNDS
    if np.any((s > b[0] + 1e-9) | (s < b[-1] - 1e-9)):
        raise ValueError(f"S1002 is defined for {b[-1]} <= S <= {b[0]} mm")
    f = np.empty_like(s)

    def arc(sv, a, r, c, sign=1.0):
        return a + sign * np.sqrt(np.maximum(r * r - (sv + c) ** 2, 0.0))

    sections = [
        (b[1], b[0], lambda v: _S1002_A[0] + _S1002_A[1] * v),
        (b[2], b[1], lambda v: np.polynomial.polynomial.polyval(v, _S1002_B)),
        (b[3], b[2], lambda v: -np.polynomial.polynomial.polyval(v, _S1002_C)),
        (b[4], b[3], lambda v: arc(v, *_S1002_D, sign=-1.0)),
        (b[5], b[4], lambda v: _S1002_E[0] + _S1002_E[1] * v),
        (b[6], b[5], lambda v: arc(v, *_S1002_ARCS["F"])),
        (b[7], b[6], lambda v: arc(v, *_S1002_ARCS["G"])),
        (b[8] - 1e-9, b[7], lambda v: arc(v, *_S1002_ARCS["H"])),
    ]
    done = np.zeros(s.shape, bool)
    for lo, hi, fn in sections:
        sel = (s >= lo) & (s <= hi) & ~done
        f[sel] = fn(s[sel])
        done |= sel
    return f


def s1002_profile(step_mm: float = 0.1) -> Profile:
    """The S1002 wheel profile sampled every ``step_mm`` from the flange back to the field side."""
    s = np.unique(np.round(np.concatenate([np.arange(-70.0, 60.0, step_mm), _S1002_BOUNDS]), 6))
    return Profile("s1002", "wheel", s * MM, -s1002_radius_increase(s) * MM,
                   source=_SOURCES["s1002"], flange_back=-70.0 * MM)


# ---------------------------------------------------------------------------------------------
# 60E1 (EN 13674-1), head
# ---------------------------------------------------------------------------------------------
_60E1_R = (300.0, 80.0, 13.0)               # crown, intermediate and corner radii (mm)
_60E1_ARC_ENDS = (20.456 / 2.0, 52.053 / 2.0)  # lateral ends of the R300 and R80 arcs (mm)
_60E1_FLANK = 1.0 / 20.0                    # head flank inclination to the vertical
_60E1_UNDERSIDE = (-51.0, 1.0 / 2.75)       # underside of the head: z = -51 + |y| / 2.75 (mm)
_60E1_FILLET = 3.0                          # flank-underside fillet radius (mm)


def rail_60e1_half(step_mm: float = 0.1) -> tuple[np.ndarray, np.ndarray, dict]:
    """Field-side half of the 60E1 head (y >= 0, mm), from the crown down to the flank's end.

    Tangent-continuous construction: each arc's centre lies on the normal of the previous one at
    the joint. The flank ends where it meets the R3 fillet to the underside of the head (35.3 mm
    below the crown); the fillet, which turns back under the head, is not part of the running
    profile (no wheel reaches it) and is left out so that the lateral coordinate stays monotonic.
    Returns y, z and the joint points (for the docs and tests).
    """
    r1, r2, r3 = _60E1_R
    c1 = np.array([0.0, -r1])
    # joint 1 on R300 at y = 10.228
    a1 = np.arcsin(_60E1_ARC_ENDS[0] / r1)                 # angle from the vertical
    p1 = c1 + r1 * np.array([np.sin(a1), np.cos(a1)])
    c2 = p1 - r2 * np.array([np.sin(a1), np.cos(a1)])
    a2 = np.arcsin((_60E1_ARC_ENDS[1] - c2[0]) / r2)
    p2 = c2 + r2 * np.array([np.sin(a2), np.cos(a2)])
    c3 = p2 - r3 * np.array([np.sin(a2), np.cos(a2)])
    # the R13 arc ends where its outward normal is perpendicular to the flank direction
    flank_dir = np.array([_60E1_FLANK, -1.0]) / np.hypot(_60E1_FLANK, 1.0)   # going down
    n3 = np.array([-flank_dir[1], flank_dir[0]])                              # outward normal
    a3 = np.arctan2(n3[0], n3[1])
    p3 = c3 + r3 * n3
    # fillet R3 between the flank line (through p3, direction flank_dir) and the underside line
    u0, u_slope = _60E1_UNDERSIDE
    und_dir = np.array([-1.0, -u_slope]) / np.hypot(1.0, u_slope)     # towards the web, down
    und_pt = np.array([0.0, u0])
    # the fillet centre is offset by R inwards from both lines
    n_flank_in = -n3
    n_und_in = np.array([-und_dir[1], und_dir[0]])
    if n_und_in[1] < 0:                                      # inwards = up into the head
        n_und_in = -n_und_in
    # solve p3 + t flank_dir + R n_flank_in = und_pt + u und_dir + R n_und_in
    lhs = np.column_stack([flank_dir, -und_dir])
    rhs = und_pt + _60E1_FILLET * n_und_in - p3 - _60E1_FILLET * n_flank_in
    t, _ = np.linalg.solve(lhs, rhs)
    p4 = p3 + t * flank_dir                                  # flank-fillet tangent point
    c4 = p4 + _60E1_FILLET * n_flank_in
    p5 = c4 - _60E1_FILLET * n_und_in                        # fillet-underside tangent point
    # polyline: angles measured from the vertical (sin -> y, cos -> z)
    parts_y, parts_z = [], []
    for c, r, b0, b1 in ((c1, r1, 0.0, a1), (c2, r2, a1, a2), (c3, r3, a2, a3)):
        n = max(2, int(np.ceil((b1 - b0) * r / step_mm)) + 1)
        b = np.linspace(b0, b1, n)
        parts_y.append(c[0] + r * np.sin(b))
        parts_z.append(c[1] + r * np.cos(b))
    n = max(2, int(np.ceil(t / step_mm)) + 1)
    tt = np.linspace(0.0, t, n)
    parts_y.append(p3[0] + tt * flank_dir[0])
    parts_z.append(p3[1] + tt * flank_dir[1])
    y = np.concatenate(parts_y)
    z = np.concatenate(parts_z)
    keep = np.concatenate([[True], np.hypot(np.diff(y), np.diff(z)) > 1e-9])
    joints = {"r300_r80": p1, "r80_r13": p2, "r13_flank": p3, "flank_fillet": p4,
              "fillet_underside": p5, "fillet_centre": c4}
    return y[keep], z[keep], joints


def rail_60e1_profile(step_mm: float = 0.1) -> Profile:
    """The 60E1 rail head (both halves, symmetric), upright, origin at the crown."""
    y, z, _ = rail_60e1_half(step_mm)
    yy = np.concatenate([-y[:0:-1], y])
    zz = np.concatenate([z[:0:-1], z])
    return Profile("60e1", "rail", yy * MM, zz * MM, source=_SOURCES["60e1"])


# ---------------------------------------------------------------------------------------------
# Test profiles with exact answers
# ---------------------------------------------------------------------------------------------
def cone_wheel_profile(conicity: float, half_width_mm: float = 60.0, flange_back_mm: float = -70.0,
                       step_mm: float = 0.1) -> Profile:
    """A conical tread without flange: z = conicity * y (radius falls towards the field side)."""
    s = np.arange(flange_back_mm, half_width_mm + step_mm / 2, step_mm)
    return Profile(f"cone_{conicity:g}", "wheel", s * MM, conicity * s * MM,
                   source="test profile: straight cone", flange_back=flange_back_mm * MM)


def crown_rail_profile(radius_mm: float = 10.0, depth_mm: float = 20.0,
                       step_mm: float = 0.02) -> Profile:
    """A narrow rail: a circular crown of radius ``radius_mm`` over +-60 degrees, continued by its
    tangents down to ``depth_mm`` below the crown (deep enough for a gauge point at 14 mm)."""
    a = np.pi / 3
    ang = np.linspace(-a, a, int(np.ceil(2 * a * radius_mm / step_mm)) + 1)
    y = radius_mm * np.sin(ang)
    z = radius_mm * (np.cos(ang) - 1.0)
    t = np.linspace(0.0, (depth_mm + z[-1]) / np.sin(a), 200)[1:]
    ty, tz = y[-1] + t * np.cos(a), z[-1] - t * np.sin(a)
    y = np.concatenate([-ty[::-1], y, ty])
    z = np.concatenate([tz[::-1], z, tz])
    return Profile(f"crown_r{radius_mm:g}", "rail", y * MM, z * MM,
                   source="test profile: circular crown with tangent flanks")


# ---------------------------------------------------------------------------------------------
# Package data and measured files
# ---------------------------------------------------------------------------------------------
_REFERENCE = {"s1002": s1002_profile, "60e1": rail_60e1_profile}
_SOURCES = {"s1002": "EN 13715 S1002, piecewise definition (DLR / H. Netter coefficients)",
            "60e1": "EN 13674-1 60E1 head: R300/R80/R13 arcs, 1:20 flanks to the R3 fillets"}
_ALIASES = {"uic60": "60e1", "s1002": "s1002", "60e1": "60e1"}


def reference_profile_names() -> list[str]:
    return sorted(_REFERENCE)


def write_reference_profiles(directory: str | Path, step_mm: float = 0.1) -> list[Path]:
    """Write the analytic reference profiles as point files (mm), one per profile.

    This is how ``src/ttbpipe/data/profiles/*.txt`` were made
    (``python -c "from ttbpipe.vehicle.profiles import write_reference_profiles as w;
    w('src/ttbpipe/data/profiles')"``); a test checks that the shipped files equal the analytic
    definitions. Coordinates to 1e-9 mm: the contact radii come from the second derivative of a
    spline through the points, which rounding to 1e-6 mm at a 0.1 mm step would spoil (R300 read
    as 312 mm).
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    out = []
    for name, make in _REFERENCE.items():
        p = make(step_mm)
        header = [f"ttbpipe reference profile {name} ({p.kind})", f"source: {p.source}",
                  "columns: lateral_mm (towards the field side), vertical_mm (up)",
                  f"generated by ttbpipe.vehicle.profiles.write_reference_profiles, step {step_mm} mm"]
        if p.kind == "wheel":
            header.append(f"flange_back_mm: {p.flange_back / MM:.6f}")
        path = directory / f"{name}.txt"
        np.savetxt(path, np.column_stack([p.lateral / MM, p.vertical / MM]), fmt="%.9f",
                   header="\n".join(header))
        out.append(path)
    return out


def reference_profile(name: str) -> Profile:
    """A shipped reference profile by name (``s1002``, ``60e1``; alias ``uic60``)."""
    key = _ALIASES.get(name.lower().replace("-", "").replace(" ", ""))
    if key is None:
        raise ValueError(f"unknown reference profile {name!r}; shipped: {reference_profile_names()}"
                         " (LMA and CHN60 are not shipped: read a point file with read_profile)")
    res = resources.files("ttbpipe").joinpath("data", "profiles", f"{key}.txt")
    with resources.as_file(res) as path:
        p = read_profile(path, kind="wheel" if key == "s1002" else "rail", name=key)
    return Profile(p.name, p.kind, p.lateral, p.vertical, flange_back=p.flange_back,
                   source=f"{_SOURCES[key]} (ttbpipe/data/profiles/{key}.txt)")


def profile_by_name_or_path(text: str, kind: str) -> Profile:
    """A shipped reference profile by name, or a measured profile file (a path with a suffix or
    an existing file) read with :func:`read_profile` as a ``kind`` (wheel | rail)."""
    path = Path(str(text))
    if path.suffix or path.exists():
        return read_profile(path, kind=kind)
    return reference_profile(str(text))


_NUM = re.compile(r"^[\s]*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")


def read_profile(path: str | Path, kind: str, *, name: str | None = None, units: str = "mm",
                 mirror: bool = False, flange_back_mm: float | None = None) -> Profile:
    """Read a measured or drawn profile: two columns, lateral y and vertical z.

    Accepted: whitespace- or comma-separated numbers, or semicolon-separated ones with decimal
    commas (``-12,5;3,25``, European CSV); lines starting with ``#``, ``!``,
    ``%`` or a non-numeric header are skipped; a ``flange_back_mm: X`` comment sets the wheel's
    flange back. Coordinates as described in the module docstring (y towards the field side, z
    up; ``mirror=True`` flips y for files written with y towards the track centre).
    ``flange_back_mm`` (profile coordinates) overrides the file's comment; without either, a
    wheel's flange back is its smallest lateral coordinate.

    Errors (ValueError, naming the file): fewer than :data:`MIN_POINTS` points; a row without
    two numbers; a lateral coordinate that is not strictly monotonic (a profile must be a
    single-valued trace from one side to the other: re-order or remove the loop); a lateral span
    that contradicts ``units`` (a profile in "mm" spanning less than 0.5, i.e. written in
    metres, or one in "m" spanning more than 0.5, i.e. written in mm).
    """
    path = Path(path)
    rows = []
    flange_back = None
    with open(path, encoding="utf-8", errors="replace") as fh:
        for lineno, line in enumerate(fh, 1):
            text = line.strip()
            if not text:
                continue
            if text[0] in "#!%":
                m = re.search(r"flange_back_mm:\s*([-+0-9.eE]+)", text)
                if m and flange_back is None:
                    flange_back = float(m.group(1))
                continue
            if not _NUM.match(text):
                if rows:
                    raise ValueError(f"{path}:{lineno}: non-numeric row after the data started: {text!r}")
                continue                                 # a header line
            if ";" in text:                              # European CSV: ';' columns, ',' decimals
                parts = [p.strip().replace(",", ".") for p in text.split(";") if p.strip()]
            else:
                parts = [p for p in re.split(r"[,\s]+", text) if p]
            try:
                vals = [float(p) for p in parts[:2]]
            except ValueError:
                raise ValueError(f"{path}:{lineno}: expected two numbers (y z), got {text!r}") from None
            if len(vals) < 2:
                raise ValueError(f"{path}:{lineno}: expected two numbers (y z), got {text!r}")
            rows.append(vals)
    if len(rows) < MIN_POINTS:
        raise ValueError(f"{path}: {len(rows)} profile points, at least {MIN_POINTS} needed")
    data = np.asarray(rows)
    y, z = data[:, 0], data[:, 1]
    span = float(np.ptp(y))
    if units == "mm":
        if span < _MIN_SPAN_MM:
            raise ValueError(f"{path}: lateral span {span:g} is too small for millimetres (a profile is"
                             " 60-160 mm wide); the file looks like metres: pass units='m'")
        scale = MM
    elif units == "m":
        if span > _MIN_SPAN_MM:
            raise ValueError(f"{path}: lateral span {span:g} is too large for metres; the file looks"
                             " like millimetres: pass units='mm'")
        scale = 1.0
    else:
        raise ValueError(f"units must be 'mm' or 'm', got {units!r}")
    dy = np.diff(y)
    if not (np.all(dy > 0) or np.all(dy < 0)):
        bad = int(np.argmax(dy <= 0) if dy[0] > 0 else np.argmax(dy >= 0)) + 1
        raise ValueError(f"{path}: the lateral coordinate is not strictly monotonic (row {bad + 1} of"
                         f" the data, y = {y[bad]:g} after {y[bad - 1]:g}); a profile must run from"
                         " one side to the other without reversing")
    fb = None                                            # flange back in m, profile coordinates
    if flange_back_mm is not None:
        fb = flange_back_mm * MM
    elif flange_back is not None:                        # the file's comment, mm, file coordinates
        fb = (-flange_back if mirror else flange_back) * MM
    if mirror:
        y = -y
    if y[0] > y[-1]:
        y, z = y[::-1], z[::-1]
    return Profile(name or path.stem, kind, y * scale, z * scale, source=str(path), flange_back=fb)
