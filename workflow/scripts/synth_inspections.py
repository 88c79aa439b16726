"""Snakemake script of rule synth_inspections: write the synthetic default campaigns."""

from pathlib import Path

from ttbpipe.inspection.synthetic import write_synthetic_campaigns
from ttbpipe.logs import setup_logging
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "synth_inspections")
setup_logging(snakemake.log[0])
synthetic = snakemake.params.synthetic
write_synthetic_campaigns(
    Path(snakemake.output[0]).parent,
    dates=list(snakemake.params.dates),
    spectrum=synthetic.get("spectrum", "tbt3352"),
    length_km=synthetic.get("length_km", 5.0),
    seed=synthetic.get("seed", 1),
    fmt="parquet",
    config=snakemake.config,
)
