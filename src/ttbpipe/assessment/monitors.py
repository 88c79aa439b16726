"""The extra structure monitors a run needs for the EN 1990 A2 deck checks.

EN 1990 A2 A2.4.4.2.2 limits the twist of the track over a length of 3 m (gauge 1.435 m):
t = (z_left - z_right)(x) - (z_left - z_right)(x + 3 m). The default monitors of a run
(:func:`ttbpipe.structure.monitors.default_monitors`) record one rail at midspan only, so a run
whose deck twist is to be checked must add, for each pair of sections 3 m apart, the vertical
displacement of both rails: :func:`deck_check_monitors` returns those monitor specs in the public
format (docs/structure.md section 6: ``kind: rail``, ``rail`` 0 left / 1 right, ``x_m``,
``directions: [z]``, ``quantities: [displacement]``).

Sections: on every span at its start, its middle and its end (3 m inside the span), and across
every span joint and both abutments (1.5 m either side), where the girder end rotations make the
twist largest. A case lists them after the default monitors (a case's ``monitors:`` replaces the
default set): ``monitors: default_monitors(structure) + deck_check_monitors(structure)``, which
:func:`case_with_deck_monitors` and ``ttbpipe assess-monitors CASE.yaml --out CASE_DECK.yaml`` do.

Column of a monitor: ``twist_<where>_<a|b>_<left|right>_z_disp_mm`` with ``<where>`` ``spanS_start``,
``spanS_mid``, ``spanS_end`` or ``jointJ`` (joint 0 the first abutment); ``a`` the section at x,
``b`` the one at x + 3 m. :data:`TWIST_COLUMN` parses them.
"""

from __future__ import annotations

import copy
import re
from typing import Any, Mapping

#: Length over which the twist is measured (m), EN 1990 A2 A2.4.4.2.2.
TWIST_BASE_M = 3.0
#: Rail index of each side (docs/structure.md: rail 0 left, 1 right).
RAIL_OF_SIDE = {"left": 0, "right": 1}
TWIST_COLUMN = re.compile(r"^twist_(?P<where>.+)_(?P<end>[ab])_(?P<side>left|right)_z_disp_mm$")


def twist_sections(structure) -> list[tuple[str, float]]:
    """(where, x of section a) of every twist pair; section b is at x + 3 m."""
    out = []
    for s, red in enumerate(structure.spans):
        a, L = float(red.start_m), float(red.length_m)
        if L < TWIST_BASE_M:
            raise ValueError(f"span {s + 1} ({L} m) is shorter than the {TWIST_BASE_M} m twist base")
        out += [(f"span{s + 1}_start", a), (f"span{s + 1}_mid", a + 0.5 * (L - TWIST_BASE_M)),
                (f"span{s + 1}_end", a + L - TWIST_BASE_M)]
    joints = [float(r.start_m) for r in structure.spans]
    if structure.spans:
        last = structure.spans[-1]
        joints.append(float(last.start_m + last.length_m))
    x_min, x_max = structure.rail_x_range
    for j, xj in enumerate(joints):
        xa = xj - 0.5 * TWIST_BASE_M
        if xa >= x_min and xa + TWIST_BASE_M <= x_max:
            out.append((f"joint{j}", xa))
    return out


def deck_check_monitors(structure) -> list[dict[str, Any]]:
    """Monitor specs (public format) of both rails' vertical displacement at every twist section
    of ``structure`` (a :class:`ttbpipe.structure.StructureModel`); see the module docstring."""
    if structure.packed.n_rails == 0:
        raise ValueError("deck twist monitors need rails; the structure has none")
    specs = []
    for where, xa in twist_sections(structure):
        for end, x in (("a", xa), ("b", xa + TWIST_BASE_M)):
            for side, rail in RAIL_OF_SIDE.items():
                specs.append({"name": f"twist_{where}_{end}_{side}", "kind": "rail", "rail": rail,
                              "x_m": round(float(x), 6), "directions": ["z"],
                              "quantities": ["displacement"]})
    return specs


def case_with_deck_monitors(case: Mapping[str, Any]) -> dict[str, Any]:
    """A copy of ``case`` whose monitors are its own (or the structure's default ones) followed by
    :func:`deck_check_monitors` of its structure."""
    from ..simulation.setup import nominal_structure
    from ..structure.monitors import default_monitors

    out = copy.deepcopy(dict(case))
    structure = nominal_structure(out)   # on the case's layout: curves move the deck monitors
    base = list(out.get("monitors") or default_monitors(structure))
    names = {m.get("name") for m in base}
    extra = [m for m in deck_check_monitors(structure) if m["name"] not in names]
    out["monitors"] = base + extra
    return out
