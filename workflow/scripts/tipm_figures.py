"""Snakemake script of rule tipm_figures: PSD bands and selection fidelity of one campaign."""

from ttbpipe.io import read_table, save_figure
from ttbpipe.logs import setup_logging
from ttbpipe.tipm.plots import plot_psd_bands, plot_selection_fidelity
from ttbpipe.tipm.population import PSDPopulation, load_population
from ttbpipe.tipm.selection import TIPMSelection
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "tipm_figures", date="2025-12-15")
setup_logging(snakemake.log[0])
population = PSDPopulation.concat(load_population(list(snakemake.input.psd),
                                                  snakemake.params.psd.get("wavelength_band_m")))
selection = TIPMSelection.from_long_table(read_table(snakemake.input.selection),
                                          read_table(snakemake.input.weights))
date = snakemake.wildcards.date
save_figure(plot_psd_bands(population, selection,
                           f"campaign {date}: {population.n_sections} sections, "
                           f"{selection.n_samples} representative sets"), snakemake.output.bands)
save_figure(plot_selection_fidelity(population, selection, read_table(snakemake.input.metrics),
                                    f"campaign {date}: selected sets against the population"),
            snakemake.output.fidelity)
