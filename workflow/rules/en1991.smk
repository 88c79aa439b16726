# EN 1991-2 dynamic analysis (docs/en1991.md). Active only when the configuration has an
# `en1991:` section (config/en1991.yaml); then `snakemake` builds exactly its outputs
# (all_targets() in common.smk returns en1991_targets()).
#
# One job per train: the whole speed sweep of that train on every distinct span (moving-load
# runs of a simply supported span take a few hundredths of a second each, so a train is a job of
# about a minute, not thousands of short jobs); one report job.

EN1991 = config.get("en1991") or {}
EN1991_OUT = f"{RESULTS}/en1991"


if EN1991:

  from ttbpipe.en1991.study import settings as _en1991_settings

  EN1991_TRAINS = _en1991_settings(config)["trains"]


  rule en1991_train:
      """EN 1991-2: one train over the speed range on every distinct span (moving loads)."""
      output:
          f"{EN1991_OUT}/trains/{{train}}.parquet",
      params:
          en1991=EN1991,
          structure=config.get("structure", {}),
          version=MODEL_VERSION,
      log:
          f"{LOGS}/en1991/{{train}}.log",
      script:
          "../scripts/en1991_train.py"


  rule en1991_report:
      """EN 1991-2: envelopes, resonance table, Figure 6.9 and EN 1990 A2 checks, figures."""
      input:
          trains=expand(f"{EN1991_OUT}/trains/{{train}}.parquet", train=EN1991_TRAINS),
      output:
          envelope=f"{EN1991_OUT}/envelope.parquet",
          resonance=f"{EN1991_OUT}/resonance.parquet",
          checks=f"{EN1991_OUT}/checks.parquet",
          summary=report(f"{EN1991_OUT}/summary.md", caption="../report/en1991_summary.rst",
                         category="EN 1991-2 dynamic analysis"),
          figures=report(directory(f"{EN1991_OUT}/figures"), patterns=["{name}.png"],
                         caption="../report/en1991_figures.rst",
                         category="EN 1991-2 dynamic analysis"),
      params:
          en1991=EN1991,
          structure=config.get("structure", {}),
          version=MODEL_VERSION,
      log:
          f"{LOGS}/en1991/report.log",
      script:
          "../scripts/en1991_report.py"


def en1991_targets() -> list[str]:
    """The EN 1991-2 study's final outputs (empty without an en1991: section)."""
    if not EN1991:
        return []
    return [f"{EN1991_OUT}/summary.md", f"{EN1991_OUT}/envelope.parquet"]
