"""Vehicle, wheel-rail contact and train parameters: one coherent CRH-type default set.

Every value is SI and **per element** (per spring, per damper, per wheel) unless the name says
otherwise; the source tag follows physics.md: [V] read in a public source, [M] standard literature
value not re-read, [A] assumed here (typical value, no single source; override it).

Vertical set: Zeng et al. 2014, Shock and Vibration 2014:304219, Table 1 [V]. Zeng's suspension
values are per bogie (secondary) and per wheelset (primary); a bogie has two air springs and a
wheelset two axle-box spring groups, so the per-spring values below are half of Zeng's
(physics.md section 6, and section 7 item 8 on suspension units: with per-bogie values the
car-body bounce is 0.75 Hz and the bogie bounce 6 Hz, which is what the paper reports).

Lateral/longitudinal set: Zhai, "Vehicle-track coupled dynamics", high-speed passenger car
(physics.md section 6, [V]); these are not CRH-specific.

Geometry: bogie centres 17.375 m, wheelbase 2.5 m [V: Zeng 2014; Velaro/ICE3 in TTB-2D].
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass, field, fields
from typing import Any, Mapping

from ..constants import STANDARD_GRAVITY

log = logging.getLogger(__name__)

#: Gravity acting on the train (m/s^2): :data:`ttbpipe.constants.STANDARD_GRAVITY`.
GRAVITY = STANDARD_GRAVITY


@dataclass
class CarParameters:
    """One car of 7 rigid bodies (car body, 2 bogie frames, 4 wheelsets), per-element values."""

    kind: str = "trailer"
    # masses and inertias (kg, kg m^2); x roll, y pitch, z yaw
    car_mass: float = 44_000.0            # [V] Zeng 2014 trailer
    car_roll_inertia: float = 7.506e4     # [V] Zhai (not CRH)
    car_pitch_inertia: float = 2.7e6      # [V] Zeng 2014
    car_yaw_inertia: float = 2.7e6        # [A] = pitch inertia (long slender body; Zhai's 2.086e6 is
    #                                       for a lighter 25.5 m car and would be incoherent here)
    bogie_mass: float = 2_400.0           # [V] Zeng 2014
    bogie_roll_inertia: float = 2_260.0   # [V] Zhai
    bogie_pitch_inertia: float = 2_200.0  # [V] Zeng 2014
    bogie_yaw_inertia: float = 3_160.0    # [V] Zhai
    wheelset_mass: float = 2_400.0        # [V] Zeng 2014
    wheelset_roll_inertia: float = 915.0  # [V] Zhai
    wheelset_spin_inertia: float = 140.0  # [A] polar inertia about the axle, typical 120-160
    wheelset_yaw_inertia: float = 915.0   # [V] Zhai
    # primary suspension, per axle-box (two per wheelset)
    primary_kz: float = 0.7e6             # [V] Zeng 1.4e6 per wheelset / 2
    primary_cz: float = 4.0e4             # [V] Zeng 8.0e4 per wheelset / 2
    primary_ky: float = 5.0e6             # [V] Zhai per spring
    primary_cy: float = 0.0               # [V] Zhai: no primary lateral damper
    primary_kx: float = 1.0e7             # [V] Zhai per spring
    primary_cx: float = 0.0
    # secondary suspension, per air spring (two per bogie)
    secondary_kz: float = 3.0e5           # [V] Zeng 6.0e5 per bogie / 2
    secondary_cz: float = 4.0e4           # [V] Zeng 8.0e4 per bogie / 2
    secondary_ky: float = 1.5e5           # [V] Zhai per spring
    secondary_cy: float = 6.0e4           # [V] Zhai per spring (lateral damper)
    secondary_kx: float = 1.5e5           # [V] Zhai per spring
    secondary_cx: float = 0.0
    yaw_damper_c: float = 2.5e5           # [A] anti-yaw damper per side, N s/m (CRH: 2 per bogie)
    yaw_damper_half_spacing: float = 1.35  # [A] m
    # geometry (m)
    bogie_half_spacing: float = 8.6875    # [V] 17.375 / 2
    wheelbase_half: float = 1.25          # [V] 2.5 / 2
    primary_half_spacing: float = 0.978   # [V] Zhai d_w
    secondary_half_spacing: float = 0.978  # [V] Zhai d_s
    car_length: float = 25.0              # [A] coupler plane to coupler plane (CRH3: 24.8-25.9)
    # heights above the rail top (m)
    car_cg_height: float = 1.60           # [A] typical
    secondary_height: float = 0.90        # [A] air-spring seat
    bogie_cg_height: float = 0.60         # [A]
    primary_height: float = 0.43          # [A] axle height
    coupler_height: float = 1.00          # [A]

    @property
    def static_wheel_load(self) -> float:
        """Static vertical load of one wheel (N) for a car with its centre of gravity centred."""
        return GRAVITY * (self.car_mass / 8.0 + self.bogie_mass / 4.0 + self.wheelset_mass / 2.0)

    @property
    def total_mass(self) -> float:
        return self.car_mass + 2 * self.bogie_mass + 4 * self.wheelset_mass


def trailer_car() -> CarParameters:
    """Default trailer car (Zeng 2014 trailer column, Zhai lateral set)."""
    return CarParameters()


def motor_car() -> CarParameters:
    """Default motor car (Zeng 2014 motor column, Zhai lateral set; bogie roll/yaw scaled)."""
    return CarParameters(
        kind="motor",
        car_mass=48_000.0,               # [V] Zeng
        bogie_mass=3_200.0,              # [V] Zeng
        bogie_pitch_inertia=7_200.0,     # [V] Zeng
        bogie_roll_inertia=3_000.0,      # [A] Zhai 2,260 scaled by the mass ratio 3200/2400
        bogie_yaw_inertia=7_900.0,       # [A] ~ pitch inertia + roll contribution (motors on axles)
        primary_kz=1.04e6,               # [V] Zeng 2.08e6 per wheelset / 2
        primary_cz=3.0e4,                # [V] Zeng 6.0e4 per wheelset / 2
        secondary_kz=4.0e5,              # [V] Zeng 8.0e5 per bogie / 2
        secondary_cz=4.5e4,              # [V] Zeng 9.0e4 per bogie / 2
    )


@dataclass
class ContactParameters:
    """Wheel-rail contact: geometry, Hertz, creep and flange parameters."""

    wheel_radius: float = 0.43            # [V] physics.md 0.43-0.46 m
    contact_half_distance: float = 0.7465  # [V] 2a ~ 1.493 m (Hindawi ACE 2020)
    profile: str = "conical"              # conical | table | profiles
    conicity: float = 0.04                # [M] equivalent conicity 0.02-0.05 (EN 15302 range)
    profile_table: str | None = None      # CSV/Parquet path when profile == "table"; None -> demo
    rail_head_radius: float = 0.30        # [M] CHN60 head crown radius
    wheel_transverse_radius: float = 1.0e9  # cone: flat generator
    youngs_modulus: float = 2.059e11      # [V] CHN60 steel
    poisson: float = 0.30                 # [V]
    friction: float = 0.30                # [M] physics.md section 4
    hertz_law: str = "auto"               # auto (cone for conical, worn for table, hertz for
    #                                       two-point profiles) | cone | worn | hertz (from the
    #                                       contact's curvatures; profiles with contact_points 2)
    flange_clearance: float = 9.1e-3      # [M] Knudsen, Feldberg & True 1991 wheelset model
    flange_stiffness: float = 1.823e7     # [M] same source: F = k0 (y - delta), k0 1.823e7 N/m
    rail_head_height: float = 0.10        # [A] lever of the lateral force about the rail's axis
    # profile == "profiles": a wheel and rail profile pair (ttbpipe.vehicle.profile_contact;
    # names as `ttbpipe contact-geometry` takes them, or point files)
    wheel_profile: str = "s1002"          # EN 13715 S1002
    rail_profile: str = "60e1"            # EN 13674-1 60E1
    rail_inclination: str = "1:40"        # 1:20 | 1:40 | none
    gauge_m: float = 1.435                # nominal gauge, measured 14 mm below the rail top
    flange_back_m: float = 1.360          # flange-back spacing of the wheelset
    contact_points: int = 2               # profiles: 2 = tread and flange with forces of their
    #                                       own; 1 = one point per wheel (the smallest gap)
    # two-point contact: the contact of a yawed wheelset on its trace line, tabulated over
    # yaw_layers layers from 0 to yaw_max_rad (held beyond; 1 = the contact at zero yaw only)
    yaw_max_rad: float = 0.03             # [M] above curving's angles of attack (~10-20 mrad)
    yaw_layers: int = 7                   # 5 mrad apart (docs/contact_geometry.md)
    # creep law of every contact point (ttbpipe.vehicle.contact): kalker_she = Kalker's linear
    # theory saturated by Shen-Hedrick-Elkins; polach = Polach's method (large spin, and with
    # the parameters below the adhesion fall-off with the slip velocity; Polach 1999, 2005)
    creep_law: str = "kalker_she"
    polach_k_a: float = 1.0               # reduction factor kA in the area of adhesion (Polach
    #                                       2005; 1 = Kalker's initial slope, Polach 1999)
    polach_k_s: float = 1.0               # reduction factor kS in the area of slip (<= kA)
    polach_a: float = 1.0                 # mu_inf / mu0 at infinite slip velocity (1: no fall-off)
    polach_b_s_m: float = 0.0             # exponential decrease rate B of the friction (s/m)


#: Contact geometries: a cone (closed form), a tabulated file, a wheel and rail profile pair.
CONTACT_PROFILES = ("conical", "table", "profiles")
#: Creep laws of the contact points (ttbpipe.vehicle.contact; the kernels' code is the index).
CREEP_LAWS = ("kalker_she", "polach")


@dataclass
class CouplerParameters:
    """Inter-car coupler: springs and dampers in y and z between adjacent car ends.

    The longitudinal DOF is not in the 35-DOF car model, so the coupler acts on the lateral and
    vertical relative motion of the two coupler heads (which includes car yaw, pitch and roll).
    It is stress-free in the static equilibrium. Values [A]: semi-permanent couplers of EMUs are
    soft in y and z compared with the suspension; set to 0 to uncouple the cars.
    """

    ky: float = 5.0e5
    kz: float = 5.0e5
    cy: float = 2.0e4
    cz: float = 2.0e4


@dataclass
class TrainParameters:
    """A train: its cars (front to rear), couplers, contact, speed."""

    cars: list[CarParameters] = field(default_factory=lambda: [
        motor_car(), trailer_car(), trailer_car(), trailer_car(), motor_car()])
    coupler: CouplerParameters = field(default_factory=CouplerParameters)
    contact: ContactParameters = field(default_factory=ContactParameters)

    @property
    def n_cars(self) -> int:
        return len(self.cars)


def check_creep_law(contact: ContactParameters) -> None:
    """The creep law and Polach's parameters of ``train.contact`` (ranges of Polach 2005:
    0 < kS <= kA <= 1, 0 < A <= 1, B >= 0)."""
    if contact.creep_law not in CREEP_LAWS:
        raise ValueError(f"train.contact.creep_law: {contact.creep_law!r}; expected one of "
                         f"{CREEP_LAWS}")
    k_a, k_s = contact.polach_k_a, contact.polach_k_s
    if not (0.0 < k_s <= k_a <= 1.0):
        raise ValueError(f"train.contact.polach_k_a, polach_k_s: {k_a}, {k_s}; Polach's "
                         "reduction factors need 0 < k_s <= k_a <= 1")
    if not (0.0 < contact.polach_a <= 1.0) or contact.polach_b_s_m < 0.0:
        raise ValueError(f"train.contact.polach_a, polach_b_s_m: {contact.polach_a}, "
                         f"{contact.polach_b_s_m}; expected 0 < polach_a <= 1 (mu_inf / mu0) "
                         "and polach_b_s_m >= 0")


def _apply_overrides(obj: Any, overrides: Mapping[str, Any], where: str) -> Any:
    """Return a copy of dataclass ``obj`` with ``overrides`` applied; unknown keys are an error."""
    names = {f.name: f for f in fields(obj)}
    unknown = sorted(set(overrides) - set(names))
    if unknown:
        raise ValueError(f"{where}: unknown parameter(s) {unknown}; known: {sorted(names)}")
    values = {}
    for key, value in overrides.items():
        current = getattr(obj, key)
        if isinstance(current, (int, float)) and not isinstance(current, bool):
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"{where}.{key}: expected a number, got {value!r}") from None
        values[key] = value
    return dataclasses.replace(obj, **values)


def train_from_config(cfg: Mapping[str, Any] | None) -> TrainParameters:
    """Build the train from the ``train:`` section of a case configuration.

    Keys (all optional)::

        composition: [motor, trailer, trailer, trailer, motor]
        motor: {car_mass: 48000, ...}      # overrides for every motor car
        trailer: {...}                      # overrides for every trailer car
        car_overrides: {2: {car_mass: 50000}}  # per car index (0 = leading car)
        coupler: {ky: ..., kz: ..., cy: ..., cz: ...}
        contact: {conicity: 0.04, profile: conical, ...}
    """
    cfg = dict(cfg or {})
    known = {"composition", "motor", "trailer", "car_overrides", "coupler", "contact", "speed_kmh"}
    unknown = sorted(set(cfg) - known)
    if unknown:
        raise ValueError(f"train: unknown key(s) {unknown}; known: {sorted(known)}")
    composition = cfg.get("composition", ["motor", "trailer", "trailer", "trailer", "motor"])
    if not composition:
        raise ValueError("train.composition: at least one car is needed")
    cars = []
    for i, kind in enumerate(composition):
        if kind == "motor":
            car = _apply_overrides(motor_car(), cfg.get("motor", {}) or {}, "train.motor")
        elif kind == "trailer":
            car = _apply_overrides(trailer_car(), cfg.get("trailer", {}) or {}, "train.trailer")
        else:
            raise ValueError(f"train.composition[{i}]: {kind!r} is neither 'motor' nor 'trailer'")
        per_car = (cfg.get("car_overrides") or {}).get(i) or (cfg.get("car_overrides") or {}).get(str(i))
        if per_car:
            car = _apply_overrides(car, per_car, f"train.car_overrides[{i}]")
        cars.append(car)
    coupler = _apply_overrides(CouplerParameters(), cfg.get("coupler", {}) or {}, "train.coupler")
    contact = _apply_overrides(ContactParameters(), cfg.get("contact", {}) or {}, "train.contact")
    if contact.profile not in CONTACT_PROFILES:
        raise ValueError(f"train.contact.profile: {contact.profile!r}; expected one of "
                         f"{CONTACT_PROFILES}")
    check_creep_law(contact)
    return TrainParameters(cars=cars, coupler=coupler, contact=contact)
