"""Run a workflow script outside Snakemake, for debugging (the PyPSA-Eur pattern).

Every script in ``workflow/scripts`` starts with::

    from ttbpipe.workflow import snakemake_context
    snakemake = snakemake_context(globals(), "study_design", scenario="C1")

Under Snakemake this returns the ``snakemake`` object Snakemake injected. Run directly
(``python workflow/scripts/study_design.py [key=value ...]`` from the repository root), it parses
the Snakefile with the default configuration and builds the same object for the named rule, with
the wildcards given as defaults or as ``key=value`` arguments on the command line; a
``--configfile=PATH`` argument selects another study configuration.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any


def _repository_root(start: Path) -> Path:
    for candidate in [start, *start.parents]:
        if (candidate / "Snakefile").is_file():
            return candidate
    raise FileNotFoundError(f"no Snakefile above {start}")


def mock_snakemake(rule_name: str, configfiles: list[str] | None = None,
                   root: str | os.PathLike[str] | None = None, **wildcards: Any) -> Any:
    """Build the ``snakemake`` object of one job of ``rule_name`` without running Snakemake."""
    from snakemake.api import SnakemakeApi
    from snakemake.dag import DAG
    from snakemake.iocontainers import Snakemake
    from snakemake.jobs import Job
    from snakemake.settings.types import (ConfigSettings, DAGSettings, OutputSettings, ResourceSettings,
                                          StorageSettings, WorkflowSettings)

    root_path = _repository_root(Path(root or Path.cwd()).resolve())
    previous = Path.cwd()
    try:
        with SnakemakeApi(OutputSettings(quiet={"all"})) as api:
            workflow_api = api.workflow(
                resource_settings=ResourceSettings(cores=1),
                config_settings=ConfigSettings(
                    configfiles=[Path(p).resolve() for p in (configfiles or [])]),
                storage_settings=StorageSettings(),
                workflow_settings=WorkflowSettings(),
                snakefile=root_path / "Snakefile",
                workdir=root_path,
            )
            workflow = workflow_api._workflow
            workflow.dag_settings = DAGSettings()
            workflow.global_resources = {}
            rule = workflow.get_rule(rule_name)
            dag = DAG(workflow, rules=[rule])
            # a default wildcard may be a function of the parsed workflow's globals and the
            # other wildcards (e.g. the settings digest of a batch's scenario)
            plain = {k: v for k, v in wildcards.items() if not callable(v)}
            wildcards = {k: (v(workflow.globals, plain) if callable(v) else v)
                         for k, v in wildcards.items()}
            job = Job(rule, dag, dict(wildcards))
            return Snakemake(job.input, job.output, job.params, job.wildcards, 1,
                             job.resources, job.log, workflow.config, rule.name, None,
                             scriptdir=str(root_path / "workflow" / "scripts"))
    finally:
        os.chdir(previous)


def snakemake_context(script_globals: dict[str, Any], rule_name: str, **default_wildcards: Any) -> Any:
    """Return Snakemake's injected object, or a mock of it when the script runs on its own."""
    if "snakemake" in script_globals:
        return script_globals["snakemake"]
    wildcards = dict(default_wildcards)
    configfiles: list[str] = []
    for arg in sys.argv[1:]:
        if arg.startswith("--configfile="):
            configfiles.append(arg.split("=", 1)[1])
        elif "=" in arg:
            key, value = arg.split("=", 1)
            wildcards[key] = value
    root = _repository_root(Path.cwd().resolve())
    os.chdir(root)  # outputs and logs are relative to the repository root, as under Snakemake
    return mock_snakemake(rule_name, configfiles=configfiles, root=root, **wildcards)
