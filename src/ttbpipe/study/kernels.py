"""The coupled model's numba kernels, compiled once per study before its batches run.

A batch job that finds numba's cache empty (a fresh installation, or a cache emptied because the
code changed, :mod:`ttbpipe.kernel_cache`) compiles the coupled loop and its kernels: about 40 s
on the development machine, against about 1.5 s per sample of the default study. Snakemake starts
as many batch jobs as it has cores, so on a fresh checkout every one of the first batches compiled
the same kernels at the same time, and the jobs that did not need them (the inspection and TIPM
stages) waited. :func:`compile_study_kernels` runs the study's nominal case for a few output
intervals -- the same case-building path as a sample (:func:`ttbpipe.study.samples.run_sample`),
so the loop is compiled for the same argument types -- which leaves the kernels in numba's on-disk
cache; the batches then load them (about 1 s).

A kernel the short run did not reach (a configuration only some samples use) is compiled by the
batch that needs it, as before: this step saves time, it decides no result. For the same reason a
compiling run that fails is logged as a warning with its error, and the batches, which run the
samples themselves, report what is wrong with them.
"""

from __future__ import annotations

import copy
import logging
import time
from collections.abc import Mapping
from typing import Any

log = logging.getLogger(__name__)

#: Simulated time of the compiling run, in output intervals of the study: enough to pass every
#: branch of the loop that records output (the first row, a decimated row, the final flush).
COMPILE_RUN_OUTPUT_INTERVALS = 20


class _CompileCounter:
    """Counts numba's compilations (those of callees included) and the wall time of the
    outermost ones (numba.core.event)."""

    def __init__(self) -> None:
        from numba.core import event

        self.count = 0
        self.seconds = 0.0
        self._depth = 0
        self._start = 0.0
        counter = self

        class Listener(event.Listener):
            def on_start(self, ev):
                if counter._depth == 0:
                    counter._start = time.perf_counter()
                counter._depth += 1

            def on_end(self, ev):
                counter._depth -= 1
                counter.count += 1
                if counter._depth == 0:
                    counter.seconds += time.perf_counter() - counter._start

        self._event = event
        self._listener = Listener()

    def __enter__(self) -> _CompileCounter:
        self._event.register("numba:compile", self._listener)
        return self

    def __exit__(self, *exc: Any) -> None:
        self._event.unregister("numba:compile", self._listener)


def compiling_case(config: Mapping[str, Any]) -> dict[str, Any]:
    """The case of the compiling run: the study's nominal structure and train with the single
    mean-spectrum irregularity and the monitors of the selected assessment (as every sample),
    shortened to :data:`COMPILE_RUN_OUTPUT_INTERVALS` output intervals."""
    from ..assessment.study import resolve_assessment, run_case
    from .samples import build_case, mean_spectrum_irregularity, resolve_simulation

    if "structure" not in config:
        raise ValueError("configuration has no structure: section (the study's bridge); copy the "
                         "one in config/config.yaml")
    sim = resolve_simulation(config.get("simulation"))
    irregularity = mean_spectrum_irregularity(sim["irregularity"], int(config["study"]["seed"]))
    case = run_case(build_case(sim, dict(config["structure"]), irregularity=irregularity),
                    resolve_assessment(config.get("assessment")))
    case = copy.deepcopy(case)
    run = case["simulation"]
    run.pop("end_x_m", None)
    run["duration_s"] = COMPILE_RUN_OUTPUT_INTERVALS * float(run["output_interval_s"])
    return case


def compile_study_kernels(config: Mapping[str, Any]) -> dict[str, Any]:
    """Run :func:`compiling_case` once (numba compiles what its cache lacks); returns a record:
    the code version, the kernels compiled now (0: all were cached) and the seconds spent, or
    the error of a compiling run that could not run (logged as a warning, not raised)."""
    from .. import code_version
    from ..simulation.coupled import run_coupled

    record: dict[str, Any] = {"code_version": code_version()}
    compiled = _CompileCounter()
    package_log = logging.getLogger("ttbpipe")
    level = package_log.level
    # the run's own warnings are about its record of a few hundredths of a second (too short
    # for Sperling's window, ...), not about the study
    package_log.setLevel(logging.ERROR)
    start = time.perf_counter()
    try:
        case = compiling_case(config)
        with compiled:
            run_coupled(case)
    except Exception as exc:   # the batches run and report the samples themselves
        log.warning("coupled model's kernels not compiled ahead of the batches (%d compiled; each "
                    "batch compiles what it lacks and reports its samples' errors): the study's "
                    "nominal case failed: %s: %s", compiled.count, type(exc).__name__, exc)
        return {**record, "kernels_compiled": compiled.count,
                "error": f"{type(exc).__name__}: {exc}"}
    finally:
        package_log.setLevel(level)
    wall = time.perf_counter() - start
    log.info("coupled model's kernels: %d compiled in %.1f s (%s), compiling run %.1f s wall",
             compiled.count, compiled.seconds,
             "the cache had them all" if compiled.count == 0 else "written to numba's cache",
             wall)
    return {**record, "kernels_compiled": compiled.count,
            "compile_s": round(compiled.seconds, 3), "wall_s": round(wall, 3)}
