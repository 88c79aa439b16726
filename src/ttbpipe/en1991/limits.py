"""EN 1991-2 dynamic-analysis rules: need for a dynamic analysis, frequency limits, resonance.

Sources (EN 1991-2:2003, Eurocode 1 Part 2, Traffic loads on bridges; EN 1990:2002/A1:2005
Annex A2; the clauses are named at each function):

* 6.4.4 and Figure 6.9: the flow chart deciding whether a dynamic analysis is required. Its
  first test is the maximum line speed at the site: above 200 km/h a dynamic analysis is
  required. At or below 200 km/h, a simple structure (simply supported span) whose first
  bending frequency n0 lies within the limits of Figure 6.10 and whose first torsional
  frequency exceeds 1.2 n0 needs none (the static analysis with the dynamic factor of 6.4.5
  covers it), provided v/n0 stays within the limits of Annex F (Tables F.1/F.2), which are not
  coded here: that branch is reported as "Annex F check required".
* Figure 6.10: limits of n0 (Hz) against the span L (m), 4 m <= L <= 100 m:
  upper limit n0 = 94.76 L^-0.748; lower limit n0 = 80 / L for 4 m <= L <= 20 m and
  n0 = 23.58 L^-0.592 for 20 m < L <= 100 m (eqs. 6.1, 6.2, 6.3).
* 6.4.6.2: speeds up to the maximum design speed, 1.2 x the maximum line speed.
* 6.4.6.3.1 and Table 6.6: damping (ttbpipe.structure.damping holds the table and eq. 6.13).
* Resonance of a train of regularly spaced axle groups: v_i = n0 lambda_i with lambda_i = D / i
  the wavelengths of excitation (6.4.6.4 and the note to Figure 6.9's "resonance"; for the
  HSLM-A the regular spacing D is the coach length).
* EN 1990 A2.4.4.2.1(4)P: peak deck acceleration along each track, frequencies up to
  max(30 Hz, 1.5 n0, n3), at most 3.5 m/s^2 for ballasted and 5 m/s^2 for direct-fastened
  track (ttbpipe.assessment.en1990 holds the limits and the filter).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["n0_limits_hz", "dynamic_analysis_need", "resonance_speeds_kmh",
           "maximum_design_speed_kmh", "DynamicAnalysisNeed", "SPEED_LIMIT_KMH",
           "DESIGN_SPEED_FACTOR"]

#: Figure 6.9: above this maximum line speed a dynamic analysis is required [km/h].
SPEED_LIMIT_KMH = 200.0
#: 6.4.6.2: the maximum design speed is 1.2 x the maximum line speed.
DESIGN_SPEED_FACTOR = 1.2
#: Figure 6.9: a torsional frequency above this multiple of n0 keeps torsion out of it.
TORSION_FACTOR = 1.2


def n0_limits_hz(span_m: float) -> tuple[float, float]:
    """(lower, upper) limit of the first bending frequency, EN 1991-2 Figure 6.10 (eqs. 6.1-6.3).

    Defined for 4 m <= L <= 100 m; outside that range a ValueError says so (Figure 6.9 then
    asks for a dynamic analysis).
    """
    L = float(span_m)
    if not 4.0 <= L <= 100.0:
        raise ValueError(f"span {L:g} m: EN 1991-2 Figure 6.10 covers 4 m <= L <= 100 m")
    upper = 94.76 * L ** -0.748
    lower = 80.0 / L if L <= 20.0 else 23.58 * L ** -0.592
    return lower, upper


def maximum_design_speed_kmh(line_speed_kmh: float) -> float:
    """EN 1991-2 6.4.6.2: 1.2 x the maximum line speed."""
    return DESIGN_SPEED_FACTOR * float(line_speed_kmh)


def resonance_speeds_kmh(n0_hz: float, spacing_m: float, orders=(1, 2, 3, 4)) -> dict[int, float]:
    """v_i = n0 D / i (km/h) for the regular axle-group spacing D (EN 1991-2 6.4.6.4)."""
    return {int(i): 3.6 * float(n0_hz) * float(spacing_m) / int(i) for i in orders}


@dataclass(frozen=True)
class DynamicAnalysisNeed:
    """The outcome of EN 1991-2 Figure 6.9 for one span, with the branch that decided it."""

    required: bool | None          # None: the Annex F check (not coded) decides
    reason: str
    n0_hz: float
    n0_lower_hz: float | None
    n0_upper_hz: float | None
    torsion_hz: float | None

    @property
    def verdict(self) -> str:
        if self.required is None:
            return "Annex F check required"
        return "dynamic analysis required" if self.required else "no dynamic analysis required"


def dynamic_analysis_need(line_speed_kmh: float, span_m: float, n0_hz: float,
                          torsion_hz: float | None = None, *,
                          simply_supported: bool = True) -> DynamicAnalysisNeed:
    """EN 1991-2 6.4.4, Figure 6.9, for a span with first bending frequency ``n0_hz``."""
    V, L, n0 = float(line_speed_kmh), float(span_m), float(n0_hz)
    try:
        lower, upper = n0_limits_hz(L)
    except ValueError:
        lower = upper = None
    common = dict(n0_hz=n0, n0_lower_hz=lower, n0_upper_hz=upper, torsion_hz=torsion_hz)
    if V > SPEED_LIMIT_KMH:
        return DynamicAnalysisNeed(True, f"maximum line speed {V:g} km/h > "
                                   f"{SPEED_LIMIT_KMH:g} km/h (Figure 6.9)", **common)
    if not simply_supported:
        return DynamicAnalysisNeed(True, "not a simple structure: Figure 6.9 asks for a "
                                   "dynamic analysis unless 6.4.4 is met otherwise", **common)
    if lower is None:
        return DynamicAnalysisNeed(True, f"span {L:g} m outside Figure 6.10 (4-100 m)", **common)
    if not lower <= n0 <= upper:
        return DynamicAnalysisNeed(True, f"n0 = {n0:.3f} Hz outside the Figure 6.10 limits "
                                   f"{lower:.3f}-{upper:.3f} Hz", **common)
    if torsion_hz is not None and not torsion_hz > TORSION_FACTOR * n0:
        return DynamicAnalysisNeed(True, f"first torsional frequency {torsion_hz:.3f} Hz "
                                   f"<= {TORSION_FACTOR:g} n0 (Figure 6.9)", **common)
    return DynamicAnalysisNeed(None, f"V <= {SPEED_LIMIT_KMH:g} km/h and n0 within Figure 6.10:"
                               " v/n0 against Annex F Tables F.1/F.2 decides", **common)

