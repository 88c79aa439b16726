"""The study configuration: one schema for every section, strict validation, the defaults.

The study configuration (``config/config.yaml`` and the paper cases) is described by one JSON
Schema (2020-12), ``schemas/study.schema.yaml``, which takes the ``structure:`` section and the
train of ``simulation.train`` from the case schema ``schemas/simulation.schema.json`` (the same
sections a ``ttbpipe simulate`` case has) by ``$ref``. Every object in both schemas rejects keys
it does not know, so a misspelt key (``simulaton:``, ``time_stp_s``) is an error naming the key,
where it is, and the closest valid key, instead of being silently ignored while a default runs.

Defaults: the study schema's ``default`` values are the only home of the study's defaults.
:func:`validate_study_config` fills them into the configuration (so the provenance of every
table records what actually ran), and the package reads them with :func:`section_defaults`
instead of keeping copies. Sections whose values are resolved by the package itself (the
structure, the train, the limits, the inspection cleaning) carry no schema defaults: their
defaults live beside the code that applies them, with their sources.

The car-parameter names accepted under ``train.motor``, ``train.trailer`` and
``train.car_overrides`` are those of :class:`ttbpipe.vehicle.parameters.CarParameters` (and the
coupler and contact dataclasses): they are written into the case schema when it is loaded, so the
dataclasses stay their one home.
"""

from __future__ import annotations

import copy
import dataclasses
import difflib
import json
from functools import lru_cache
from importlib import resources
from typing import Any, Iterable, Mapping

import yaml
from jsonschema import Draft202012Validator
from referencing import Registry, Resource
from referencing.jsonschema import DRAFT202012

STUDY_SCHEMA = "study.schema.yaml"
CASE_SCHEMA = "simulation.schema.json"


class ConfigurationError(ValueError):
    """An invalid configuration; the message lists every violation with its key path."""


def load_packaged_yaml(text: str) -> Any:
    """A YAML document shipped with the package (schemas, train library), parsed by libyaml's C
    parser when PyYAML has it, else by PyYAML's own: the same safe constructor and resolver, so
    the same data; 0.018 instead of 0.15 s for the study schema, which every job reads. Users'
    files keep ``yaml.safe_load``, whose errors quote the offending line."""
    return yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))


def _read_schema(name: str) -> dict:
    text = resources.files("ttbpipe").joinpath("schemas", name).read_text()
    return load_packaged_yaml(text) if name.endswith(".yaml") else json.loads(text)


def _dataclass_properties(cls: type) -> dict[str, dict]:
    """JSON-schema properties of a parameter dataclass (its field names and value types)."""
    kinds = {float: {"type": "number"}, int: {"type": "integer"}, str: {"type": "string"},
             bool: {"type": "boolean"}, "float": {"type": "number"}, "int": {"type": "integer"},
             "str": {"type": "string"}, "bool": {"type": "boolean"},
             "str | None": {"type": ["string", "null"]}}
    out = {}
    for f in dataclasses.fields(cls):
        out[f.name] = dict(kinds.get(f.type, {}))
    return out


@lru_cache(maxsize=None)
def schema(name: str = STUDY_SCHEMA) -> dict:
    """A packaged schema; the case schema with the vehicle dataclasses' parameter names."""
    doc = _read_schema(name)
    if name == CASE_SCHEMA:
        from .vehicle.parameters import (CONTACT_PROFILES, CREEP_LAWS, CarParameters,
                                         ContactParameters, CouplerParameters)

        car = {"type": "object", "additionalProperties": False,
               "properties": {k: v for k, v in _dataclass_properties(CarParameters).items()
                              if k != "kind"}}
        defs = doc.setdefault("$defs", {})
        defs["car_parameters"] = car
        defs["coupler_parameters"] = {"type": "object", "additionalProperties": False,
                                      "properties": _dataclass_properties(CouplerParameters)}
        contact = _dataclass_properties(ContactParameters)
        contact["profile"] = {"type": "string", "enum": list(CONTACT_PROFILES)}
        contact["creep_law"] = {
            "type": "string", "enum": list(CREEP_LAWS),
            "description": "creep law of every contact point (ttbpipe.vehicle.contact): "
                           "kalker_she = Kalker linear + Shen-Hedrick-Elkins (default); polach = "
                           "Polach 1999 (large spin) with the adhesion fall-off of Polach 2005"}
        contact["polach_k_a"].update(exclusiveMinimum=0, maximum=1, description=(
            "Polach 2005 reduction factor kA in the area of adhesion (1 = Kalker's slope)"))
        contact["polach_k_s"].update(exclusiveMinimum=0, maximum=1, description=(
            "Polach 2005 reduction factor kS in the area of slip, kS <= kA"))
        contact["polach_a"].update(exclusiveMinimum=0, maximum=1, description=(
            "Polach 2005 A = mu_inf / mu0, the friction at infinite slip velocity over friction"))
        contact["polach_b_s_m"].update(minimum=0, description=(
            "Polach 2005 B (s/m), the exponential decrease of the friction with the slip velocity"))
        defs["contact_parameters"] = {"type": "object", "additionalProperties": False,
                                      "properties": contact}
    return doc


@lru_cache(maxsize=1)
def _registry() -> Registry:
    return Registry().with_resources(
        (name, Resource.from_contents(schema(name), default_specification=DRAFT202012))
        for name in (STUDY_SCHEMA, CASE_SCHEMA))


def _validator(name: str) -> Draft202012Validator:
    return Draft202012Validator(schema(name), registry=_registry())


def _resolve(node: Mapping[str, Any], resolver) -> tuple[Mapping[str, Any], Any]:
    """Follow ``$ref`` with ``resolver`` (a referencing Resolver) to the node it names."""
    while "$ref" in node:
        resolved = resolver.lookup(node["$ref"])
        node, resolver = resolved.contents, resolved.resolver
    return node, resolver


def _root(name: str):
    return schema(name), _registry().resolver(base_uri=name)


def _path(parts: Iterable[Any]) -> str:
    text = ""
    for part in parts:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


def _closest(key: str, candidates: Iterable[str]) -> str:
    candidates = sorted(str(c) for c in candidates)
    match = difflib.get_close_matches(str(key), candidates, n=1, cutoff=0.6)
    if match:
        return f"did you mean {match[0]!r}?"
    return f"valid keys here: {', '.join(candidates)}" if candidates else "no keys are valid here"


def _messages(error, source: str) -> list[str]:
    lines = _plain_messages(error, source)
    hint = error.schema.get("x-hint") if isinstance(error.schema, Mapping) else None
    return [f"{line} ({' '.join(str(hint).split())})" for line in lines] if hint else lines


def _plain_messages(error, source: str) -> list[str]:
    where = _path(error.absolute_path)
    at = f"{source}: {where}" if where else f"{source}: (top level)"
    if error.validator == "additionalProperties" and isinstance(error.instance, Mapping):
        known = set(error.schema.get("properties", {}))
        patterns = error.schema.get("patternProperties", {})
        import re

        extra = [k for k in error.instance if k not in known
                 and not any(re.search(p, str(k)) for p in patterns)]
        return [f"{source}: {_path([*error.absolute_path, k])}: unknown key; {_closest(k, known)}"
                for k in extra]
    if "propertyNames" in error.schema_path and error.validator == "enum":
        return [f"{source}: {_path([*error.absolute_path, error.instance])}: unknown key; "
                f"{_closest(error.instance, error.validator_value)}"]
    if error.validator == "enum":
        hint = _closest(error.instance, error.validator_value) if isinstance(error.instance, str) else ""
        return [f"{at}: {error.instance!r} is not one of {error.validator_value}"
                + (f"; {hint}" if hint.startswith("did you mean") else "")]
    if error.validator in ("oneOf", "anyOf") and error.context:
        from jsonschema.exceptions import best_match

        return _plain_messages(best_match(error.context), source)
    return [f"{at}: {error.message}"]


def validate(instance: Any, name: str, source: str) -> None:
    """Raise :class:`ConfigurationError` listing every violation of schema ``name``."""
    errors = sorted(_validator(name).iter_errors(instance), key=lambda e: list(map(str, e.path)))
    lines: list[str] = []
    for error in errors:
        for line in _messages(error, source):
            if line not in lines:
                lines.append(line)
    if lines:
        raise ConfigurationError("invalid configuration:\n  " + "\n  ".join(lines))


def _fill(instance: Any, node: Mapping[str, Any], resolver) -> None:
    """Fill ``default`` values of ``node``'s properties into ``instance`` (in place, recursive)."""
    node, resolver = _resolve(node, resolver)
    if not isinstance(instance, dict):
        return
    for key, sub in node.get("properties", {}).items():
        if key not in instance:
            if "default" in sub:
                instance[key] = copy.deepcopy(sub["default"])
            else:
                resolved, _ = _resolve(sub, resolver)
                if "default" in resolved:
                    instance[key] = copy.deepcopy(resolved["default"])
        if key in instance:
            _fill(instance[key], sub, resolver)


def _node(name: str, path: Iterable[str]):
    node, resolver = _root(name)
    for key in path:
        node, resolver = _resolve(node, resolver)
        node = node["properties"][key]
    return _resolve(node, resolver)


def fill_defaults(instance: dict, name: str = STUDY_SCHEMA, *path: str) -> dict:
    """``instance`` (the section at ``path`` of schema ``name``) with its defaults filled in."""
    node, resolver = _node(name, path)
    _fill(instance, node, resolver)
    return instance


def section_defaults(*path: str) -> dict[str, Any]:
    """The study schema's defaults of the section at ``path`` (e.g. ``"simulation"``)."""
    return fill_defaults({}, STUDY_SCHEMA, *path)


def validate_section(section: Mapping[str, Any] | None, *path: str, source: str = "config") -> dict:
    """Validate one section of the study configuration (``path`` below the top level) and
    return a copy with its defaults filled in (for code called outside the workflow)."""
    section = copy.deepcopy(dict(section or {}))
    node, _ = _node(STUDY_SCHEMA, path)
    errors = sorted(Draft202012Validator(node, registry=_registry()).iter_errors(section),
                    key=lambda e: list(map(str, e.path)))
    lines: list[str] = []
    for error in errors:
        error.path.extendleft(reversed(path))
        for line in _messages(error, source):
            if line not in lines:
                lines.append(line)
    if lines:
        raise ConfigurationError("invalid configuration:\n  " + "\n  ".join(lines))
    return fill_defaults(section, STUDY_SCHEMA, *path)


def validate_study_config(config: dict, source: str = "config") -> dict:
    """Validate a whole study configuration and fill in its defaults (in place); return it."""
    validate(config, STUDY_SCHEMA, source)
    filled = fill_defaults(config, STUDY_SCHEMA)
    if "assessment" in filled:
        # the profiles' options are checked against the profiles' own defaults (their one home)
        from .assessment.study import resolve_assessment

        try:
            resolve_assessment(filled["assessment"])
        except ValueError as exc:
            raise ConfigurationError(f"invalid configuration ({source}): {exc}") from None
    return filled


def validate_scale_overlays(config: Mapping[str, Any], source: str = "config") -> None:
    """Validate the ``small:`` / ``medium:`` overlays of a paper case that this run does not
    apply (each merged into a copy of the configuration), so that a misspelt key in one is an
    error now and not when that scale is first run. Call before
    :func:`ttbpipe.study.cases.apply_scale` removes them."""
    from .study.cases import SCALES, _merge

    scale = str(config.get("scale", "full"))
    base = {k: v for k, v in config.items() if k not in SCALES[1:] and k != "scale"}
    for name in SCALES[1:]:
        overlay = config.get(name)
        if overlay and name != scale:
            trial = copy.deepcopy(base)
            _merge(trial, overlay)
            validate(trial, STUDY_SCHEMA, f"{source} ({name}: overlay)")


def validate_case_config(case: Mapping[str, Any], source: str = "case") -> dict:
    """Validate a ``ttbpipe simulate`` case (schema ``simulation.schema.json``)."""
    validate(case, CASE_SCHEMA, source)
    return dict(case)
