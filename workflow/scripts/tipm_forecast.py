"""Snakemake script of rule tipm_forecast: forecast spectra and profiles of the latest campaign."""

from ttbpipe.io import read_provenance, read_table, save_figure, write_table
from ttbpipe.logs import setup_logging
from ttbpipe.tipm.evolution import SpectralEvolution
from ttbpipe.tipm.profiles import PROFILE_ID_COLUMN, write_profiles
from ttbpipe.tipm.plots import plot_forecast_spectra
from ttbpipe.tipm.stages import forecast_base, forecast_stage
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "tipm_forecast")
setup_logging(snakemake.log[0])
model = SpectralEvolution.from_table(read_table(snakemake.input.model),
                                     read_provenance(snakemake.input.model)["model"])
base = forecast_base(snakemake.params.tipm, snakemake.params.psd, snakemake.input.latest_psd,
                     read_table(snakemake.input.selection), read_table(snakemake.input.weights))
forecast, states, profiles = forecast_stage(model, base, snakemake.params.base_date,
                                            snakemake.params.tipm, snakemake.params.psd,
                                            snakemake.params.seed)
extra = dict(config=snakemake.config, base_date=snakemake.params.base_date)
write_table(forecast, snakemake.output.forecast, kind="tipm_forecast", **extra)
write_table(states, snakemake.output.states, kind="tipm_forecast_states", **extra)
write_profiles(profiles, snakemake.output.profiles, id_column=PROFILE_ID_COLUMN["forecast"],
               kind="tipm_forecast_profiles", **extra)
save_figure(plot_forecast_spectra(forecast, base, snakemake.params.base_date),
            snakemake.output.figure)
