"""One deterministic simulation case: ``ttbpipe simulate CONFIG.yaml --out RESULT.parquet``.

* :mod:`ttbpipe.simulation.config` -- case YAML schema (schemas/simulation.schema.json) and loader;
* :mod:`ttbpipe.simulation.run` -- moving-load cases on the structure (issue 3);
* :mod:`ttbpipe.simulation.coupled` -- train cases (vehicle owner), used when the case has ``train:``;
* :mod:`ttbpipe.simulation.cli` -- the command.
"""
