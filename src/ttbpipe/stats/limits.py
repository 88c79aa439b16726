"""Safety and comfort limits checked against the per-sample extremes, each with its source.

Defaults follow ``docs/reference/physics.md`` section 4 ("Limits"); the tag after each
source says how well it is established there: [V] verified against the standard's text or a
script implementing it, [M] quoted from memory / secondary literature and to be confirmed.

A limit is exceeded by a sample when its response index is **strictly greater** than the
sample's threshold. Thresholds are in SI units like the extremes table. ``category`` is
``'limit'`` (a safety or serviceability limit) or ``'grade'`` (a quality grade boundary such as
Sperling 'excellent' / 'good', reported separately). Three kinds:

* :class:`ConstantLimit`: one threshold for every sample;
* :class:`SpeedDependentLimit`: wheel unloading, 0.65 up to 160 km/h and 0.8 above;
* :class:`StaticLoadLimit`: lateral wheelset force ``a + P0/3`` with the static wheel load P0.

``limits:`` in ``config/config.yaml`` selects the deck track type, gives the train speed and
static wheel load when the results do not carry them, overrides thresholds and disables limits
(:func:`limits_from_config`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from typing import Any, Mapping

import numpy as np
import pandas as pd

from ..constants import STANDARD_GRAVITY

log = logging.getLogger(__name__)

KMH = 1.0 / 3.6  # m/s per km/h


class LimitNotEvaluable(ValueError):
    """A limit needs an input (train speed, static wheel load) that neither results nor config give."""


@dataclass(frozen=True)
class LimitContext:
    """Inputs some thresholds need when the results table does not carry them.

    ``train_speed_kmh`` and ``static_axle_load_N`` are used only when the extremes table has no
    ``train_speed_m_s`` / ``static_axle_load_N`` column.
    """

    train_speed_kmh: float | None = None
    static_axle_load_N: float | None = None


@dataclass(frozen=True)
class ConstantLimit:
    """``index > threshold`` with one threshold (SI) for all samples."""

    name: str
    column: str
    threshold: float
    unit: str
    source: str
    description: str
    category: str = "limit"

    def thresholds(self, df: pd.DataFrame, context: LimitContext = LimitContext()) -> np.ndarray:
        """Per-sample threshold (SI), one per row of ``df``."""
        return np.full(len(df), float(self.threshold))

    def threshold_text(self) -> str:
        return f"{self.threshold:.4g}" + ("" if self.unit == "1" else f" {self.unit}")

    def with_threshold(self, value: float) -> "ConstantLimit":
        return replace(self, threshold=float(value))


@dataclass(frozen=True)
class SpeedDependentLimit:
    """Wheel unloading ratio: ``low`` for v <= ``speed_kmh``, ``high`` above.

    Source: GB/T 5599-2019 (0.65 for v <= 160 km/h) [V: script quoted in physics.md section 4];
    0.8 above 160 km/h [M]; TB 10621 uses 0.6 [M].
    """

    name: str
    column: str
    low: float
    high: float
    speed_kmh: float
    unit: str
    source: str
    description: str
    category: str = "limit"

    def thresholds(self, df: pd.DataFrame, context: LimitContext = LimitContext()) -> np.ndarray:
        if "train_speed_m_s" in df.columns:
            speed_kmh = df["train_speed_m_s"].to_numpy(dtype=float) / KMH
        elif context.train_speed_kmh is not None:
            speed_kmh = np.full(len(df), float(context.train_speed_kmh))
        else:
            raise LimitNotEvaluable(
                f"limit {self.name!r} depends on the train speed: write column train_speed_m_s "
                "in the extremes tables or set limits.train_speed_kmh in the configuration")
        return self.value_at(speed_kmh)

    def value_at(self, speed_kmh: np.ndarray | float) -> np.ndarray:
        """The limit at ``speed_kmh`` (km/h): ``low`` up to :attr:`speed_kmh`, ``high`` above."""
        # 1e-9 guards 160 km/h read back from m/s against rounding.
        return np.where(np.asarray(speed_kmh, dtype=float) <= self.speed_kmh + 1e-9, self.low,
                        self.high)

    def threshold_text(self) -> str:
        return f"{self.low:g} (v <= {self.speed_kmh:g} km/h) / {self.high:g} above"


@dataclass(frozen=True)
class StaticLoadLimit:
    """Lateral wheelset force ``H > constant + P0 / divisor`` (N), P0 the static axle load.

    Source: GB/T 5599-2019, H <= 15 + P0/3 kN [V: physics.md section 4]; the
    Prud'homme / TB 10621 / EN 14363 variant 10 + P0/3 kN is [M].
    """

    name: str
    column: str
    constant: float
    divisor: float
    unit: str
    source: str
    description: str
    category: str = "limit"

    def thresholds(self, df: pd.DataFrame, context: LimitContext = LimitContext()) -> np.ndarray:
        if "static_axle_load_N" in df.columns:
            p0 = df["static_axle_load_N"].to_numpy(dtype=float)
        elif context.static_axle_load_N is not None:
            p0 = np.full(len(df), float(context.static_axle_load_N))
        else:
            raise LimitNotEvaluable(
                f"limit {self.name!r} needs the static axle load P0: write column "
                "static_axle_load_N in the extremes tables or set limits.static_axle_load_N")
        return self.constant + p0 / self.divisor

    def threshold_text(self) -> str:
        return f"{self.constant / 1e3:g} kN + P0/{self.divisor:g}"


Limit = ConstantLimit | SpeedDependentLimit | StaticLoadLimit

#: Deck vertical acceleration limits (m/s^2) by track type, EN 1990 A2 A2.4.4.2.1.
DECK_VERTICAL_ACC_M_S2 = {"ballasted": 3.5, "ballastless": 5.0}


def applied_threshold_text(limit: Limit, thresholds: np.ndarray) -> str:
    """The thresholds actually applied to a set of samples: one value, or the range."""
    unit = "" if limit.unit == "1" else f" {limit.unit}"
    lo, hi = float(np.min(thresholds)), float(np.max(thresholds))
    if lo == hi:
        return f"{lo:.4g}{unit}"
    return f"{lo:.4g} to {hi:.4g}{unit} (per sample)"


def default_limits(deck_track_type: str = "ballastless") -> list[Limit]:
    """The default limits of physics.md section 4, in SI units."""
    if deck_track_type not in DECK_VERTICAL_ACC_M_S2:
        raise ValueError(f"deck_track_type must be one of {list(DECK_VERTICAL_ACC_M_S2)}, "
                         f"got {deck_track_type!r}")
    limits: list[Limit] = [
        ConstantLimit("derailment_coefficient", "max_derailment_coefficient", 0.8, "1",
                      "GB/T 5599-2019, tangent track and R > 400 m [V]",
                      "derailment coefficient Q/P"),
        SpeedDependentLimit("wheel_unloading_ratio", "max_wheel_unloading_ratio", 0.65, 0.8,
                            160.0, "1",
                            "GB/T 5599-2019: 0.65 for v <= 160 km/h [V]; 0.8 above [M]",
                            "wheel unloading ratio (P0 - P)/P0"),
        StaticLoadLimit("lateral_wheelset_force", "max_lateral_wheelset_force_N", 15e3, 3.0, "N",
                        "GB/T 5599-2019, H <= 15 + P0/3 kN [V]", "lateral wheelset force H"),
        ConstantLimit("carbody_vertical_acc", "max_carbody_vertical_acc_m_s2",
                      0.13 * STANDARD_GRAVITY, "m/s^2", "TB 10621, 0.13 g [M]",
                      "car-body vertical acceleration"),
        ConstantLimit("carbody_lateral_acc", "max_carbody_lateral_acc_m_s2",
                      0.10 * STANDARD_GRAVITY, "m/s^2", "TB 10621, 0.10 g [M]",
                      "car-body lateral acceleration"),
    ]
    for axis in ("vertical", "lateral"):
        for grade, value in (("excellent", 2.5), ("good", 2.75), ("pass", 3.0)):
            limits.append(ConstantLimit(
                f"sperling_{axis}_{grade}", f"sperling_{axis}", value, "1",
                "Sperling ride index grades 2.5 excellent / 2.75 good / 3.0 pass [M]",
                f"{axis} Sperling index, grade '{grade}'",
                category="limit" if grade == "pass" else "grade"))
    limits += [
        ConstantLimit("deck_vertical_acc", "max_deck_vertical_acc_m_s2",
                      DECK_VERTICAL_ACC_M_S2[deck_track_type], "m/s^2",
                      f"EN 1990 A2 A2.4.4.2.1, {deck_track_type} track "
                      "(3.5 m/s^2 ballasted / 5 m/s^2 ballastless) [V]",
                      "deck vertical acceleration"),
        ConstantLimit("deck_lateral_acc", "max_deck_lateral_acc_m_s2",
                      0.14 * STANDARD_GRAVITY, "m/s^2",
                      "Chinese bridge inspection code 2004, 0.14 g [M]",
                      "deck lateral acceleration"),
    ]
    return limits


def limits_from_config(section: Mapping[str, Any] | None) -> tuple[list[Limit], LimitContext]:
    """Limits and context from the ``limits:`` section of the configuration.

    Keys (all optional): ``deck_track_type`` (ballasted | ballastless), ``train_speed_kmh``,
    ``static_axle_load_N``, ``thresholds`` (name -> SI value replacing a constant default),
    ``disabled`` (names to skip). Unknown limit names are an error.
    """
    section = dict(section or {})
    limits = default_limits(section.get("deck_track_type", "ballastless"))
    by_name = {lim.name: lim for lim in limits}
    for name in list(section.get("thresholds") or {}) + list(section.get("disabled") or []):
        if name not in by_name:
            raise ValueError(f"config limits: unknown limit {name!r}; known: {sorted(by_name)}")
    for name, value in (section.get("thresholds") or {}).items():
        if not isinstance(by_name[name], ConstantLimit):
            raise ValueError(f"config limits.thresholds: {name!r} is not a constant limit; "
                             "set train_speed_kmh / static_axle_load_N instead")
        log.info("limit %s: threshold %s replaced by configured %s", name,
                 by_name[name].threshold, value)
        old = by_name[name]
        by_name[name] = replace(old.with_threshold(value), source=(
            f"configured in limits.thresholds (default {old.threshold:.4g}: {old.source})"))
    disabled = set(section.get("disabled") or [])
    if disabled:
        log.info("limits disabled by configuration: %s", sorted(disabled))
    context = LimitContext(train_speed_kmh=section.get("train_speed_kmh"),
                           static_axle_load_N=section.get("static_axle_load_N"))
    return [by_name[lim.name] for lim in limits if lim.name not in disabled], context
