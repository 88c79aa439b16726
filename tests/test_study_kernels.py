"""The coupled model's kernels compiled once per study (ttbpipe.study.kernels, rule study_kernels).

What is checked and against what:

* the compiling run is the study's own sample case (the path of ``run_sample``: nominal
  structure, train, mean-spectrum irregularity, the selected assessment's monitors), shortened:
  the two case dictionaries are equal apart from the run's length;
* the claim the rule exists for: after the compiling run has filled an empty numba cache, a
  sample of the study run in another process -- as a batch job runs -- compiles nothing (numba's
  compile events counted in that process; a kernel reached with other argument types would be
  compiled and counted). Both processes use their own, initially empty, ``NUMBA_CACHE_DIR``.
"""

import copy
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from test_study_batch import CONFIG as BATCH_CONFIG
from ttbpipe.study import kernels as study_kernels
from ttbpipe.study import samples as study_samples

ROOT = Path(__file__).resolve().parents[1]

# The tiny fields study of tests/test_study_batch.py (one trailer car, one 32 m span; its
# assessment is off: the run is too short for the standards' windows, and the compiled kernels do
# not depend on it), with one C2 sample.
TINY = copy.deepcopy(BATCH_CONFIG)
TINY["study"]["scenarios"]["fields"]["samples"] = 1


def test_compiling_case_is_the_sample_case_shortened(monkeypatch):
    """The default study's configuration: the compiling run's case equals the case a sample of
    the single/fields kind builds (captured from run_sample) except the run's end."""
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    captured = {}

    def fake_run_coupled(case, **kwargs):
        captured["case"] = case
        raise RuntimeError("stop after the case is built")

    import ttbpipe.simulation.coupled as coupled

    monkeypatch.setattr(coupled, "run_coupled", fake_run_coupled)
    from ttbpipe.assessment.study import resolve_assessment

    row = {"kind": "single", "sample_index": 0, "scenario": "single", "weight": 1.0,
           "seed_entropy": "0"}
    with pytest.raises(RuntimeError, match="stop after the case is built"):
        study_samples.run_sample(
            row, study_seed=int(config["study"]["seed"]),
            sim=study_samples.resolve_simulation(config["simulation"]),
            structure=config["structure"], fields=None, profiles={},
            assessment=resolve_assessment(config.get("assessment")))
    sample_case = captured["case"]
    compiling = study_kernels.compiling_case(config)
    assert compiling["simulation"]["duration_s"] == pytest.approx(
        study_kernels.COMPILE_RUN_OUTPUT_INTERVALS * sample_case["simulation"]["output_interval_s"])
    assert "end_x_m" not in compiling["simulation"]
    strip = lambda case: {**case, "simulation": {k: v for k, v in case["simulation"].items()
                                                 if k not in ("end_x_m", "duration_s")}}
    assert strip(compiling) == strip(sample_case)
    assert compiling.get("monitors"), "the default assessment's twist monitors are in the case"


def test_a_case_that_cannot_be_built_is_a_warning_not_an_error(caplog):
    """The step only saves time: a configuration the compiling run cannot use is logged (the
    batches then compile, and report the configuration's error themselves)."""
    config = {k: v for k, v in TINY.items() if k != "structure"}
    with caplog.at_level("WARNING", logger="ttbpipe.study.kernels"):
        record = study_kernels.compile_study_kernels(config)
    assert record["kernels_compiled"] == 0
    assert "no structure: section" in record["error"]
    assert "not compiled ahead of the batches" in caplog.text


CHILD = r"""
import json, sys, time
from numba.core import event
from ttbpipe.study import kernels
config = json.loads(sys.argv[2])
if sys.argv[1] == "compile":
    print(json.dumps(kernels.compile_study_kernels(config)))
else:
    from ttbpipe.study import samples
    from ttbpipe.study.batch import _sample_kwargs
    from ttbpipe.study.design import build_design
    design = build_design(config["study"], latest_campaign="2025-12-15", horizons_months=[])
    row = design.to_dict("records")[0]
    with kernels._CompileCounter() as compiled:
        extremes, _ = samples.run_sample(row, **_sample_kwargs(config, {}))
    print(json.dumps({"kernels_compiled": compiled.count, "compile_s": compiled.seconds,
                      "kind": row["kind"]}))
"""


@pytest.mark.slow
def test_a_sample_compiles_nothing_after_the_compiling_run(tmp_path):
    """Fresh numba cache; process 1 runs the compiling run (it must compile: the cache was
    empty), process 2 runs the study's first sample (a C2 fields sample) and must compile
    nothing."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba_cache")}
    config = json.dumps(TINY)

    def child(mode):
        proc = subprocess.run([sys.executable, "-c", CHILD, mode, config], env=env,
                              capture_output=True, text=True, cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr[-3000:]
        return json.loads(proc.stdout.strip().splitlines()[-1])

    first = child("compile")
    assert first["kernels_compiled"] > 0, "an empty cache: the compiling run compiles"
    second = child("sample")
    assert second["kind"] == "fields"
    assert second["kernels_compiled"] == 0, second
