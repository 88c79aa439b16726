"""``ttbpipe simulate CONFIG.yaml --out RESULT.parquet``: one deterministic case.

Cases with a ``train:`` section go to :func:`ttbpipe.simulation.coupled.run_coupled`; cases with
``loads:`` run moving loads on the structure (:mod:`ttbpipe.simulation.moving_load_case`).
The table (time_s + monitor columns with units) is written atomically with the resolved case in
its provenance (kind "simulation").

Exit status 1, nothing written, with the message on stderr: an invalid case, a refused time step
(the message proposes a step that passes every stability limit, or ``time_step_s: auto``, which
one case may use), a run that stopped (non-finite state, every wheel off the rail, divergence:
the message names the likely cause, e.g. the irregularity, and its remedy) or a non-finite value
in the results. A run in which wheels lose contact but which completes is a result (exit 0):
its loss-of-contact index is in the summary (``contact_loss_*``), Q/P is 0 where a wheel is off
the rail (``<wheel>_in_contact`` = 0).
"""

from __future__ import annotations

import argparse
import logging
import sys

log = logging.getLogger(__name__)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("config", help="case YAML (schema: src/ttbpipe/schemas/simulation.schema.json)")
    parser.add_argument("--out", required=True, help="output Parquet table")


def run(args: argparse.Namespace) -> int:
    from ..io import write_table
    from .config import load_case

    try:
        case = load_case(args.config)
        if "train" in case:
            from .coupled import SimulationStopped, run_coupled

            try:
                table, summary = run_coupled(case, propose_auto=True)
            except SimulationStopped as exc:
                raise ValueError(str(exc)) from exc
        else:
            from .moving_load_case import run_moving_loads
            table, summary = run_moving_loads(case)
    except (ValueError, FloatingPointError) as exc:
        print(f"ttbpipe simulate: {exc}", file=sys.stderr)
        return 1
    write_table(table, args.out, config=case, kind="simulation", summary=summary)
    log.info("wrote %s (%d rows, %d columns)", args.out, len(table), table.shape[1])
    return 0
