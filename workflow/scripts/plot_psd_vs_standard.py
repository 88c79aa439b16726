"""Snakemake script of rule plot_psd_vs_standard: all campaign PSDs against the standard."""

from pathlib import Path

from ttbpipe.io import read_table, save_figure
from ttbpipe.irregularity.plots import plot_psd_vs_standard
from ttbpipe.logs import setup_logging
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "plot_psd_vs_standard")
setup_logging(snakemake.log[0])
psd_config = snakemake.params.psd
tables = {Path(path).stem: read_table(path) for path in snakemake.input}
band = psd_config.get("wavelength_band_m")
figure = plot_psd_vs_standard(tables, psd_config.get("reference_spectrum", "tbt3352"),
                              None if band is None else tuple(band))
save_figure(figure, snakemake.output[0])
