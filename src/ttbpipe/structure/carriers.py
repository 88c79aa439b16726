"""Carriers of the random properties: parameter names, nominal values, factors, positions.

A carrier is what one value of a random field applies to: a rail element, a fastener (one seat
per rail), a slab element, a girder element. The random-field stage samples the fields at
:func:`carrier_positions` and the structure multiplies its nominal properties by them
(:func:`factored`, ``ttbpipe.structure.apply_factors``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Mapping

import numpy as np

from .layout import Layout

if TYPE_CHECKING:
    from .assembly import StructureModel

#: Parameter names per carrier kind (the random-field interface, ttbpipe.fields.groups).
CARRIER_PARAMETERS: dict[str, tuple[str, ...]] = {
    "rail_element": ("rail_E", "rail_mass", "rail_Iy", "rail_Iz"),
    "fastener": ("pad_kz", "pad_cz", "pad_ky", "pad_cy"),
    "slab_element": ("ca_kz", "ca_cz", "ca_ky", "ca_cy"),
    "girder_element": ("girder_E", "girder_mass", "girder_Iy", "girder_Iz"),
}
PARAMETER_CARRIER = {p: kind for kind, ps in CARRIER_PARAMETERS.items() for p in ps}


def nominal_properties(cfg: Mapping[str, Any], layout: Layout) -> dict[str, np.ndarray]:
    """Per-carrier nominal property arrays (SI), before random factors.

    Rail and fastener arrays have shape (2 n_tracks, n) (rail 2k left and 2k + 1 right of
    track k); slab (track after track) and girder arrays (n,).
    """
    r, f, ca, g = cfg["rail"], cfg["fastener"], cfg["ca"], cfg["girder"]
    n_rel = layout.rail_x.size - 1
    n_fas = layout.rail_x.size
    n_r = 2 * layout.n_tracks
    n_sel = layout.n_tracks * sum(u[1].size - 1 for u in layout.slab_units)
    n_gel = int(sum(layout.girder_n_el))
    full = lambda v, shape: np.full(shape, float(v))  # noqa: E731
    return {
        "rail_E": full(r["E_Pa"], (n_r, n_rel)), "rail_mass": full(r["mass_kg_m"], (n_r, n_rel)),
        "rail_Iy": full(r["Iy_m4"], (n_r, n_rel)), "rail_Iz": full(r["Iz_m4"], (n_r, n_rel)),
        "pad_kz": full(f["kz_N_m"], (n_r, n_fas)), "pad_cz": full(f["cz_Ns_m"], (n_r, n_fas)),
        "pad_ky": full(f["ky_N_m"], (n_r, n_fas)), "pad_cy": full(f["cy_Ns_m"], (n_r, n_fas)),
        "ca_kz": full(ca["kz_N_m2"], n_sel), "ca_cz": full(ca["cz_Ns_m2"], n_sel),
        "ca_ky": full(ca["ky_N_m2"], n_sel), "ca_cy": full(ca["cy_Ns_m2"], n_sel),
        "girder_E": full(g["E_Pa"], n_gel), "girder_mass": full(g["mass_kg_m"], n_gel),
        "girder_Iy": full(g["Iy_m4"], n_gel), "girder_Iz": full(g["Iz_m4"], n_gel),
    }


def factored(props: Mapping[str, np.ndarray], factors: Mapping[str, np.ndarray]) -> dict:
    """A new properties dict: ``props`` times the random-field ``factors`` (checked against the
    carriers: one value per carrier, positive and finite; see :func:`apply_factors`)."""
    out = {k: np.array(v, dtype=float, copy=True) for k, v in props.items()}
    for name, fac in factors.items():
        if name not in PARAMETER_CARRIER:
            raise ValueError(f"factor {name!r}: unknown parameter; expected one of "
                             f"{sorted(PARAMETER_CARRIER)}")
        fac = np.asarray(fac, dtype=float)
        base = out[name]
        n = base.shape[-1]
        n_r = base.shape[0] if base.ndim == 2 else 1
        if base.ndim == 2 and fac.size == n_r * n:
            fac = fac.reshape(n_r, n)
        elif fac.shape != (n,) and not (base.ndim == 2 and fac.shape == base.shape):
            raise ValueError(f"factor {name!r}: {fac.size} values, but the structure has {n} "
                             f"{PARAMETER_CARRIER[name]} carriers"
                             + (f" (or {n_r * n} for its {n_r} rails, rail after rail)"
                                if base.ndim == 2 else "")
                             + "; sample the field at carrier_positions(model)")
        if not np.all(np.isfinite(fac)) or np.any(fac <= 0):
            bad = int(np.sum(~np.isfinite(fac) | (fac <= 0)))
            raise ValueError(f"factor {name!r}: {bad} non-positive or non-finite values; a "
                             "property factor must be > 0 (truncate the field's marginal)")
        out[name] = base * fac
    return out


def carrier_positions(model: "StructureModel") -> dict[str, np.ndarray]:
    """x (m) of every carrier, per kind, in the order factor arrays must follow.

    rail_element: element midpoints (shared by every rail); fastener: rail node positions (one
    seat per rail per position); slab_element: element midpoints of all slab units (track after
    track on a double-track deck); girder_element: element midpoints of each span's FE mesh,
    span after span.
    """
    lay = model.layout
    x = lay.rail_x
    girder = [s.node_x[:-1] + 0.5 * np.diff(s.node_x) for s in model.spans]
    return {
        "rail_element": 0.5 * (x[:-1] + x[1:]),
        "fastener": x.copy(),
        "slab_element": model.slab_elements.mean(axis=1) if model.slab_elements.size
        else np.zeros(0),
        "girder_element": np.concatenate(girder) if girder else np.zeros(0),
    }
