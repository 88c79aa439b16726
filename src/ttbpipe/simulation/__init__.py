"""Simulation cases: coupled train-track-bridge runs and moving-load runs of the structure.

* :mod:`.coupled` -- :func:`run_coupled`, a coupled run: :mod:`.setup` (case -> train,
  structure, track input, step, static state), :mod:`.loop` (the numba time loop),
  :mod:`.recorder` (what the loop records of the train), :mod:`.outputs` (time histories,
  response indices, summary), :mod:`.diagnosis` (why a run stopped);
* :mod:`.moving_load_case` -- moving-load cases on the structure alone (validation);
* :mod:`.hunting` -- hunting runs on rigid straight track: disturbed starts, growth rates,
  stepwise ramp-down (docs/vehicle.md section 10);
* :mod:`.config` -- case YAML schema (schemas/simulation.schema.json) and loader;
* :mod:`.cli` -- ``ttbpipe simulate CONFIG.yaml --out RESULT.parquet``.

Architecture and interfaces: docs/dev/architecture.md.
"""
