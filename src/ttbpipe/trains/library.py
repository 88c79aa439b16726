"""The train library: named trains as ordered axles (position behind the first axle, static load).

The data ship with the package (``ttbpipe/trains/*.yaml``, declared in pyproject's package-data);
each file states where every number comes from: the ten universal trains HSLM-A1 ... HSLM-A10 of
EN 1991-2:2003 Annex E (``hslm.yaml``: Table E.1 for N, D, d, P; Figure E.1 for the power cars
and end coaches), then the real trains of ``real_trains.yaml`` (axle tables of the Spanish IAPF-07
Appendix C.2; a car-by-car description of the AVE S-103 / Velaro E). SI inside: positions in m,
axle loads in N (the files' kN and t are converted on reading). ``Train.mass_kg`` is the static
load over the standard gravity.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

import numpy as np
import pandas as pd

from ..constants import STANDARD_GRAVITY

__all__ = ["Train", "train_names", "get_train", "hslm_a_axles", "car_train_axles", "axle_table",
           "library_table"]


@dataclass(frozen=True)
class Train:
    """One train: axles in running order (``positions_m[0] == 0``, increasing), loads in N."""

    name: str
    positions_m: np.ndarray
    axle_loads_N: np.ndarray
    source: str
    parameters: dict

    @property
    def n_axles(self) -> int:
        return int(self.positions_m.size)

    @property
    def length_m(self) -> float:
        """First to last axle (m)."""
        return float(self.positions_m[-1] - self.positions_m[0])

    @property
    def total_load_N(self) -> float:
        return float(self.axle_loads_N.sum())

    @property
    def mass_kg(self) -> float:
        """Static load / g_n (kg)."""
        return self.total_load_N / STANDARD_GRAVITY


def hslm_a_axles(N: int, D: float, d: float, power_car_offsets, gap: float) -> np.ndarray:
    """Axle positions (m, first axle at 0) of an HSLM-A train, EN 1991-2:2003 Figure E.1.

    Leading power car (axles at ``power_car_offsets``; 0, 3, 14, 17 m in ``hslm.yaml``), ``gap``
    (3.525 m) to the end coach's own bogie (axle spacing d), N + 1 articulated bogies (spacing d)
    whose centres are D apart, the first D behind the point ``gap/2`` behind the power car's last
    axle, then the trailing end coach and power car, mirror images of the leading ones:
    2N + 14 axles over 2 (17 + gap/2) + (N + 2) D.
    """
    pc = np.asarray(power_car_offsets, dtype=float)
    joint = pc[-1] + gap / 2.0                       # power car / end coach coupling point
    length = 2.0 * joint + (N + 2) * D               # first to last axle
    front = [*pc, pc[-1] + gap, pc[-1] + gap + d]
    articulated = []
    for k in range(1, N + 2):
        centre = joint + k * D
        articulated += [centre - d / 2.0, centre + d / 2.0]
    rear = [length - x for x in reversed(front)]
    pos = np.array(front + articulated + rear)
    return pos


def car_train_axles(cars) -> tuple[np.ndarray, np.ndarray]:
    """Axle positions (m, first axle at 0) and static axle loads (N) of a train of bogie cars.

    ``cars`` in running order, each a mapping with ``front_m`` (car end to its first bogie
    centre), ``bogie_centres_m``, ``rear_m`` (last bogie centre to the car end), ``wheelbase_m``
    and the masses ``body_kg``, ``bogie_kg`` (one bogie frame), ``wheelset_kg``. Adjacent cars
    touch at their ends. Every axle of a car carries g (m_body / 4 + m_bogie / 2 + m_wheelset):
    the body, its centre of gravity midway between the bogie centres, rests half on each bogie,
    each bogie half on each wheelset (statics of the two-level suspension).
    """
    pos, load = [], []
    start = 0.0
    for car in cars:
        a = float(car["wheelbase_m"]) / 2.0
        c1 = start + float(car["front_m"])
        c2 = c1 + float(car["bogie_centres_m"])
        pos += [c1 - a, c1 + a, c2 - a, c2 + a]
        axle_kg = (float(car["body_kg"]) / 4.0 + float(car["bogie_kg"]) / 2.0
                   + float(car["wheelset_kg"]))
        load += 4 * [axle_kg * STANDARD_GRAVITY]
        start = c2 + float(car["rear_m"])
    pos = np.asarray(pos)
    return pos - pos[0], np.asarray(load)


def _read_yaml(name: str) -> dict:
    from ..configuration import load_packaged_yaml

    text = resources.files("ttbpipe.trains").joinpath(name).read_text(encoding="utf-8")
    return load_packaged_yaml(text)


@lru_cache(maxsize=1)
def _library() -> dict[str, Train]:
    trains: dict[str, Train] = {}
    hslm = _read_yaml("hslm.yaml")
    pc = hslm["power_car"]
    for name, row in hslm["trains"].items():
        pos = hslm_a_axles(int(row["N"]), float(row["D_m"]), float(row["d_m"]),
                           pc["axle_offsets_m"], float(pc["gap_to_end_coach_m"]))
        pos.setflags(write=False)
        loads = np.full(pos.size, float(row["P_kN"]) * 1e3)
        loads.setflags(write=False)
        trains[name] = Train(name, pos, loads, hslm["standard"],
                             {"N": int(row["N"]), "D_m": float(row["D_m"]),
                              "d_m": float(row["d_m"]), "P_N": float(row["P_kN"]) * 1e3})
    real = _read_yaml("real_trains.yaml")["trains"]
    for name, row in real.items():
        if "axles" in row:
            table = np.asarray(row["axles"], dtype=float)
            pos, loads = table[:, 0] - table[0, 0], table[:, 1] * 1e3
        elif "cars" in row:
            pos, loads = car_train_axles(row["cars"])
        else:                               # units of a train described above, coupled end to end
            unit = real[row["units"]["of"]]
            pos, loads = car_train_axles(list(unit["cars"]) * int(row["units"]["count"]))
        pos.setflags(write=False)
        loads.setflags(write=False)
        trains[name] = Train(name, pos, loads, str(row["source"]),
                             {"D_m": float(row["spacing_m"]),
                              "composition": str(row["composition"]),
                              "reference": " ".join(str(row["reference"]).split())})
    return trains


def train_names() -> list[str]:
    """Names in library order (HSLM-A1 ... HSLM-A10, then the real trains)."""
    return list(_library())


def get_train(name: str) -> Train:
    """The named train; ValueError listing the valid names otherwise (case-insensitive match)."""
    lib = _library()
    if name in lib:
        return lib[name]
    folded = {k.casefold(): k for k in lib}
    if name.casefold() in folded:
        return lib[folded[name.casefold()]]
    raise ValueError(f"unknown train {name!r}; the library has: {', '.join(lib)}")


def axle_table(train: Train) -> pd.DataFrame:
    """One row per axle: ``axle`` (1-based), ``position_m``, ``axle_load_kN``."""
    return pd.DataFrame({"axle": np.arange(1, train.n_axles + 1),
                         "position_m": train.positions_m,
                         "axle_load_kN": train.axle_loads_N / 1e3})


def library_table() -> pd.DataFrame:
    """One row per train: name, axles, length (first to last axle), total load and mass, source."""
    rows = [{"name": t.name, "n_axles": t.n_axles, "length_m": t.length_m,
             "total_load_kN": t.total_load_N / 1e3, "mass_t": t.mass_kg / 1e3,
             "source": t.source} for t in _library().values()]
    return pd.DataFrame(rows)
