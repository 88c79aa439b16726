"""Snakemake script of rule simulate_batch: one batch of samples (ttbpipe.study.batch)."""

from ttbpipe.io import read_provenance, read_table
from ttbpipe.logs import setup_logging
from ttbpipe.study.batch import simulate_batch
from ttbpipe.study.design import batch_rows
from ttbpipe.study.plan import settings_digest
from ttbpipe.workflow import snakemake_context


def main(snakemake) -> None:
    setup_logging(snakemake.log[0])
    w = snakemake.wildcards
    settings = dict(snakemake.params.settings)
    if settings_digest(settings) != w.digest:
        raise ValueError(f"batch {w.scenario} {w.first}-{w.last}: the settings passed have digest "
                         f"{settings_digest(settings)}, the output path {w.digest}")
    rows = batch_rows(read_table(snakemake.input.design), w.scenario, int(w.first), int(w.last))
    config = dict(snakemake.config)
    simulation = dict(config.get("simulation") or {})
    if simulation.get("executor") == "dask":
        # a LocalCluster gets the cores Snakemake granted this job (threads: local_workers,
        # capped by --cores); an external scheduler ignores local_workers
        simulation["dask"] = {**dict(simulation.get("dask") or {}),
                              "local_workers": snakemake.threads}
        config["simulation"] = simulation
    profiles = {}
    if "profiles" in snakemake.input.keys():
        profiles = {str(rows["kind"].iloc[0]): snakemake.input.profiles}
    if "population" in snakemake.input.keys():   # irregularity_mc (paper case 3's MCM)
        pooled = str(snakemake.input.population)
        # the profile settings of the digest (ttbpipe.study.plan.mc_profile_settings: band,
        # length, step, amplitudes), so that what ran is what the batch path names
        mc = dict(settings.get("mc_profiles") or {})
        profiles = {"irregularity_mc": {**mc, "pooled_path": pooled,
                                        "date": max(read_provenance(pooled)["campaigns"])}}
    spans = (snakemake.input.span_frequencies if "span_frequencies" in snakemake.input.keys()
             else None)   # the study's EN 1990 span frequencies, analysed once per study
    simulate_batch(rows, config, profiles, snakemake.output.extremes, snakemake.output.histories,
                   span_frequencies=spans, scenario=w.scenario, first=int(w.first),
                   last=int(w.last), settings=settings, settings_digest=w.digest)


# Dask's LocalCluster starts its workers with multiprocessing "spawn", which re-imports this
# script as __mp_main__ in every worker: the batch must run only in the main process.
if __name__ == "__main__":
    main(snakemake_context(globals(), "simulate_batch", scenario="C1", first="00000",
                           last="00003",
                           digest=lambda workflow, w: workflow["STUDY_DIGEST"][w["scenario"]]))
