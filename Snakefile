# ttbpipe: probabilistic dynamic assessment of railway train-track-bridge systems.
#
#   snakemake --cores 2                       # the default study (config/config.yaml)
#   snakemake --cores 2 --configfile X.yaml   # another study
#   snakemake --report results/report.html    # the report (after a run)
#
# Stages live in workflow/rules/*.smk; scripts in workflow/scripts are thin and call the package.

from snakemake.utils import min_version

min_version("9.0")

configfile: "config/config.yaml"


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"
include: "workflow/rules/inspections.smk"
include: "workflow/rules/tipm.smk"
include: "workflow/rules/fields.smk"
include: "workflow/rules/study.smk"
include: "workflow/rules/report.smk"
include: "workflow/rules/reliability.smk"
include: "workflow/rules/cases.smk"
include: "workflow/rules/en1991.smk"


rule all:
    input:
        all_targets(),
    default_target: True
