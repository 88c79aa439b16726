"""Case configuration: YAML -> validated dict (JSON Schema 2020-12, schemas/simulation.schema.json).

Errors name the file and the offending key path, e.g.
``case.yaml: structure.girder.damping_ratio: -0.1 is less than the minimum of 0``, and for an
unknown key the closest valid one (``case.yaml: simulation.time_stp_s: unknown key; did you mean
'time_step_s'?``). Validation is :mod:`ttbpipe.configuration`'s, shared with the study
configuration. Structure defaults are filled by :func:`ttbpipe.structure.properties.resolve`
when the model is built, run defaults by the simulation code: the schema carries none.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import yaml

from ..configuration import CASE_SCHEMA, ConfigurationError, validate_case_config
from ..configuration import schema as _schema


def schema() -> dict:
    """The case schema (packaged JSON, with the vehicle dataclasses' parameter names)."""
    return _schema(CASE_SCHEMA)


def validate_case(case: Mapping[str, Any], source: str = "case") -> dict:
    """Validate a case dict; raise ValueError listing every violation with its key path."""
    if not isinstance(case, Mapping):
        raise ValueError(f"{source}: the case must be a YAML mapping, got {type(case).__name__}")
    try:
        validate_case_config(case, source)
    except ConfigurationError as exc:
        raise ValueError(str(exc).replace("invalid configuration:", "invalid simulation case:", 1)) from None
    if "train" not in case and "loads" not in case:
        raise ValueError(f"{source}: give a loads: section (moving loads) or a train: section")
    return dict(case)


def load_case(path: str | Path) -> dict:
    """Read and validate a case YAML file."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the case file ({exc})") from exc
    try:
        case = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise ValueError(f"{path}: not valid YAML ({exc})") from exc
    return validate_case(case or {}, str(path))
