"""GEV tail fits started from the L-moment estimate against the former start, scipy's fit.

    python benchmarks/tail_fit_starts.py [--replicates 12]

`ttbpipe.reliability.tail.estimate_tail` maximises the (weighted) GEV likelihood from a few
starting points (`_GEV.starts`). The first start was scipy's unweighted
``stats.genextreme.fit`` (its own Nelder-Mead on its own likelihood, about 20 ms a call); it is
now the closed-form L-moment estimate (`ttbpipe.reliability.tail.gev_from_lmoments`). This
script keeps the former starts as a pinned copy (`scipy_fit_starts`), fits the same samples with
both (GEV maxima, xi in -0.4 .. 0.4, n = 30, 100, 300, every second sample with log-normal
weights, the limit 1.3 times the 0.999 quantile, 19 goodness-of-fit refits as a study), and
prints the time of each and the largest differences of the results (relative for P, its interval
and the location and scale, absolute for the shape and the goodness-of-fit p-value, whose step
is 1/20). Timings and differences only, nothing asserted (tests/test_reliability_tail.py
asserts the fits against scipy's and against exact tail probabilities).
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np
from scipy import stats

import ttbpipe.reliability.tail as tail

FIELDS = ("probability", "ci_low", "ci_high", "location", "scale", "shape", "gof_pvalue")
ABSOLUTE = ("shape", "gof_pvalue")


def scipy_fit_starts(model) -> list[np.ndarray]:
    """The former `_GEV.starts`: scipy's unweighted fit, then weighted Gumbel moments."""
    out = []
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        try:
            c, loc, scale = stats.genextreme.fit(model.x)
            if np.isfinite([c, loc, scale]).all() and scale > 0:
                out.append(np.array([loc, np.log(scale), -c]))
        except Exception:
            pass
    m = np.average(model.x, weights=model.a)
    sd = np.sqrt(np.average((model.x - m) ** 2, weights=model.a))
    sig = np.sqrt(6.0) * sd / np.pi
    out += [np.array([m - tail._EULER_GAMMA * sig, np.log(sig), xi]) for xi in (0.1, -0.1)]
    return out


def fit(x, z, weights, starts) -> tuple[object, float]:
    """The tail estimate with ``starts`` as the GEV's starting points, and its wall time."""
    current = tail._GEV.starts
    tail._GEV.starts = starts
    try:
        start = time.perf_counter()
        try:
            result = tail.estimate_tail(x, z, weights=weights,
                                        settings=tail.TailSettings(gof_bootstrap=19))
        except tail.TailNotEstimable as error:
            result = str(error)
        return result, time.perf_counter() - start
    finally:
        tail._GEV.starts = current


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--replicates", type=int, default=12)
    args = parser.parse_args()
    lmoment_starts = tail._GEV.starts
    fit(np.random.default_rng(0).gumbel(size=50), 5.0, None, lmoment_starts)   # numba warm-up
    spent = {"scipy": 0.0, "lmoment": 0.0}
    worst = dict.fromkeys(FIELDS, 0.0)
    fits = refused = status_differs = 0
    for xi in (-0.4, -0.2, 0.0, 0.2, 0.4):
        for n in (30, 100, 300):
            for seed in range(args.replicates):
                rng = np.random.default_rng(seed)
                x = stats.genextreme.rvs(-xi, loc=1.0, scale=0.3, size=n, random_state=rng)
                weights = None if seed % 2 == 0 else rng.lognormal(0.0, 0.5, n)
                z = 1.3 * float(np.quantile(x, 0.999))
                old, spent_old = fit(x, z, weights, scipy_fit_starts)
                new, spent_new = fit(x, z, weights, lmoment_starts)
                spent["scipy"] += spent_old
                spent["lmoment"] += spent_new
                if isinstance(old, str) or isinstance(new, str):
                    refused += 1
                    status_differs += old != new
                    continue
                fits += 1
                status_differs += old.status != new.status
                for name in FIELDS:
                    a, b = getattr(old, name), getattr(new, name)
                    if a == b:
                        continue
                    d = abs(a - b) if name in ABSOLUTE else abs(a - b) / max(abs(a), 1e-300)
                    worst[name] = max(worst[name], d)
    total = fits + refused
    print(f"{total} samples: {fits} fitted by both, {refused} not estimable by both or either, "
          f"{status_differs} with a different status")
    for name, seconds in spent.items():
        print(f"FIGURE tail_fit_{name}_start_ms = {1e3 * seconds / total:.4g} ms")
    for name in FIELDS:
        kind = "absolute" if name in ABSOLUTE else "relative"
        print(f"  largest {kind} difference of {name:12s} {worst[name]:.2e}")


if __name__ == "__main__":
    main()
