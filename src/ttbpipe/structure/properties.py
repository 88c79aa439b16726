"""Default properties of the track-bridge structure, each with its source.

Tags as in docs/reference/physics.md: [V] read in a public source, [M] standard literature
value not re-read at the source, [C] computed here from the others. All values SI.

The set is chosen to be coherent (Zeng et al. 2014 for fastener, slab, CA and girder; Hindawi SV
2020/6878252 for CHN60), see docs/structure.md section "Parameters". The CA mortar value is the
one point where sources disagree by two orders of magnitude (Zeng's CRTS I-like 60 MPa mortar vs
7-10 GPa quoted for CRTS II); we keep Zeng's, which belongs with the rest of this set.

Every section is a plain dict so that a case YAML overrides any key; :func:`resolve` merges a user
section into the defaults and rejects unknown keys with the full key path.
"""

from __future__ import annotations

import copy
from typing import Any, Mapping

#: CHN60 rail, one rail. [V: Hindawi SV 2020/6878252 tab 2] unless tagged otherwise.
RAIL = {
    "E_Pa": 2.059e11,                # Young's modulus
    "G_Pa": 7.9e10,                  # shear modulus of steel, not 2e11 (physics.md sec. 7 item 14)
    "mass_kg_m": 60.64,              # mass per unit length
    "Iy_m4": 3.217e-5,               # second moment for VERTICAL bending (about the y axis)
    "Iz_m4": 5.24e-6,                # second moment for LATERAL bending (about the z axis)
    "I0_m4": 3.741e-5,               # polar second moment (roll inertia = rho*I0 per metre)
    "density_kg_m3": 7860.0,
    "GK_Nm2": 1.9587e5,              # torsional stiffness G*K
    "head_height_m": 0.095,          # shear centre to rail-head top [M: CHN60 176 mm high, shear
                                     # centre ~ 81 mm above the foot]
    "foot_depth_m": 0.081,           # shear centre to rail foot (pad level) [M, as above]
    "foot_width_m": 0.150,           # CHN60 foot width [M]
    "rotary_inertia_scaling": 3.25,  # x HRZ lumped slope inertia m L^3/78 -> m L^3/24 (see docs)
}

#: Fasteners (rail pads), per rail seat. [V: Zeng 2014; DDNS 2015]
FASTENER = {
    "spacing_m": 0.63,               # [V] 0.629-0.65 m; one rail node per fastener
    "kz_N_m": 5.0e7,                 # vertical stiffness
    "cz_Ns_m": 3.625e4,              # vertical damping
    "ky_N_m": 3.0e7,                 # lateral stiffness
    "cy_Ns_m": 3.625e4,              # lateral damping [M: Zeng gives vertical only; same value]
    "rail_centre_distance_m": 1.505,  # 1435 mm gauge + CHN60 head width 70 mm [C]
}

#: Track slab on the bridge. CRTS II: 6.45 x 2.55 x 0.20 m, E 3.6e10 [V: physics.md section 6].
SLAB = {
    "type": "continuous",            # continuous (CRTS II, longitudinally connected) | discrete
    "unit_length_m": 6.45,           # discrete slabs: unit length (CRTS II 6.45 m, CRTS III 5.6 m)
    "joint_m": 0.05,                 # discrete slabs: gap between units
    "element_length_m": 2.52,        # slab beam element length (4 fastener bays; see docs)
    "width_m": 2.55,
    "thickness_m": 0.20,
    "E_Pa": 3.6e10,
    "poisson": 0.2,
    "density_kg_m3": 2500.0,         # -> 1275 kg/m [C]
    "rotary_inertia_scaling": 1.0,   # x HRZ m L^3/78 on the vertical-slope DOFs
    "lateral_rotary_inertia_scaling": 1.0,  # x HRZ on the lateral-slope DOFs (see docs)
}

#: CA mortar between slab and girder (or base), per metre of track. [V: Zeng 2014: 2 x 1.5e9 N/m2,
#: 2 x 8.3e4 N s/m2 for the 2-D "2x" convention -> whole slab 3.0e9 N/m2, 1.66e5 N s/m2 [C]].
CA = {
    "kz_N_m2": 3.0e9,
    "cz_Ns_m2": 1.66e5,
    "ky_N_m2": 3.0e9,                # lateral [M: not given by Zeng; taken equal to vertical,
    "cy_Ns_m2": 1.66e5,              # representing CA shear plus the lateral stoppers]
}

#: Simply supported box girder, 32 m class. [V: physics.md section 6] unless tagged otherwise.
GIRDER = {
    "E_Pa": 3.45e10,
    "poisson": 0.2,
    "mass_kg_m": 2.972e4,
    "Iy_m4": 12.744,                 # vertical bending ("I_v")
    "Iz_m4": 96.435,                 # lateral bending ("I_h")
    "J_m4": 22.650,                  # torsion constant [V: "girder, alternative" row]
    "area_m2": 8.8889,               # [V: "girder, alternative" row], for the roll inertia
    # damping (ttbpipe.structure.damping): None -> EN 1991-2 Table 6.6 by span length and
    # construction (1.0 % for a prestressed span >= 20 m) [V]; the seed paper's value is 0.05
    # with Rayleigh damping (eq. 18) [V]
    "damping_ratio": None,
    "damping_model": "modal",        # modal: every kept span mode gets the ratio | rayleigh
    "construction": "prestressed_concrete",  # steel_composite | reinforced_concrete
    "additional_damping": False,     # EN 1991-2 eq. 6.13 (moving-load analyses of L < 30 m)
    "rayleigh_frequencies_hz": None,  # omega_1, omega_2 of eq. 18; None -> first two span modes
    "element_length_m": 1.0,         # FE mesh of each span used to compute its modes
    "max_mode_frequency_hz": 120.0,  # fixed-interface modes kept per span (see docs)
    "min_modes_per_direction": 1,
    "deck_height_m": 1.1,            # girder shear centre to top of deck (CA level) [M]
    # lateral position of the track's centre line (midway between the rails) from the girder's
    # shear centre, + to the left (rail 0's side): the seed paper's eq. 24 term B_r - b_s/2;
    # about 2.5 m for each track of a double-track box girder [V]
    "track_offset_m": 0.0,
    # a double-track deck (layout.tracks: 2): one offset per track, track k's rails 2k, 2k+1;
    # null: 2.5 and -2.5 (tracks 5.0 m apart, TB 10621-2014 [M]); structure.layout.track_offsets
    "track_offsets_m": None,
    # deck width (m): with a value, default monitors also at both deck edges (null: none)
    "deck_width_m": None,
    # where the straight girder's axis lies under a track curved in plan (simulation.layout):
    # split_versine (moved outwards by half the mid-span offset from the chord) | chord
    # (ttbpipe.structure.plan)
    "placement_on_curves": "split_versine",
}

#: Bearings: two per girder end at +- lateral_spacing/2. [V: k, c physics.md section 6]
BEARING = {
    "rigid": False,                  # True: ideal pinned supports (girder ends fixed)
    "kz_N_m": 6.0e9,
    "cz_Ns_m": 2.0e6,
    "ky_N_m": 6.0e9,
    "cy_Ns_m": 2.0e6,
    "lateral_spacing_m": 4.0,        # [M] typical 32 m box girder bearing spacing
    "height_m": 1.9,                 # girder shear centre to bearing plane [M]
}

#: Piers as 3-DOF mass-spring-dampers (y, z, roll) after paper eqs. 19-21 (longitudinal x replaced
#: by roll: the model carries no longitudinal loads). Defaults [C] from pier E 3.15e10, I 73.23 m4,
#: m 5.2e4 kg/m [V] for a 10 m cantilever: m_eq = 0.25 m H + cap; k_y = 3EI/H^3, k_z = EA/H with
#: A = m/rho = 20.8 m2; roll: k = EI/H with J = m_eq r^2 (r = 3 m).
PIER = {
    "mass_kg": 2.3e5,                # 0.25 * 5.2e4 * 10 + 1.0e5 kg cap [C, M]
    "roll_inertia_kgm2": 2.1e6,      # 2.3e5 * 3^2 [C]
    "ky_N_m": 6.9e9,                 # 3 * 3.15e10 * 73.23 / 10^3 [C]
    "kz_N_m": 6.55e10,               # 3.15e10 * 20.8 / 10 [C]
    "kroll_Nm_rad": 2.3e11,          # 3.15e10 * 73.23 / 10 [C]
    "cy_Ns_m": 2.0e6,                # [M] same order as the bearings
    "cz_Ns_m": 2.0e6,
    "croll_Nms_rad": 2.0e7,
    # a pier of this height (m, foundation to bearing plane) replaces the 3-DOF values above by
    # a cantilever of the section below, reduced at its top (ttbpipe.structure.pier); null keeps
    # the 3-DOF pier
    "height_m": None,
    "E_Pa": 3.15e10,                 # [V]
    "I_lateral_m4": 73.23,           # bending in the lateral plane [V: "I"]
    "area_m2": 20.8,                 # 5.2e4 kg/m / 2500 kg/m3 [C]
    "mass_kg_m": 5.2e4,              # [V]
    "cap_mass_kg": 1.0e5,            # pier cap at the top [M]
    "cap_roll_inertia_kgm2": 9.0e5,  # 1.0e5 * 3^2 [C, M]
    "damping_ratio": 0.05,           # every mode of the reduced pier [V: the paper's 0.05]
    "element_length_m": 1.0,
    "max_mode_frequency_hz": 120.0,  # fixed-interface modes kept, as for the girder
}

#: Ballasted track on subgrade, Zhai's model (Zhai, Wang & Lin 2004, JSV 270:673; Zhai's book)
#: [M]: sleeper rigid body (z, y, roll), two ballast blocks per sleeper (z), shear coupling between
#: neighbouring blocks, subgrade spring under each block.
BALLASTED = {
    "sleeper_mass_kg": 340.0,
    "sleeper_roll_inertia_kgm2": 191.0,   # 340 * 2.6^2 / 12 [C]
    "ballast_mass_kg": 683.0,             # one block under one rail seat
    "ballast_kz_N_m": 1.8e8,              # sleeper -> block, per rail seat
    "ballast_cz_Ns_m": 5.88e4,
    "ballast_ky_N_m": 5.0e7,              # sleeper lateral resistance, whole sleeper
    "ballast_cy_Ns_m": 4.0e4,
    "shear_k_N_m": 7.84e7,                # between neighbouring blocks
    "shear_c_Ns_m": 8.0e4,
    "subgrade_k_N_m": 6.5e7,              # under each block
    "subgrade_c_Ns_m": 3.1e4,
}

#: Slab track on subgrade: the same slab on a distributed foundation per metre of track, the CA
#: mortar in series with the subgrade under the concrete base (the base's own bending stiffness and
#: mass are neglected: a softer, conservative foundation; docs/structure.md section 1):
#: CA 3.0e9 N/m2 (Zeng 2014, as on the bridge) [V]; subgrade modulus K30 = 190 MPa/m, the minimum
#: for the subgrade bed surface layer under ballastless track (TB 10621-2014) [M], times the width
#: of the CRTS II hydraulically bonded base on subgrade, 2.95 m [M] -> 5.6e8 N/m2 [C];
#: series 1 / (1/3.0e9 + 1/5.6e8) = 4.72e8 N/m2 [C]. Lateral: taken equal to the vertical [M,
#: as the CA's]. Damping: Zhai's subgrade damping 3.1e4 N s/m per ballast block (BALLASTED) [M]
#: spread over the 0.63 m seat pitch, two blocks per seat: 2 x 3.1e4 / 0.63 = 9.84e4 N s/m2 [C].
SLAB_ON_SUBGRADE = {
    "foundation_kz_N_m2": 4.72e8,
    "foundation_cz_Ns_m2": 9.84e4,
    "foundation_ky_N_m2": 4.72e8,
    "foundation_cy_Ns_m2": 9.84e4,
}

#: Layout: approach, spans, approach along x (x = 0 at the start of the first approach).
LAYOUT = {
    "approach_length_m": 100.0,
    "spans_m": [32.0, 32.0, 32.0, 32.0, 32.0],
    "approach_track": "ballasted",   # ballasted (the paper) | slab | rigid (pads on rigid ground)
    "bridge_track": "slab",          # slab | rigid | none (girder only, no track: validation)
    # tracks side by side on the same girders, each with its own rails, pads, slab (CA to the
    # girder at its offset, girder.track_offsets_m) and approaches: 1 | 2
    "tracks": 1,
}

DEFAULTS: dict[str, Any] = {
    "layout": LAYOUT,
    "rail": RAIL,
    "fastener": FASTENER,
    "slab": SLAB,
    "ca": CA,
    "girder": GIRDER,
    "bearing": BEARING,
    "pier": PIER,
    "ballasted": BALLASTED,
    "slab_on_subgrade": SLAB_ON_SUBGRADE,
}


def resolve(config: Mapping[str, Any] | None, where: str = "structure") -> dict[str, Any]:
    """Defaults merged with a user ``structure:`` section; unknown keys raise ValueError."""
    out = copy.deepcopy(DEFAULTS)
    for section, values in (config or {}).items():
        if section not in out:
            raise ValueError(f"{where}.{section}: unknown section; expected one of {list(out)}")
        if values is None:
            continue
        if not isinstance(values, Mapping):
            raise ValueError(f"{where}.{section}: expected a mapping, got {type(values).__name__}")
        for key, value in values.items():
            if key not in out[section]:
                raise ValueError(f"{where}.{section}.{key}: unknown key; expected one of "
                                 f"{sorted(out[section])}")
            out[section][key] = copy.deepcopy(value)
    return out
