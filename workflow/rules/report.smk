# Stage: study aggregation, reliability and the report (docs/studies.md, docs/reliability.md).
# Checks every batch file's provenance against the current settings (a stale or unreadable batch
# stops the aggregation, naming the files and the command that remakes them), then reads them one
# at a time (memory independent of the sample count).

STUDY_OUT = results_path("study")


rule aggregate_study:
    """Extremes, history statistics, exceedance probabilities, Table 1, figures, report pages."""
    input:
        unpack(study_batch_files),
        designs=study_design_files(),
    output:
        design=f"{STUDY_OUT}/design.parquet",
        extremes=f"{STUDY_OUT}/extremes.parquet",
        history=f"{STUDY_OUT}/history_statistics.parquet",
        reliability=f"{STUDY_OUT}/reliability.parquet",
        utilisation=f"{STUDY_OUT}/utilisation.parquet",
        convergence=f"{STUDY_OUT}/convergence.parquet",
        table1=f"{STUDY_OUT}/table1_std.parquet",
        table1_history=f"{STUDY_OUT}/table1_history_std.parquet",
        summary_rst=f"{STUDY_OUT}/summary.rst",
        summary=report(
            f"{STUDY_OUT}/report/summary.html",
            # the caption is the generated first page itself: the report's main page
            # (workflow/report/workflow.rst) embeds it
            caption=report_caption_path(f"{STUDY_OUT}/summary.rst"),
            category="0. Summary",
        ),
        reliability_html=report(
            f"{STUDY_OUT}/report/reliability.html",
            caption="../report/study_reliability.rst",
            category="0. Summary",
        ),
        utilisation_html=report(
            f"{STUDY_OUT}/report/utilisation.html",
            caption="../report/study_utilisation.rst",
            category="1. Margins to the limits",
        ),
        table1_html=report(
            f"{STUDY_OUT}/report/table1_std.html",
            caption="../report/study_table1.rst",
            category="6. Randomness of parameters (Table 1)",
        ),
        table1_history_html=report(
            f"{STUDY_OUT}/report/table1_history_std.html",
            caption="../report/study_table1_history.rst",
            category="6. Randomness of parameters (Table 1)",
        ),
        configuration=report(
            f"{STUDY_OUT}/report/configuration.html",
            caption="../report/study_configuration.rst",
            category="9. Configuration",
        ),
        utilisation_figures=report(
            directory(f"{STUDY_OUT}/figures/utilisation"),
            patterns=["{section}.png"],
            caption="../report/stats_utilisation.rst",
            category="1. Margins to the limits",
        ),
        convergence_figures=report(
            directory(f"{STUDY_OUT}/figures/convergence"),
            patterns=["{scenario}.png"],
            caption="../report/stats_exceedance_convergence.rst",
            category="4. Reliability",
            subcategory="Convergence of exceedance probabilities",
        ),
        pdf_figures=report(
            directory(f"{STUDY_OUT}/figures/pdf"),
            # the group is one word: a greedy {group} would swallow part of the index name
            patterns=["{group,irregularity|fields}_{index}.png"],
            caption="../report/stats_extreme_pdfs.rst",
            category="5. Extremes",
            subcategory="{group} scenarios",
        ),
        history_figures=report(
            directory(f"{STUDY_OUT}/figures/history"),
            patterns=["{group,irregularity|fields}_{quantity}.png"],
            caption="../report/stats_history_statistics.rst",
            category="7. Time histories",
            subcategory="{group} scenarios",
        ),
        envelope_figures=report(
            directory(f"{STUDY_OUT}/figures/envelope"),
            patterns=["{index}.png"],
            caption="../report/stats_forecast_envelope.rst",
            category="8. Forecast",
        ),
    # tail fits and figures in two processes (ttbpipe.parallel); the job runs alone at the end
    threads: 2
    params:
        limits=config.get("limits"),
        settings=STUDY_SETTINGS,
        version=MODEL_VERSION,
    log:
        log_path("study/aggregate.log"),
    script:
        "../scripts/aggregate_study.py"


def study_targets() -> list[str]:
    """Final outputs of the study (every batch is known from the plan: ttbpipe.study.plan)."""
    return [f"{STUDY_OUT}/extremes.parquet", f"{STUDY_OUT}/report/summary.html"]
