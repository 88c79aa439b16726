"""Stability limits of Zhai's scheme for every model ttbpipe integrates, and the chosen step.

Every limit of a case is computed before the run, so that a refused step is refused with a
message that names each violated limit and proposes one step that passes all of them:

* the **structure** alone (:func:`stable_time_step`: top eigenpairs of (K, M), modal damping,
  the critical omega dt of Zhai's scheme for that damping);
* the **wheel-rail contact** (:func:`contact_time_step_limit`: the Hertz mode of half a
  wheelset on the lightest rail node, the creep dampers);
* the **coupled** rail-contact mode (:func:`coupled_time_step_limit`: Weyl's inequality on the
  sum of the structure's and the Hertz stiffness);
* the **vehicle** suspension (:func:`ttbpipe.vehicle.stability.vehicle_time_step_limit`: the
  spectral radius of the amplification matrix of each car's linear system).

:func:`resolve_time_step` applies them to ``simulation.time_step_s`` (a number, or ``auto`` for
a single case: the smallest limit); :func:`time_step_remedy` words the remedy. The scheme
itself and the generic criteria are :mod:`ttbpipe.timestepping.zhai`.
"""

from __future__ import annotations

import logging
from typing import Any, Mapping

import numpy as np
from scipy import sparse
from scipy.sparse import linalg as splinalg

from ..vehicle.contact import ContactGeometry, creep_coefficients, hertz_stiffness
from ..vehicle.model import TrainModel
from ..vehicle.stability import VEHICLE_SAFETY, vehicle_step_is_stable, vehicle_time_step_limit
from .zhai import zhai_critical_omega_dt

log = logging.getLogger(__name__)


def _mass_inverse_sqrt(model, M):
    """Sparse L^-1 with M_ff = L L^T on the free DOFs (diagonal part + dense span blocks)."""
    free = ~model.fixed
    nd = model.packed.n_diag
    diag = M.diagonal()[:nd][free[:nd]]
    blocks = [sparse.diags(1.0 / np.sqrt(diag))]
    for o, block_mass in zip(model.dof_info["block_dof0"], model.dof_info["block_mass"]):
        f = free[o:o + block_mass.shape[0]]
        if f.any():
            L = np.linalg.cholesky(block_mass[np.ix_(f, f)])
            blocks.append(sparse.csr_matrix(np.linalg.inv(L)))
    return sparse.block_diag(blocks).tocsr()


def stable_time_step(model, safety: float = 0.9, n_modes: int = 6) -> dict:
    """Stability limit of Zhai's method for this structure.

    The top ``n_modes`` eigenpairs of (K, M), computed as the largest eigenvalues of the
    standard form L^-1 K L^-T (M = L L^T, block-diagonal so L is cheap; ARPACK, ~0.05 s for
    the reference structure), give omega and the modal damping ratio
    zeta = x^T C x / (2 omega) with x = L^-T y; each mode allows dt = Omega_crit(zeta) / omega.
    Returns the minimum times ``safety`` with its mode. The analysis is made once per model
    (:meth:`ttbpipe.structure.StructureModel.derived`).
    """
    best = dict(model.derived(("stability", n_modes), lambda: _stability_analysis(model, n_modes)))
    best["dt_s"] = safety * best["dt_limit_s"]
    return best


def _stability_analysis(model, n_modes: int) -> dict:
    """The mode with the smallest Zhai limit among the top ``n_modes`` (:func:`stable_time_step`)."""
    M, K, C = model.matrices()
    free = np.flatnonzero(~model.fixed)
    K, C = (A[free][:, free].tocsr() for A in (K, C))
    Linv = _mass_inverse_sqrt(model, M)
    A = (Linv @ K @ Linv.T).tocsr()
    k = min(n_modes, free.size - 2)
    # loose tol: the top eigenvalues are clustered (identical rail bays), so tight vector
    # convergence costs thousands of iterations. For a symmetric matrix each Ritz value is within
    # the residual tol*|lambda| of an eigenvalue (and its vector's Rayleigh quotient within
    # ~tol^2): tol 1e-3 bounds omega to 0.05 %, far inside the 0.9 safety factor. Measured on
    # the reference case: tol 1e-3 0.03 s vs 1e-5 0.55 s, top four omega identical to 1e-10,
    # limit unchanged (docs/performance.md). Fixed start vector: deterministic run time/result.
    v0 = np.random.default_rng(20261121).standard_normal(A.shape[0])
    w2, vec = splinalg.eigsh(A, k=k, which="LA", tol=1e-3, v0=v0)
    best = None
    for i in range(w2.size):
        w = np.sqrt(max(w2[i], 0.0))
        if w <= 0:
            continue
        x = Linv.T @ vec[:, i]
        zeta = float(x @ (C @ x)) / (2 * w)
        dt = zhai_critical_omega_dt(round(zeta, 6)) / w
        if best is None or dt < best["dt_limit_s"]:
            best = {"dt_limit_s": dt, "omega_rad_s": w, "frequency_hz": w / (2 * np.pi),
                    "zeta": zeta}
    best["omega_max_rad_s"] = float(np.sqrt(np.max(w2)))
    return best


def check_time_step(model, dt: float) -> dict:
    """Raise ValueError naming the remedy when dt exceeds the Zhai stability limit."""
    info = stable_time_step(model, safety=1.0)
    if dt > info["dt_limit_s"]:
        raise ValueError(
            f"time step dt={dt:.3g} s exceeds the Zhai stability limit {info['dt_limit_s']:.3g} s "
            f"of this structure (mode at {info['frequency_hz']:.0f} Hz, damping ratio "
            f"{info['zeta']:.3f}); set simulation.time_step_s <= "
            f"{0.9 * info['dt_limit_s']:.3g}, or raise structure.rail.rotary_inertia_scaling / "
            "coarsen structure.slab.element_length_m (see docs/structure.md)")
    return info



def contact_time_step_limit(model: TrainModel, geom: ContactGeometry, speed: float,
                            rail_inv_mass_z: float = 0.0, rail_inv_mass_y: float = 0.0) -> dict:
    """Largest stable Zhai step from the wheel-rail contact (safety 0.9; omega dt <= 2 undamped,
    c dt / m <= 2 for a stiff damper, physics.md section 5).

    * Hertz mode: linearised stiffness k_H = 1.5 P^(1/3)/G at twice the largest static wheel load
      (dynamic peaks) between half a wheelset and the rail node under it:
      omega = sqrt(k_H (1/m_w + 1/m_r,z)) (rigid track: 1/m_r = 0).
    * Creep damping: the creep forces are viscous in the sliding velocities, with c = f11/V per
      wheel on the spin (lever r0: c_spin = 2 f11 r0^2/V on the spin inertia), c = f22/V per
      wheel laterally between the wheelset and the rail head (effective inverse mass of the head
      1/m_y + h^2/I_roll). At low speed these become the stiffest "modes" of the system.
    ``rail_inv_mass_*``: largest inverse mass of a rail node (z) and of the rail head (y).
    """
    p_max = 2.0 * float(model.static_wheel_load.max())
    k_h = hertz_stiffness(p_max, geom.hertz_g)
    m_w = 0.5 * min(c.wheelset_mass for c in model.params.cars)
    omega = np.sqrt(k_h * (1.0 / m_w + rail_inv_mass_z))
    dt_hertz = 0.9 * 2.0 / omega
    f11, f22, _, _ = creep_coefficients(geom, p_max)
    spin_inertia = min(c_.wheelset_spin_inertia for c_ in model.params.cars)
    dt_spin = 0.9 * 2.0 * spin_inertia / (2 * f11 * geom.wheel_radius ** 2 / speed)
    # lateral: wheelset (two wheels, mass 2 m_w) against the rail head of one wheel
    inv_lat = max(1.0 / (2 * m_w) * 2.0, rail_inv_mass_y + 1.0 / (2 * m_w))
    dt_lat = 0.9 * 2.0 / (f22 / speed * inv_lat)
    return {"dt_s": float(min(dt_hertz, dt_spin, dt_lat)), "dt_hertz_s": float(dt_hertz),
            "omega_hertz_rad_s": float(omega),
            "dt_creep_spin_s": float(dt_spin), "dt_creep_lateral_s": float(dt_lat),
            "hertz_stiffness_N_m": float(k_h),
            "lateral_creep_inverse_mass_1_kg": float(inv_lat)}


def coupled_time_step_limit(structure, limits: Mapping[str, Any], safety: float = 0.9) -> dict:
    """Zhai step limit of the structure with the Hertz contact springs (physics.md section 5).

    The structure's check (K, M of the structure alone) and the contact check (Hertz spring
    between half a wheelset and a rail node, rail node otherwise free) each miss the other's
    stiffness: the rail node under a wheel carries both. In mass-normalised coordinates the
    coupled stiffness is the sum of the two, so by Weyl's inequality (Horn & Johnson, Matrix
    Analysis, thm 4.3.1) omega_coupled^2 <= omega_structure^2 + omega_hertz^2; the limit is
    Omega_crit(zeta of the structure's top mode) / that omega, times ``safety``. Both omegas come
    from the model actually integrated (factored rail masses and stiffnesses).
    Returns dt_structure_s (safety 0.9, as stable_time_step), dt_structure_limit_s (safety 1),
    dt_coupled_s (with ``safety``: the ``auto`` step and the step :func:`prepare` enforces, as
    the contact check does), dt_coupled_limit_s (safety 1), omega_structure_rad_s.
    Measured (case 2, C1 sample 32, rail mass factor 0.63): dt_coupled_limit_s 1.228e-4 s,
    dt_coupled_s 1.105e-4 s; the run is stable at 1.2e-4 s and diverges at 1.22e-4 s (t = 1.36 s),
    1.23e-4 (0.94 s), 1.25e-4 s (0.65 s): the linear bound with k_H at twice the static load
    needs the 0.9 margin (dynamic wheel loads stiffen the Hertz spring, k ~ P^(1/3)).
    """
    info = stable_time_step(structure, safety=1.0)
    w_s = float(info["omega_max_rad_s"])
    w_c = float(np.hypot(w_s, float(limits["omega_hertz_rad_s"])))
    crit = zhai_critical_omega_dt(round(max(float(info["zeta"]), 0.0), 6))
    return {"dt_structure_s": 0.9 * float(info["dt_limit_s"]),
            "dt_structure_limit_s": float(info["dt_limit_s"]),
            "structure_frequency_hz": float(info["frequency_hz"]),
            "structure_zeta": float(info["zeta"]),
            "omega_structure_rad_s": w_s, "dt_coupled_s": float(safety * crit / w_c),
            "dt_coupled_limit_s": float(crit / w_c)}


def floor_significant(x: float, digits: int = 2) -> float:
    """x rounded DOWN to ``digits`` significant digits; the printed value ``f'{r:.{digits}g}'``
    parses back to a number <= x (a proposed step must pass the limit it was derived from)."""
    if not np.isfinite(x) or x <= 0:
        return float(x)
    e = int(np.floor(np.log10(x))) - (digits - 1)
    m = int(np.floor(x / 10.0 ** e * (1.0 - 1e-12)))
    while m > 0 and float(f"{m}e{e}") > x:
        m -= 1
    return float(f"{m}e{e}")


#: Names of the stability limits in messages and in the summary's ``dt_limits``.
LIMIT_NAMES = {"structure": "structure", "coupled": "coupled rail-contact",
               "hertz": "Hertz contact", "creep_spin": "creep spin",
               "creep_lateral": "creep lateral", "vehicle": "vehicle suspension"}


def step_limits(limits: Mapping[str, Any]) -> dict[str, float]:
    """Every stability limit of a case that applies (s, safety factors included), by
    :data:`LIMIT_NAMES` key: a step at or below their minimum passes every check of
    :func:`prepare`. Structure and coupled limits only when they were computed (a structure,
    and ``check_time_step`` or ``auto``); creep lateral only with ``lateral_creep: explicit``."""
    out = {}
    if "dt_structure_s" in limits:
        out["structure"] = float(limits["dt_structure_s"])
        out["coupled"] = float(limits["dt_coupled_s"])
    if "dt_hertz_s" in limits:   # absent only in a summary that was not made by prepare()
        out["hertz"] = float(limits["dt_hertz_s"])
        out["creep_spin"] = float(limits["dt_creep_spin_s"])
    if limits.get("lateral_creep") == "explicit":
        out["creep_lateral"] = float(limits["dt_creep_lateral_s"])
    if "dt_vehicle_s" in limits:
        out["vehicle"] = float(limits["dt_vehicle_s"])
    return out


def proposed_time_step(limits: Mapping[str, Any]) -> float:
    """The step a message proposes: min of :func:`step_limits` rounded down to 2 digits."""
    return floor_significant(min(step_limits(limits).values()), 2)


def _limit_list(limits: Mapping[str, Any]) -> str:
    lims = step_limits(limits)
    text = ", ".join(f"{LIMIT_NAMES[k]} {v:.3g} s" for k, v in sorted(lims.items(), key=lambda kv: kv[1]))
    if "structure" not in lims:
        text += ("; rigid track: no structure limit" if limits.get("track") == "rigid" else
                 "; structure and coupled limits not computed: simulation.check_time_step false")
    return text


def time_step_remedy(limits: Mapping[str, Any], propose_auto: bool) -> str:
    """'set simulation.time_step_s <= N ...': N passes every limit (rounded down, 2 digits)."""
    text = (f"set simulation.time_step_s <= {proposed_time_step(limits):.2g}, which passes every "
            f"stability limit of this case ({_limit_list(limits)})")
    if propose_auto:
        return text + ", or time_step_s: auto (the smallest of these limits)"
    return (text + "; in a study every sample uses this one step, and random properties move the "
            "structure and coupled limits from sample to sample: leave a margin below this "
            "sample's limits")


def _violation_text(key: str, dt: float, limits: Mapping[str, Any]) -> str:
    """What a violated limit is and what moves it (the old per-check messages)."""
    if key == "structure":
        return (f"the Zhai stability limit {limits['dt_structure_limit_s']:.3g} s of this structure "
                f"(mode at {limits['structure_frequency_hz']:.0f} Hz, damping ratio "
                f"{limits['structure_zeta']:.3f}; structure.rail.rotary_inertia_scaling or a coarser "
                "structure.slab.element_length_m raises it, docs/structure.md)")
    if key == "coupled":
        return (f"the coupled rail-contact stability limit {limits['dt_coupled_s']:.3g} s (safety 0.9) "
                f"of this structure (highest structural mode "
                f"{limits['omega_structure_rad_s'] / (2 * np.pi):.0f} Hz plus the Hertz contact mode "
                f"{limits['omega_hertz_rad_s'] / (2 * np.pi):.0f} Hz on the lightest rail node; with "
                "random rail properties a light or stiff rail element lowers it)")
    if key == "contact":
        return (f"the wheel-rail contact stability limit {limits['dt_s']:.3g} s (Hertz "
                f"{limits['dt_hertz_s']:.3g} s, creep {limits['dt_creep_spin_s']:.3g} s spin, "
                f"{limits['dt_creep_lateral_s']:.3g} s lateral, {limits['lateral_creep']}; creep "
                "damping grows as 1/V: low speeds need smaller steps; simulation.lateral_creep: "
                "semi_implicit removes the lateral creep limit)")
    return (f"the vehicle suspension stability limit {limits['dt_vehicle_s']:.3g} s (safety "
            f"{VEHICLE_SAFETY}; Zhai amplification of the linearised car on a fixed rail, first mode "
            f"to diverge: {limits['vehicle_mode']}: a light body on stiff springs or strong dampers; "
            "check the train parameters, vehicle/stability.py)")


def resolve_time_step(sim: Mapping[str, Any], model: TrainModel, geom: ContactGeometry,
                      speed: float, structure, limits: dict, *, propose_auto: bool = False
                      ) -> float:
    """The step of a case from ``simulation.time_step_s`` after every stability check.

    ``limits`` (the contact limits) is completed in place with the vehicle limit
    (:func:`ttbpipe.vehicle.stability.vehicle_time_step_limit`) and, on a structure with
    ``check_time_step`` (default) or ``auto``, the structure and coupled limits
    (:func:`coupled_time_step_limit`). ``auto`` is the smallest of them (:func:`step_limits`).
    A number is refused when it exceeds the structure's limit, the coupled limit, the contact
    limit (``dt_s``) or the vehicle limit (also checked directly at dt / safety: one spectral
    radius per car); the message names every violated limit and proposes a step that passes
    all of them (:func:`time_step_remedy`), with ``auto`` only if ``propose_auto``.
    """
    dt_setting = sim.get("time_step_s", 1.0e-4)
    check = sim.get("check_time_step", True)
    lateral_creep = limits["lateral_creep"]
    limits["track"] = "rigid" if structure is None else "structure"
    limits.update(vehicle_time_step_limit(model, geom, speed, lateral_creep))
    if structure is not None and (dt_setting == "auto" or check):
        # on the model actually integrated (random-property factors applied above)
        limits.update(coupled_time_step_limit(structure, limits))
    if dt_setting == "auto":
        dt = min(step_limits(limits).values())
        log.info("time_step_s auto: %.3g s (%s)", dt, _limit_list(limits))
        return float(dt)
    dt = float(dt_setting)
    if not dt > 0:
        raise ValueError(f"simulation.time_step_s must be positive, got {dt_setting!r}")
    violated = []
    if structure is not None and check:
        if dt > limits["dt_structure_limit_s"]:
            violated.append("structure")
        if dt > limits["dt_coupled_s"] * (1 + 1e-9):
            violated.append("coupled")
    if dt > limits["dt_s"]:
        violated.append("contact")
    if dt > limits["dt_vehicle_s"] * (1 + 1e-9) or not vehicle_step_is_stable(
            model, geom, speed, dt / VEHICLE_SAFETY, lateral_creep):
        violated.append("vehicle")
    if violated:
        raise ValueError(f"simulation.time_step_s={dt:g} s exceeds "
                         + " and ".join(_violation_text(k, dt, limits) for k in violated)
                         + "; " + time_step_remedy(limits, propose_auto))
    return dt
