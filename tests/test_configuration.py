"""Strict configuration (ttbpipe.configuration): one schema for every section of the study and of
``ttbpipe simulate`` cases; an unknown key anywhere is an error naming the key, where it is, and
the closest valid key; the study schema is the only home of the study's defaults."""

from __future__ import annotations

import copy
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from ttbpipe import configuration
from ttbpipe.configuration import ConfigurationError, validate_study_config

REPO = Path(__file__).resolve().parents[1]
DEFAULT = yaml.safe_load((REPO / "config" / "config.yaml").read_text())


def _error(config) -> str:
    with pytest.raises(ConfigurationError) as info:
        validate_study_config(copy.deepcopy(config), "study.yaml")
    return str(info.value)


def _with(path: str, value, config=DEFAULT):
    config = copy.deepcopy(config)
    *parents, last = path.split(".")
    node = config
    for key in parents:
        node = node.setdefault(key, {})
    node[last] = value
    return config


def test_the_shipped_configurations_are_valid():
    validate_study_config(copy.deepcopy(DEFAULT), "config/config.yaml")


@pytest.mark.parametrize("path,closest", [
    ("limts", "limits"),                                   # top level
    ("simulaton", "simulation"),
    ("simulation.time_stp_s", "time_step_s"),              # a section's key
    ("simulation.history.wheeel", "wheel"),
    ("structure.layout.spans", "spans_m"),                 # the structure (case schema, $ref)
    ("structure.girdr", "girder"),
    ("simulation.train.compositon", "composition"),        # the train (case schema, $ref)
    ("simulation.train.motor.car_mas", "car_mass"),        # car parameters (the dataclass)
    ("simulation.train.contact.conicty", "conicity"),
    ("study.scenarios.fields.sample", "samples"),
    ("tipm.selection.fracton", "fraction"),
    ("limits.thresholds.derailment_coeficient", "derailment_coefficient"),
])
def test_a_misspelt_key_anywhere_is_named_with_the_closest_valid_one(path, closest):
    value = 1.0 if path.startswith("limits.thresholds") else {} if path.count(".") == 0 else 1
    message = _error(_with(path, value))
    assert f"study.yaml: {path}: unknown key; did you mean '{closest}'?" in message, message


def test_a_study_rejects_time_step_auto_and_says_why():
    message = _error(_with("simulation.time_step_s", "auto"))
    assert "simulation.time_step_s: 'auto' is not of type 'number'" in message
    assert "share one time grid" in message


def test_every_violation_is_listed_at_once():
    config = _with("simulation.time_stp_s", 1.0, _with("limts", {}))
    message = _error(config)
    assert "limts: unknown key" in message and "simulation.time_stp_s: unknown key" in message


def test_defaults_are_filled_from_the_schema():
    """A section left out gets the schema's defaults (what ran is what the provenance says)."""
    config = copy.deepcopy(DEFAULT)
    del config["simulation"]
    validate_study_config(config, "study.yaml")
    assert config["simulation"] == configuration.section_defaults("simulation")
    assert config["simulation"]["time_step_s"] == 1.0e-4
    assert config["simulation"]["history"]["wheel"] == "car1_ws1_left"


def test_every_schema_default_is_a_valid_value_of_its_own_key():
    """A default that its own property schema rejects would be a silent wrong default."""
    from jsonschema import Draft202012Validator

    bad, checked = [], []

    def walk(node, path, resolver):
        node, resolver = configuration._resolve(node, resolver)
        for key, sub in node.get("properties", {}).items():
            if "default" in sub:
                checked.append(f"{path}{key}")
                errors = list(Draft202012Validator(sub, registry=configuration._registry())
                              .iter_errors(sub["default"]))
                if errors:
                    bad.append((f"{path}{key}", errors[0].message))
            walk(sub, f"{path}{key}.", resolver)

    root, resolver = configuration._root(configuration.STUDY_SCHEMA)
    walk(root, "", resolver)
    assert len(checked) > 50 and "simulation.history.wheel" in checked
    assert not bad


@pytest.mark.parametrize("section,key,closest", [
    ("simulation", "time_stp_s", "time_step_s"),
    ("irregularity", "spectrun", "spectrum"),
    ("train", "compositon", "composition"),
])
def test_case_files_reject_unknown_keys_in_every_section(tmp_path, section, key, closest):
    from ttbpipe.simulation.config import load_case

    case = yaml.safe_load((REPO / "config" / "reference_case.yaml").read_text())
    case.setdefault(section, {})[key] = 1
    path = tmp_path / "case.yaml"
    path.write_text(yaml.safe_dump(case))
    with pytest.raises(ValueError, match=rf"case.yaml: {section}.{key}: unknown key; "
                                         rf"did you mean '{closest}'\?"):
        load_case(path)


def test_an_overlay_that_this_run_does_not_apply_is_validated_too():
    case = yaml.safe_load((REPO / "config" / "case2.yaml").read_text())
    config = copy.deepcopy(DEFAULT)
    from ttbpipe.study.cases import _merge

    _merge(config, case)
    config["medium"]["simulation"] = {"batch_sise": 8}
    with pytest.raises(ConfigurationError, match=r"\(medium: overlay\): simulation.batch_sise: "
                                                 r"unknown key; did you mean 'batch_size'\?"):
        configuration.validate_scale_overlays(config, "case2.yaml")


@pytest.mark.slow
def test_snakemake_dry_run_rejects_unknown_keys(tmp_path):
    """What a user sees: `snakemake -n` stops before any job, naming each unknown key."""
    from test_workflow import _copy_repository

    _copy_repository(tmp_path)
    (tmp_path / "bad.yaml").write_text(
        "limts: {}\nsimulation:\n  time_stp_s: 2.0e-4\nstructure:\n  layout: {spans: [20.0]}\n")
    result = subprocess.run([sys.executable, "-m", "snakemake", "-n", "--cores", "1",
                             "--configfile", "bad.yaml"], cwd=tmp_path, capture_output=True,
                            text=True)
    text = result.stdout + result.stderr
    assert result.returncode != 0
    for line in ("limts: unknown key; did you mean 'limits'?",
                 "simulation.time_stp_s: unknown key; did you mean 'time_step_s'?",
                 "structure.layout.spans: unknown key; did you mean 'spans_m'?"):
        assert line in text, text[-3000:]


def test_packaged_yaml_parses_as_pyyaml_safe_load_does():
    """The schemas and the train library are read by libyaml's parser where PyYAML has it
    (load_packaged_yaml): every packaged YAML file gives the same data as yaml.safe_load."""
    files = sorted((REPO / "src" / "ttbpipe").rglob("*.yaml"))
    assert any(f.name == "study.schema.yaml" for f in files) and len(files) >= 3
    for path in files:
        text = path.read_text(encoding="utf-8")
        assert configuration.load_packaged_yaml(text) == yaml.safe_load(text), path
