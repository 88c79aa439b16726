# Paper case studies (seed paper section 5; docs/validation.md). Active only when the
# configuration has a `case:` section (config/case1.yaml .. case4.yaml); then `snakemake` builds
# exactly the case's targets (all_targets() in common.smk returns case_targets()).
#
# Case 1 (speed sweep, Figs. 6-8, eq. 55) has rules of its own: deterministic runs per speed in
# batches, one time-history run, and the figures. Cases 2-4 run through the study stage
# (study.smk, report.smk) and add a comparison step over its aggregated outputs.

from ttbpipe.study.cases import speed_batches as _case_speed_batches
from ttbpipe.study.cases import sweep_speeds as _case_sweep_speeds

CASE = config.get("case") or {}
CASE_NAME = CASE.get("name", "")
CASE_OUT = f"{RESULTS}/paper_comparison"
CASE_SWEEP = CASE.get("sweep") or {}
CASE_SPEEDS = _case_sweep_speeds(CASE_SWEEP) if CASE_SWEEP else []
CASE_SPEED_BATCHES = _case_speed_batches(CASE_SPEEDS, CASE_SWEEP.get("batch_size", 4)) if CASE_SWEEP else []

wildcard_constraints:
    sfirst=r"\d{3}",
    slast=r"\d{3}",


# Only the rules of the configured case exist, so that summary.md has exactly one producer.
if CASE_SWEEP:

  rule case_sweep_batch:
      """Case 1: deterministic coupled runs at speeds sfirst..slast of the sweep (maxima, Fig. 8)."""
      output:
          f"{CASE_OUT}/sweep/speeds_{{sfirst}}-{{slast}}.parquet",
      params:
          speeds=lambda w: CASE_SPEEDS[int(w.sfirst):int(w.slast) + 1],
          structure=config.get("structure", {}),
          simulation=config.get("simulation", {}),
          sweep=CASE_SWEEP,
          seed=config["study"]["seed"],
          version=MODEL_VERSION,
      log:
          f"{LOGS}/paper_comparison/sweep_{{sfirst}}-{{slast}}.log",
      script:
          "../scripts/case_sweep_batch.py"


  rule case_time_history:
      """Case 1: one run at case.sweep.history_speed_kmh with rail monitors (Figs. 6-7)."""
      output:
          table=f"{CASE_OUT}/time_history.parquet",
      params:
          structure=config.get("structure", {}),
          simulation=config.get("simulation", {}),
          sweep=CASE_SWEEP,
          seed=config["study"]["seed"],
          version=MODEL_VERSION,
      log:
          f"{LOGS}/paper_comparison/time_history.log",
      script:
          "../scripts/case_time_history.py"


  rule case_sweep_report:
      """Case 1: sweep table, eq. 55 against the sweep's peaks, Figs. 6-8."""
      input:
          batches=[f"{CASE_OUT}/sweep/speeds_{a:03d}-{b:03d}.parquet" for a, b in CASE_SPEED_BATCHES],
          history=f"{CASE_OUT}/time_history.parquet",
      output:
          sweep=f"{CASE_OUT}/sweep.parquet",
          resonance=f"{CASE_OUT}/resonance.parquet",
          summary=f"{CASE_OUT}/summary.md",
          figures=directory(f"{CASE_OUT}/figures"),
      params:
          structure=config.get("structure", {}),
          simulation=config.get("simulation", {}),
          sweep=CASE_SWEEP,
          version=MODEL_VERSION,
      log:
          f"{LOGS}/paper_comparison/sweep_report.log",
      script:
          "../scripts/case_sweep_report.py"


else:

  rule case_compare:
      """Cases 2-4: the paper's comparisons over the study's aggregated outputs."""
      input:
          extremes=results_path("study/extremes.parquet"),
          history=results_path("study/history_statistics.parquet"),
          table1=results_path("study/table1_std.parquet"),
          table1_history=results_path("study/table1_history_std.parquet"),
          design=results_path("study/design.parquet"),
      output:
          summary=f"{CASE_OUT}/summary.md",
          comparison=f"{CASE_OUT}/comparison.parquet",
          figures=directory(f"{CASE_OUT}/figures"),
      params:
          case=CASE,
          latest_campaign=TIPM_LAST,
          version=MODEL_VERSION,
      log:
          f"{LOGS}/paper_comparison/compare.log",
      script:
          "../scripts/case_compare.py"


def case_targets() -> list[str]:
    """The case's final outputs (empty without a case: section)."""
    if not CASE:
        return []
    if CASE_SWEEP:
        return [f"{CASE_OUT}/sweep.parquet", f"{CASE_OUT}/summary.md"]
    return [f"{CASE_OUT}/summary.md", results_path("study/report/summary.html")]
