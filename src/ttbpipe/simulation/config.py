"""Case configuration: YAML -> validated dict (JSON Schema 2020-12, schemas/simulation.schema.json).

Errors name the file and the offending key path, e.g.
``case.yaml: structure.girder.damping_ratio: -0.1 is less than the minimum of 0``.
Structure defaults are filled by :func:`ttbpipe.structure.properties.resolve` when the model is
built; the schema's defaults document them.
"""

from __future__ import annotations

import json
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

import yaml
from jsonschema import Draft202012Validator


@lru_cache(maxsize=1)
def schema() -> dict:
    """The case schema (packaged JSON)."""
    # files("ttbpipe") / "schemas": works whether or not schemas/ is a package (package-data)
    return json.loads(resources.files("ttbpipe").joinpath("schemas", "simulation.schema.json")
                      .read_text())


def _path(err) -> str:
    return ".".join(str(p) for p in err.absolute_path) or "(top level)"


def validate_case(case: Mapping[str, Any], source: str = "case") -> dict:
    """Validate a case dict; raise ValueError listing every violation with its key path."""
    if not isinstance(case, Mapping):
        raise ValueError(f"{source}: the case must be a YAML mapping, got {type(case).__name__}")
    errors = sorted(Draft202012Validator(schema()).iter_errors(case), key=lambda e: list(e.path))
    if errors:
        lines = [f"{source}: {_path(e)}: {e.message}" for e in errors]
        raise ValueError("invalid simulation case:\n  " + "\n  ".join(lines))
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
