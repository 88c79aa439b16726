"""Snakemake script of rule study_mc_population: the Monte Carlo irregularity scenario's PSD
population pooled into one table (ttbpipe.tipm.population.write_pooled_population)."""

import logging

from ttbpipe.logs import setup_logging
from ttbpipe.tipm.population import write_pooled_population
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "study_mc_population")
setup_logging(snakemake.log[0])
population = write_pooled_population([str(p) for p in snakemake.input.psds],
                                     snakemake.params.wavelength_band_m, snakemake.output[0],
                                     config=snakemake.config)
logging.getLogger("ttbpipe").info("pooled %d sections of %d campaigns, %d frequencies, channels %s",
                                  population.n_sections, len(snakemake.input.psds),
                                  population.frequency_per_m.size, ", ".join(population.channels))
