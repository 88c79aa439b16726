"""A finished study's profile-likelihood intervals against the slow multi-start reference.

    python benchmarks/tail_profile_reference.py RESULTS [--old OLD_RELIABILITY]
        [--configfile config/config.yaml]

RESULTS: a study's results folder (``results/case4`` after ``snakemake --cores 2 --configfile
config/case4.yaml``), with its batches and ``study/reliability.parquet``. For every row of the
reliability table whose tail is an unweighted GEV of the raw index at a fixed threshold (the
limits as benchmarks/study_reliability_time.py builds them), recomputes the 95 % profile
interval with the slow reference of tests/test_reliability_tail.py (`_reference_profile_ends`:
each profile point from the 6 best points of a 25 x 34 grid, Nelder-Mead to 1e-10 and scipy's
Powell) and prints the rows whose ends differ from the table's by more than 2e-3 in log P, then
the largest difference. ``--old``: another reliability table of the same study (an older
revision's), compared the same way. About 0.15 s a row. Nothing asserted (the test asserts
eight such cases).

``--every-fit``: every profile interval the table's tail fits compute (weighted or not, GEV or
Gumbel, P = 0 included; the table rebuilt from the batches with the code on the path, each call
of `ttbpipe.reliability.tail._profile_interval` recorded) against the nested one-dimensional
searches of tests/test_reliability_tail.py (`_nested_profile_interval`: the scale as the support
edge's plus e^t, with the call's own data, weights, cutoff and maximum likelihood). A failed
minimisation gives too high a profile value, so a search can only end an interval too early:
an end of the code's inside the reference's by more than 2e-3 in log P is a fault of the code
(``narrower``). Where the code's end lies beyond the reference's, the code's own profile optimum
halfway between the two is re-evaluated with the reference's likelihood: inside the support and
below the cutoff, it proves the reference stalled there (``reference stalled``). The time grows
with the number of maxima: case 4's 396 intervals of 20 maxima 10 minutes, case 3's medium
variant's 56 of 300 maxima 4 minutes.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from study_reliability_time import study_limits

from ttbpipe.stats.limits import ConstantLimit

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_reliability_tail import (_gev_nll_at, _nested_profile_interval,  # noqa: E402
                                   _profile_interval_recorder, _reference_profile_ends)


def log_difference(got: float, ref: float) -> float:
    """|log got - log ref|, 0 when both are 0 (an end below 1e-30 is reported as 0)."""
    if got == 0.0 and ref == 0.0:
        return 0.0
    if not (got > 0 and ref > 0):
        return np.inf
    return abs(float(np.log(got) - np.log(ref)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path)
    parser.add_argument("--old", type=Path, help="another reliability.parquet of the same study")
    parser.add_argument("--configfile", type=Path, default=Path("config/config.yaml"),
                        help="the configuration whose limits the study assessed")
    parser.add_argument("--every-fit", action="store_true",
                        help="every profile interval of the rebuilt table against the nested reference")
    args = parser.parse_args()
    if args.every_fit:
        every_fit(args.results, args.configfile)
        return
    table = pd.read_parquet(args.results / "study/reliability.parquet")
    old = pd.read_parquet(args.old) if args.old else None
    extremes, limits, _, _ = study_limits(args.results, args.configfile)
    thresholds = {(lim.name, lim.category): float(lim.threshold) for lim in limits
                  if isinstance(lim, ConstantLimit)}
    worst = {"table": 0.0, "old": 0.0}
    rows = 0
    for i, row in table.iterrows():
        if (str(row.tail_model) != "GEV" or "raw index" not in str(row.tail_method)
                or bool(row.weighted) or not np.isfinite(row.tail_probability)):
            continue
        limit = thresholds.get((row.limit, row.category))
        if limit is None:       # a threshold that varies from sample to sample
            continue
        x = extremes.loc[extremes.scenario == row.scenario, row.column].to_numpy(float)
        _, low, high = _reference_profile_ends(x, limit)
        rows += 1
        found = {"table": (row.tail_ci_low, row.tail_ci_high)}
        if old is not None and str(old.tail_model.iloc[i]) == "GEV":
            found["old"] = (old.tail_ci_low.iloc[i], old.tail_ci_high.iloc[i])
        differences = {name: max(log_difference(lo, low), log_difference(hi, high))
                       for name, (lo, hi) in found.items()}
        for name, d in differences.items():
            worst[name] = max(worst[name], d)
        if max(differences.values()) > 2e-3:
            print(f"{row.scenario} {row.limit}: reference [{low:.3e}, {high:.3e}]"
                  + "".join(f", {name} [{lo:.3e}, {hi:.3e}] ({differences[name]:.2g})"
                            for name, (lo, hi) in found.items()))
    print(f"{rows} rows: largest |log P| difference of an interval end, table {worst['table']:.2g}"
          + (f", old {worst['old']:.2g}" if old is not None else ""))


def recorded_profile_intervals(results: Path, configfile: Path) -> list[dict]:
    """Every `_profile_interval` call of the study's reliability table rebuilt with the code on
    the path: the model, the standardised limit, the estimate, the cutoff and the ends found."""
    import ttbpipe.reliability.tail as tail
    from ttbpipe.stats.reliability import assess_limits

    calls: list[dict] = []
    profile_interval = tail._profile_interval
    extremes, limits, context, settings = study_limits(results, configfile)
    tail._profile_interval = _profile_interval_recorder(profile_interval, calls)
    try:
        assess_limits(extremes, limits, context, settings, workers=1)
    finally:
        tail._profile_interval = profile_interval
    return calls


def code_profile_point(call: dict, lp: float) -> np.ndarray:
    """The code's own profile optimum (log sigma[, xi]) at ``lp``, searched as its interval
    search does, warm-started from the estimate (`ttbpipe.reliability.tail._profile_point`)."""
    import ttbpipe.reliability.tail as tail

    model, fixed = call["model"], call["free_hat"]
    return tail._profile_point(model, lp, call["z"], fixed, fixed,
                               tail._profile_grid(fixed, model.xi_min)).x


def every_fit(results: Path, configfile: Path) -> None:
    """``--every-fit``: see the module's docstring."""
    calls = recorded_profile_intervals(results, configfile)
    # intervals whose both ends agree, intervals of models the reference does not cover (the
    # GPD), and ends by verdict
    counts = {"intervals agreeing": 0, "GPD intervals not checked": 0, "ends narrower": 0,
              "ends where the reference stalled": 0, "ends unresolved": 0}
    worst_narrower = 0.0
    for k, call in enumerate(calls):
        model = call["model"]
        gumbel = model.name == "Gumbel"
        if model.name not in ("GEV", "Gumbel"):
            counts["GPD intervals not checked"] += 1
            continue
        ref = _nested_profile_interval(model.x, call["z"], call["lp_hat"], call["nll_hat"],
                                       call["cutoff"], weights=model.a, shape_min=model.xi_min,
                                       gumbel=gumbel)
        verdicts = []
        for side, got, want in (("lower", call["ends"][0], ref[0]),
                                ("upper", call["ends"][1], ref[1])):
            d = log_difference(got, want)
            if d <= 2e-3:
                continue
            # the code's end inside the reference's: the interval too narrow
            inside = (got > want) if side == "lower" else (got < want)
            if inside:
                verdicts.append(f"narrower {side} {got:.3e} vs {want:.3e}")
                counts["ends narrower"] += 1
                worst_narrower = max(worst_narrower, d)
                continue
            log_ends = [np.log(max(v, 1e-30)) for v in (got, want)]
            lp = 0.5 * sum(log_ends)
            point = code_profile_point(call, lp)
            log_scale, shape = (point[0], 0.0) if gumbel else point
            value = float(_gev_nll_at(model.x, lp, call["z"], np.array([log_scale]), shape,
                                      model.a)[0])
            excess = 2.0 * (value - call["nll_hat"]) - call["cutoff"]
            verdict = "reference stalled" if excess <= 0 else "unresolved"
            counts["ends where the reference stalled" if excess <= 0 else "ends unresolved"] += 1
            verdicts.append(f"{verdict} {side} {got:.3e} vs {want:.3e} (code's point at log P "
                            f"{lp:.2f}: {excess:+.3f} against the cutoff)")
        if not verdicts:
            counts["intervals agreeing"] += 1
        else:
            print(f"fit {k} ({model.name}, {model.x.size} maxima): " + "; ".join(verdicts))
    print(f"{len(calls)} profile intervals: " + ", ".join(f"{v} {n}" for n, v in counts.items())
          + (f"; largest narrower end {worst_narrower:.2g} in log P"
             if counts["ends narrower"] else ""))


if __name__ == "__main__":
    main()
