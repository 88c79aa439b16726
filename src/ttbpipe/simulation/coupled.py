"""Coupled train-track-bridge runs: :func:`run_coupled` (case -> time histories and summary).

A run is prepared (:func:`ttbpipe.simulation.setup.prepare`: train, contact, structure, track
input, time step after every stability check, static state), integrated by one numba loop
(:func:`ttbpipe.simulation.loop.integrate`: Zhai's explicit scheme for train and structure at
the same dt, wheel-rail contact at every step; physics.md section 5, seed paper sections 2.2.11,
eqs. 28-31) and reduced to its results (:mod:`ttbpipe.simulation.outputs`). ``track: rigid``
runs the same loop on rails fixed in space (irregularities only).

Time step: every stability limit is computed first (:mod:`ttbpipe.timestepping.limits`) and a
refused step's message proposes one that passes all of them. The loop's stops raise
:class:`~ttbpipe.simulation.loop.SimulationStopped`, whose message names the likely cause (the
step, or the irregularity, or a loss of contact; :mod:`ttbpipe.simulation.diagnosis`). Loss of
wheel-rail contact is counted at every step and reported as its own index (summary
``contact_loss_*``); Q/P is defined in contact only. Nothing non-finite leaves
:func:`run_coupled` (:func:`~ttbpipe.simulation.outputs.check_finite`).

On a double-track deck a train runs on either track in either direction
(``simulation.track_index``, ``simulation.direction``) and a second train may share the run
(``second_train``: two trains meeting on the bridge; its columns and indices prefixed
``train2_``, :func:`~ttbpipe.simulation.outputs.add_second_train`).
"""

from __future__ import annotations

import logging
from typing import Any, Mapping

import numpy as np
import pandas as pd

from ..irregularity.track_input import Irregularity
from ..threads import pinned
from .loop import STATUS_MESSAGES, RawResult, SimulationStopped, integrate  # noqa: F401
from .outputs import (DECK_FILTER_HZ, add_second_train, check_finite, placement,
                      results_table, summarise)
from .setup import CoupledSetup, diagnosis_limits, prepare  # noqa: F401

log = logging.getLogger(__name__)


@pinned
def run_coupled(case_config: Mapping[str, Any], *, track: Irregularity | pd.DataFrame | None = None,
                factors: Mapping[str, np.ndarray] | None = None,
                propose_auto: bool = False,
                second_track: Irregularity | pd.DataFrame | None = None
                ) -> tuple[pd.DataFrame, dict]:
    """Run one coupled case: (time-history table, summary dict).

    ``track`` / ``factors``: the track input and the structure's property factors in memory
    (:func:`~ttbpipe.simulation.setup.prepare`); no file is read or written for them;
    ``second_track``: the second train's track input (``second_train``).
    Raises :class:`SimulationStopped` (a RuntimeError) when the loop stops, with the likely
    cause, and ValueError for a refused time step (``propose_auto``: see :func:`prepare`) or a
    non-finite result (:func:`check_finite`). A run in which wheels lose contact completes: the
    loss is reported (summary ``contact_loss_*``, a warning with its likely cause).
    """
    setup = prepare(case_config, track=track, factors=factors, propose_auto=propose_auto,
                    second_track=second_track)
    log.info("coupled run: %d cars, %.1f km/h, dt %.2e s, %d steps, track %s", setup.train.n_cars,
             setup.speed * 3.6, setup.dt, setup.n_steps,
             "rigid" if setup.structure is None else f"{setup.packed.n_dof} structural DOF")
    raw = integrate(setup)
    table = results_table(setup, raw)
    deck_filter = float((case_config.get("simulation") or {}).get("deck_filter_hz", DECK_FILTER_HZ))
    summary = summarise(setup, raw, table, deck_filter)
    if setup.second is not None:
        table, summary = add_second_train(setup, raw, table, summary, deck_filter)
    elif setup.direction != 1 or (setup.structure is not None and setup.structure.n_tracks > 1):
        summary["trains"] = [placement(setup)]
    check_finite(setup, table, summary)
    check_yaw_range(setup, raw.train)
    if setup.second is not None:
        check_yaw_range(setup.second, raw.second, "the second train")
    if summary["contact_loss_count"] > 0:
        from .diagnosis import explain
        _, text = explain(setup.dt, diagnosis_limits(setup), setup.irregularity_info,
                          summary, setup.irregularity_config, setup.speed,
                          propose_auto=propose_auto, stopped=False)
        log.warning("wheel-rail contact lost %d times on %d wheel(s), longest %.1f ms: %s",
                    summary["contact_loss_count"], summary["contact_loss_wheels"],
                    1e3 * summary["contact_loss_max_s"], text)
    log.info("coupled run done: %.2f s wall, %.2f s per simulated s", raw.wall_s,
             summary["wall_s_per_simulated_s"])
    return table, summary


def check_yaw_range(setup, recorder, train: str = "the train") -> float | None:
    """Largest wheelset yaw of a run (rad, at the output steps) against the yaw the two-point
    contact tables cover (:func:`ttbpipe.vehicle.contact.yaw_table_limit`; beyond it the kernel
    holds the last layer): a warning naming the remedy when it was exceeded. None when the
    geometry has no yaw layers."""
    from ..vehicle.contact import yaw_table_limit

    limit = yaw_table_limit(setup.geom)
    if limit is None or recorder.q_hist.size == 0:
        return None
    yaw = float(np.max(np.abs(recorder.q_hist[:, setup.model.wheelset_dofs[:, 4]])))
    if yaw > limit:
        log.warning("%s: a wheelset yawed %.1f mrad, beyond the %.1f mrad that the contact "
                    "tables cover (train.contact.yaw_max_rad; the last yaw layer was used "
                    "beyond it): raise yaw_max_rad, with yaw_layers keeping the layers about "
                    "5 mrad apart", train, 1e3 * yaw, 1e3 * limit)
    return yaw
