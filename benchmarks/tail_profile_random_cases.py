"""Random far-limit GEV cases: the profile-likelihood interval against the slow multi-start reference.

    python benchmarks/tail_profile_random_cases.py [--seeds 0 600]

One case per seed (tests/test_reliability_tail.py, `_random_far_limit_case`: 20 or 40 GEV
maxima, shape -0.2 to 0.8, the limit 3 to 30 000 standard deviations above their median), its
interval by `ttbpipe.reliability.tail.estimate_tail` and by the reference of the same test
module (`_reference_profile_ends`: each profile point from the 6 best points of a 25 x 34 grid,
Nelder-Mead to 1e-10 and scipy's Powell). A profile value is a minimum over the other
parameters, so a search that stalls gives too high a value and an interval too narrow, never
too wide: where the estimate's interval is narrower than the reference's (by more than 2e-3 in
log P at either end) the estimate is wrong, where it is wider the reference stalled. Prints
both kinds of case and the counts. About 0.3 s a case. Nothing asserted (the test asserts five
such cases). Run with ``PYTHONPATH=<another tree>/src`` to check another revision's search.
``--reference nested``: against the nested one-dimensional searches along the support's edge
of the same module instead (`_nested_profile_ends`, unweighted MLE by scipy's Powell; a few
seconds a case). ``--model pot``: the POT model on random far-limit generalised Pareto samples
(`_random_far_limit_gpd_case`: 100 or 300 values, shape -0.3 to 0.8, the limit 2 to 1 000
standard deviations out) against the multi-start reference.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from ttbpipe.reliability.tail import TailNotEstimable, estimate_tail

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_reliability_tail import (_POT_SETTINGS, FAST, _nested_profile_ends,  # noqa: E402
                                   _random_far_limit_case, _random_far_limit_gpd_case,
                                   _reference_profile_ends)

_TOLERANCE = 2e-3   # in log P: Brent's tolerance 1e-3 plus the optimisers'


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs=2, default=(0, 600), metavar=("FIRST", "END"))
    parser.add_argument("--reference", choices=("multistart", "nested"), default="multistart")
    parser.add_argument("--model", choices=("gev", "pot"), default="gev")
    args = parser.parse_args()
    if args.model == "pot" and args.reference == "nested":
        parser.error("the nested reference is the GEV's")
    settings = _POT_SETTINGS if args.model == "pot" else FAST
    case = _random_far_limit_gpd_case if args.model == "pot" else _random_far_limit_case
    counts = {"cases": 0, "narrower": 0, "wider": 0, "not estimable": 0}
    for seed in range(*args.seeds):
        x, limit = case(seed)
        try:
            est = estimate_tail(x, limit, settings=settings)
            _, low, high = (_nested_profile_ends(x, limit) if args.reference == "nested" else
                            _reference_profile_ends(x, limit, settings))
        except TailNotEstimable:     # the estimate (or the reference's fit) not estimable
            counts["not estimable"] += 1
            continue
        counts["cases"] += 1
        narrower = (est.ci_high < high * np.exp(-_TOLERANCE)
                    or (low > 0 and est.ci_low > low * np.exp(_TOLERANCE)))
        wider = (est.ci_high > high * np.exp(_TOLERANCE)
                 or (est.ci_low < low * np.exp(-_TOLERANCE)))
        if narrower or wider:
            kind = "narrower" if narrower else "wider"
            counts[kind] += 1
            print(f"seed {seed}: n {x.size}, limit {limit:.4g}: estimate [{est.ci_low:.4e}, "
                  f"{est.ci_high:.4e}], reference [{low:.4e}, {high:.4e}]: {kind}", flush=True)
    print(f"{counts['cases']} cases (seeds {args.seeds[0]}-{args.seeds[1] - 1}; "
          f"{counts['not estimable']} not estimable): the estimate's interval narrower than the "
          f"reference's in {counts['narrower']}, wider in {counts['wider']}")


if __name__ == "__main__":
    main()
