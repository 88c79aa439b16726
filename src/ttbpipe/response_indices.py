"""The response indices of a coupled run: one registry of names, units and descriptions.

A run (:func:`ttbpipe.simulation.outputs.response_indices`), a study's extremes table
(:mod:`ttbpipe.study.samples`) and the results schema (:mod:`ttbpipe.stats.schema`) all name
an index by its entry here, so a result keeps its name from the loop to the report. Each index
is a maximum over the run (and over the wheels, cars, monitors it refers to), a float whose
unit the name carries; ``lower`` and ``upper`` bound its physically possible values.
Per-span and per-car indices (``max_span<k>_vertical_acc_m_s2``, ``sperling_lateral_car<k>``)
follow :data:`PER_SPAN` and :data:`PER_CAR`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class ResponseIndex:
    """One response index: name (with its unit), unit, what it is, its possible range."""

    name: str
    unit: str
    description: str
    lower: float = -math.inf
    upper: float = math.inf


#: Every response index of a run, in the documented order (docs/results_schema.md).
RESPONSE_INDEX_REGISTRY: tuple[ResponseIndex, ...] = (
    ResponseIndex("max_derailment_coefficient", "1",
               "maximum over the run and all wheels of the derailment coefficient Q/P "
               "(|lateral| / vertical wheel-rail force)", lower=0.0),
    ResponseIndex("max_wheel_unloading_ratio", "1",
               "maximum over the run and all wheels of the unloading ratio (P0 - P)/P0 "
               "(P0 the static wheel load; 1 when the wheel lifts off)", upper=1.0),
    ResponseIndex("max_lateral_wheelset_force_N", "N",
               "maximum over the run and all wheelsets of |H|, the lateral wheelset "
               "(axle-box) force", lower=0.0),
    ResponseIndex("max_wheel_vertical_force_N", "N",
               "maximum over the run and all wheels of the vertical wheel-rail force P", lower=0.0),
    ResponseIndex("max_wheel_lateral_force_N", "N",
               "maximum over the run and all wheels of |Q|, the lateral wheel-rail force",
               lower=0.0),
    ResponseIndex("max_carbody_vertical_acc_m_s2", "m/s^2",
               "maximum over the run and all cars of |vertical car-body acceleration|", lower=0.0),
    ResponseIndex("max_carbody_lateral_acc_m_s2", "m/s^2",
               "maximum over the run and all cars of |lateral car-body acceleration|", lower=0.0),
    ResponseIndex("sperling_vertical", "1",
               "largest vertical Sperling ride index over the cars (physics.md section 4)",
               lower=0.0),
    ResponseIndex("sperling_lateral", "1",
               "largest lateral Sperling ride index over the cars", lower=0.0),
    ResponseIndex("max_deck_vertical_acc_m_s2", "m/s^2",
               "maximum over the run and the deck monitors of |vertical deck acceleration| "
               "(band-limited as in EN 1990 A2 A2.4.4.2.1)", lower=0.0),
    ResponseIndex("max_deck_lateral_acc_m_s2", "m/s^2",
               "maximum over the run and the deck monitors of |lateral deck acceleration|",
               lower=0.0),
    ResponseIndex("max_rail_vertical_acc_m_s2", "m/s^2",
               "maximum over the run and the rail monitors of |vertical rail acceleration|",
               lower=0.0),
    ResponseIndex("max_rail_lateral_acc_m_s2", "m/s^2",
               "maximum over the run and the rail monitors of |lateral rail acceleration|",
               lower=0.0),
    ResponseIndex("max_girder_vertical_disp_m", "m",
               "maximum over the run and the girder monitors of |vertical girder displacement|",
               lower=0.0),
    ResponseIndex("contact_loss_count", "1",
               "number of losses of wheel-rail contact (runs of steps with zero normal force) "
               "over the run and all wheels; 0 when every wheel stays on the rail", lower=0.0),
    ResponseIndex("contact_loss_total_duration_s", "s",
               "time without wheel-rail contact over the run, summed over the wheels", lower=0.0),
    ResponseIndex("contact_loss_max_duration_s", "s",
               "longest single loss of wheel-rail contact over the run and all wheels", lower=0.0),
)

#: Name -> index.
INDEX: dict[str, ResponseIndex] = {i.name: i for i in RESPONSE_INDEX_REGISTRY}

#: Names of the per-span deck indices (format with span=k, 1-based) and the per-car Sperling
#: indices (format with car=k, 1-based).
PER_SPAN = ("max_span{span}_vertical_acc_m_s2", "max_span{span}_lateral_acc_m_s2")
PER_CAR = ("sperling_vertical_car{car}", "sperling_lateral_car{car}")
