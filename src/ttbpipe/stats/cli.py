"""``ttbpipe stats-report --extremes FILES... [--histories FILES...] --config CONFIG --out DIR``.

Reads per-batch results (docs/results_schema.md), writes into ``DIR``:

* ``reliability.parquet``: exceedance probability, interval and verdict per (scenario, limit);
* ``summary.rst``: the report's first page;
* ``table1_std.parquet``: standard deviation of each index per scenario (paper's Table 1);
* ``history_statistics.parquet``: mean, std, percentiles against time/position (with --histories);
* ``figures/``: ``convergence_<scenario>.png``, ``pdf_<index>.png``, ``history_<quantity>.png``,
  ``envelope_<index>.png`` (when two or more scenarios are ISO dates).
"""

from __future__ import annotations

import argparse
import logging
import re
from pathlib import Path

from ..inspection.format import DATE_PATTERN

log = logging.getLogger(__name__)

_DATE = re.compile(rf"^{DATE_PATTERN}$")  # a dated (campaign) scenario


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--extremes", nargs="+", required=True, type=Path,
                        help="extremes Parquet files (one per batch)")
    parser.add_argument("--histories", nargs="*", default=[], type=Path,
                        help="long-format time-history Parquet files (one per batch)")
    parser.add_argument("--config", type=Path, default=None,
                        help="study configuration (YAML); its limits: section is used")
    parser.add_argument("--out", type=Path, required=True, help="output folder")
    parser.add_argument("--bins", type=int, default=256, help="histogram bins per grid point")


def run(args: argparse.Namespace) -> int:
    import yaml

    from .. import io
    from . import aggregate, plots
    from .limits import limits_from_config
    from .reliability import ReliabilitySettings, assess_limits, convergence_curve
    from .report import write_first_page
    from .schema import ResultsSchemaError, response_columns

    config = {}
    if args.config is not None:
        with open(args.config) as handle:
            config = yaml.safe_load(handle) or {}
    section = config.get("limits")
    try:
        limits, context = limits_from_config(section)
        settings = ReliabilitySettings.from_config(section)
        extremes = aggregate.read_extremes(args.extremes)
    except (ResultsSchemaError, ValueError) as exc:
        log.error("%s", exc)
        return 1
    out = Path(args.out)
    figures = out / "figures"
    table = assess_limits(extremes, limits, context, settings)
    io.write_table(table, out / "reliability.parquet", config=config, kind="reliability")
    study = (config.get("study") or {}).get("name")
    write_first_page(table, out / "summary.rst", study=study)
    table1 = aggregate.standard_deviation_table(extremes).reset_index()
    io.write_table(table1, out / "table1_std.parquet", config=config, kind="table1_std")

    evaluable = table[~table["status"].str.startswith("not evaluated")]
    by_name = {lim.name: lim for lim in limits}
    for scenario, block in evaluable.groupby("scenario", sort=True):
        curves = [convergence_curve(extremes, by_name[name], context, settings, scenario)
                  for name in block["limit"]]
        fig = plots.plot_exceedance_convergence(curves, ncols=3)
        io.save_figure(fig, figures / f"convergence_{scenario}.png")
    thresholds = {lim.column: lim.threshold for lim in limits
                  if getattr(lim, "threshold", None) is not None}
    dated = sorted(s for s in extremes["scenario"].unique() if _DATE.match(str(s)))
    for column in response_columns(extremes):
        fig = plots.plot_extreme_pdfs(extremes, column, threshold=thresholds.get(column))
        io.save_figure(fig, figures / f"pdf_{column}.png")
        if len(dated) >= 2:
            env = aggregate.forecast_envelope(extremes[extremes["scenario"].isin(dated)], column)
            fig = plots.plot_forecast_envelope(env, threshold=thresholds.get(column))
            io.save_figure(fig, figures / f"envelope_{column}.png")
    if args.histories:
        try:
            stats = aggregate.aggregate_histories(args.histories, n_bins=args.bins)
        except (ResultsSchemaError, ValueError) as exc:
            log.error("%s", exc)
            return 1
        io.write_table(aggregate.statistics_frame(stats), out / "history_statistics.parquet",
                       config=config, kind="history_statistics", n_bins=args.bins)
        for quantity in sorted({q for _, q in stats}):
            fig = plots.plot_history_statistics(stats, quantity)
            io.save_figure(fig, figures / f"history_{quantity}.png")
    log.info("statistics report written to %s (%d limit rows, %d scenarios)", out, len(table),
             extremes["scenario"].nunique())
    return 0
