"""Snakemake script of rule study_design: the samples of one scenario (docs/studies.md)."""

from ttbpipe.io import read_table, write_table
from ttbpipe.logs import setup_logging
from ttbpipe.study.design import scenario_design
from ttbpipe.tipm.population import read_pooled_population
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "study_design", scenario="C1")
setup_logging(snakemake.log[0])
inputs, p = snakemake.input, snakemake.params.design
design = scenario_design(
    {"seed": p["seed"], "scenarios": p["scenario"]}, snakemake.wildcards.scenario, kind=p["kind"],
    latest_campaign=p.get("latest_campaign", ""),
    tipm_weights=read_table(inputs.weights) if "weights" in inputs.keys() else None,
    forecast_states=read_table(inputs.states) if "states" in inputs.keys() else None,
    horizons_months=p.get("horizons_months", ()),
    n_population_sections=(read_pooled_population(inputs.population,
                                                  p["wavelength_band_m"]).n_sections
                           if "population" in inputs.keys() else None),
    expected_samples=p["expected_samples"])
write_table(design, snakemake.output[0], config=snakemake.config, kind="study_design",
            scenario=snakemake.wildcards.scenario)
