"""Snakemake script of rule study_span_frequencies: EN 1990 A2's f0 and f3 of every span of the
study's structure, once per study (ttbpipe.assessment.modal.span_frequency_record)."""

import json

from ttbpipe.assessment.modal import span_frequency_record
from ttbpipe.io import write_text
from ttbpipe.logs import setup_logging
from ttbpipe.workflow import snakemake_context

snakemake = snakemake_context(globals(), "study_span_frequencies")
setup_logging(snakemake.log[0])
record = span_frequency_record(dict(snakemake.params.structure))
write_text(json.dumps(record, indent=1) + "\n", snakemake.output[0])
