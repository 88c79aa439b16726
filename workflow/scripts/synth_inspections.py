"""Snakemake script of rule synth_inspections: write the synthetic default campaigns."""

from pathlib import Path

from ttbpipe.inspection.synthetic import write_synthetic_campaigns
from ttbpipe.logs import setup_logging

setup_logging(snakemake.log[0])  # noqa: F821 (snakemake object injected by Snakemake)
synthetic = snakemake.params.synthetic  # noqa: F821
write_synthetic_campaigns(
    Path(snakemake.output[0]).parent,  # noqa: F821
    dates=list(snakemake.params.dates),  # noqa: F821
    spectrum=synthetic.get("spectrum", "tbt3352"),
    length_km=synthetic.get("length_km", 5.0),
    seed=synthetic.get("seed", 1),
    fmt="parquet",
    config=snakemake.config,  # noqa: F821
)
