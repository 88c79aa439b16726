"""Snakemake script of rule study_kernels: the coupled model's numba kernels compiled into
numba's cache by a short run of the study's nominal case (ttbpipe.study.kernels)."""

import json

from ttbpipe.io import write_text
from ttbpipe.logs import setup_logging
from ttbpipe.study.kernels import compile_study_kernels
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "study_kernels")
setup_logging(snakemake.log[0])
record = compile_study_kernels(dict(snakemake.config))
write_text(json.dumps(record, indent=1) + "\n", snakemake.output[0])
