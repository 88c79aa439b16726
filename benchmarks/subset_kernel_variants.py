"""Markov chain kernels for subset simulation, measured side by side over repeated seeds.

The rows of the "samplers measured" table of docs/reliability.md, section 10. A compact subset
simulation (Au & Beck 2001: N points per level, the best p0 N seed chains of 1/p0 states, the
threshold halfway between the Nc-th and (Nc+1)-th smallest g, P = p0^m P_m) with a pluggable
chain kernel; one generator per run (``default_rng(seed)``), no ask/tell, so its numbers are not
those of :class:`ttbpipe.reliability.SubsetSimulation`, whose aCS kernel is the ``acs`` row here.
The c.o.v. and the interval are those of the package (:func:`ttbpipe.reliability.subset.
lineage_variance`, :func:`ttbpipe.reliability.result.lognormal_interval`).

Kernels (each leaves the standard normal conditional on the level's domain invariant):

* ``acs``: adaptive conditional sampling (Papaioannou et al. 2015, Probab. Eng. Mech. 41:89):
  ``v_i = rho_i u_i + sigma_i xi_i``, ``sigma_i = min(1, lambda s_i)``, lambda adapted to the
  target acceptance; accepted iff in the domain.
* ``acs-antithetic``: aCS with chain c and chain c + Nc/2 driven by xi and -xi (antithetic
  coupling of chains, Frigessi, Gasemyr & Rue 2000, Ann. Stat. 28:1128); each chain alone is aCS.
* ``acs-branches``: two antithetic aCS chains of half length from every seed.
* ``ess``: elliptical slice sampling (Murray, Adams & MacKay 2010, AISTATS): the ellipse
  ``u cos t + nu sin t``, ``nu ~ N(0, I)``, the angle drawn in a bracket of width w placed at
  random around 0 and shrunk towards 0 on every point outside the domain (Neal 2003, Ann. Stat.
  31:705, shrinkage procedure); every step moves, at the cost of several evaluations.
* ``dir-*``: the component along a unit direction d moved by a one-dimensional kernel, the
  complement of d by pCN (Cotter et al. 2013, Stat. Sci. 28:424) with lambda adapted; the
  Metropolis-Hastings ratio of the one-dimensional kernel for the standard normal target.
  d is ``oracle`` (the limit state's own direction: a bound on what a fitted direction can give),
  ``self`` (the mean of the level's seeds: depends on the chains' own start points), or ``cross``
  (the seeds' lineage is split in two halves by the parity of their level-0 ancestor; the chains
  of one half use the mean of the other half's seeds, so that the kernel does not depend on the
  chain's own seed).
  ``dir-gauss``: independence proposal ``N(mu, (f s)^2)`` along d, mu and s of the seeds'
  projections (leave-one-out for fitted d); ``dir-exp``: independence proposal
  ``c + Exp(1/(mean - c))`` along d, c the smallest seed projection; ``dir-trunc``: the prior
  along d conditioned on ``s' > s - w`` (ratio ``Phibar(s - w)/Phibar(s' - w)``);
  ``dir-logrw``: random walk of step tau in ``l = ln Phibar(s)``, in which the prior along any
  line is ``e^l`` (ratio ``e^(l' - l)``), alternating with aCS steps.
* ``plane[:margin]``: ``dir-exp`` with d the steepest descent of the least-squares plane
  ``g ~ b0 + b.u`` through *every* point evaluated so far (level 0 and every candidate of every
  chain, accepted or not), not a mean of seeds; the exponential starts ``margin`` times the
  seeds' mean excess below their smallest projection (``low - margin (mean - low)``; 0: at the
  smallest). The plane's thousands of points carry little of any one seed's noise; the
  kernel's parameters still depend on the seeds (their projections), as in the ``oracle`` rows.
* ``plane-trunc[:k]``: along the same direction, the standard normal truncated below at the
  plane's own boundary of the level, ``(b0 - b_j)/|b|``, less ``k`` standard deviations of the
  plane's residuals over all points (so that a curved boundary stays inside the support);
  independent of the seeds; accepted iff the current state lies beyond the truncation and the
  candidate in the level. ``plane-trunc-acs[:k]``: its steps alternate with aCS steps.

    python benchmarks/subset_kernel_variants.py --seeds 200 acs ess:6.283 dir-exp:oracle
    python benchmarks/subset_kernel_variants.py --seeds 100 --case parabolic:4.5:0.1 \
        --n-dims 50 acs dir-exp:oracle plane plane:0.5 plane:1

``--case``: ``linear`` (``g = beta - a.u``, a = (1, ..., 1)/sqrt(n), P = Phi(-beta)),
``chi2:probability:k`` (``g = c - sum_{i<k} u_i^2``, P = chi2_k.sf(c)) or
``parabolic:beta:kappa`` (``g = beta - u_1 + (kappa/2) sum_{i=2}^{11} u_i^2``,
``P = E[Phi(-(beta + kappa X/2))]``, X ~ chi2_10, by ``scipy.integrate.quad``, as
benchmarks/line_sampling_table.py).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from scipy import stats
from scipy.special import log_ndtr, ndtr, ndtri, ndtri_exp

from ttbpipe.reliability.result import lognormal_interval
from ttbpipe.reliability.subset import indicator_gamma, lineage_variance


def _chain_arrays(seeds, gseeds, ns):
    """States (ns, nc, n) and g values (ns, nc) of nc chains of ns states, row 0 the seeds."""
    nc, n = seeds.shape
    u, gv = np.empty((ns, nc, n)), np.empty((ns, nc))
    u[0], gv[0] = seeds, gseeds
    return u, gv


class ACS:
    def __init__(self, target: float = 0.44, antithetic: str = ""):
        self.target, self.lam, self.antithetic = target, 0.6, antithetic

    def run(self, seeds, gseeds, labels, b, ns, g, rng):
        nc, n = seeds.shape
        s = seeds.std(axis=0, ddof=1)
        if self.antithetic == "branches":
            # two chains of ns/2 states from every seed; rows t * 2Nc + c', seed of c' = c' % Nc
            cur, gcur, m, steps = np.concatenate([seeds, seeds]), np.r_[gseeds, gseeds], 2 * nc, ns // 2
        else:
            cur, gcur, m, steps = seeds, gseeds, nc, ns
        u, gv = np.empty((steps, m, n)), np.empty((steps, m))
        u[0], gv[0] = cur, gcur
        evals, accepted = 0, []
        for t in range(1, steps):
            sigma = np.minimum(1.0, self.lam * s)
            rho = np.sqrt(1.0 - sigma * sigma)
            if self.antithetic:
                half = rng.standard_normal((m // 2, n))
                xi = np.concatenate([half, -half] + ([rng.standard_normal((1, n))] if m % 2 else []))
            else:
                xi = rng.standard_normal((m, n))
            v = rho * u[t - 1] + sigma * xi
            gn = g(v)
            evals += m
            ok = gn <= b
            u[t] = np.where(ok[:, None], v, u[t - 1])
            gv[t] = np.where(ok, gn, gv[t - 1])
            accepted.append(ok.mean())
            self.lam = math.exp(math.log(self.lam) + (ok.mean() - self.target) / math.sqrt(t))
        return u.reshape(-1, n), gv.reshape(-1), evals


class ESS:
    def __init__(self, width: float = 2 * math.pi, max_tries: int = 100):
        self.width, self.max_tries = width, max_tries

    def run(self, seeds, gseeds, labels, b, ns, g, rng):
        nc, n = seeds.shape
        u, gv = np.empty((ns, nc, n)), np.empty((ns, nc))
        u[0], gv[0] = seeds, gseeds
        evals = 0
        for t in range(1, ns):
            x, nu = u[t - 1], rng.standard_normal((nc, n))
            lo = -self.width * rng.random(nc)
            hi = lo + self.width
            angle = lo + (hi - lo) * rng.random(nc)
            done = np.zeros(nc, bool)
            new_u, new_g = x.copy(), gv[t - 1].copy()
            for _ in range(self.max_tries):       # a capped shrinkage is still reversible
                act = np.flatnonzero(~done)
                if act.size == 0:
                    break
                cand = x[act] * np.cos(angle[act])[:, None] + nu[act] * np.sin(angle[act])[:, None]
                gn = g(cand)
                evals += act.size
                ok = gn <= b
                new_u[act[ok]], new_g[act[ok]], done[act[ok]] = cand[ok], gn[ok], True
                rej = act[~ok]
                neg = angle[rej] < 0
                lo[rej[neg]] = angle[rej[neg]]
                hi[rej[~neg]] = angle[rej[~neg]]
                angle[rej] = lo[rej] + (hi[rej] - lo[rej]) * rng.random(rej.size)
            u[t], gv[t] = new_u, new_g
        return u.reshape(-1, n), gv.reshape(-1), evals


class Directional:
    """pCN in the complement of d, a one-dimensional Metropolis-Hastings kernel along d."""

    def __init__(self, kind: str, fit: str, param: float, direction, target: float = 0.44):
        self.kind, self.fit, self.param, self.a, self.target = kind, fit, param, direction, target
        self.lam, self.margin = 0.6, 0.0

    def _fit(self, y):
        """Direction and leave-one-out projections of the fitting set y (a seed's own noise
        would otherwise lie along the fitted direction)."""
        if self.fit == "oracle":
            return self.a, y @ self.a
        k, mean = y.shape[0], y.mean(axis=0)
        d = mean / np.linalg.norm(mean)
        loo = (k * mean[None, :] - y) / (k - 1)
        loo /= np.linalg.norm(loo, axis=1)[:, None]
        return d, np.sum(loo * y, axis=1)

    def run(self, seeds, gseeds, labels, b, ns, g, rng):
        nc, n = seeds.shape
        fits = {}
        for half in (0, 1):
            y = seeds[labels != half] if self.fit == "cross" else seeds
            fits[half] = self._fit(y if y.shape[0] >= 3 else seeds)
        d = np.stack([fits[h][0] for h in labels])
        proj = [fits[h][1] for h in labels]
        mu = np.array([p.mean() for p in proj])
        sd = np.array([p.std(ddof=1) for p in proj]) * (self.param if self.kind == "gauss" else 1)
        low = np.array([p.min() for p in proj])
        low -= self.margin * (mu - low)
        rate = 1.0 / (mu - low)
        s_all = seeds.std(axis=0, ddof=1)
        u, gv = _chain_arrays(seeds, gseeds, ns)
        evals = 0
        for t in range(1, ns):
            x = u[t - 1]
            if self.kind == "logrw" and t % 2 == 0:          # the alternating aCS step
                sigma = np.minimum(1.0, self.lam * s_all)
                v = np.sqrt(1 - sigma ** 2) * x + sigma * rng.standard_normal((nc, n))
                log_ratio = np.zeros(nc)
            else:
                s = np.sum(x * d, axis=1)
                perp = x - s[:, None] * d
                if self.kind != "logrw":
                    sig = min(1.0, self.lam)
                    xi = rng.standard_normal((nc, n))
                    xi -= np.sum(xi * d, axis=1)[:, None] * d
                    perp = math.sqrt(1 - sig * sig) * perp + sig * xi
                if self.kind == "gauss":
                    s_new = mu + sd * rng.standard_normal(nc)
                    log_ratio = (-(s_new ** 2 - s ** 2) / 2
                                 + ((s_new - mu) ** 2 - (s - mu) ** 2) / (2 * sd * sd))
                elif self.kind == "exp":
                    s_new = low + rng.exponential(size=nc) / rate
                    log_q_old = np.where(s >= low, -rate * (s - low), -np.inf)
                    log_ratio = -(s_new ** 2 - s ** 2) / 2 + log_q_old + rate * (s_new - low)
                elif self.kind == "trunc":
                    lo = s - self.param
                    s_new = -ndtri(np.maximum(ndtr(-lo) * rng.random(nc), 1e-300))
                    log_ratio = np.where(s >= s_new - self.param,
                                         log_ndtr(-lo) - log_ndtr(-(s_new - self.param)), -np.inf)
                else:                                          # logrw
                    level = log_ndtr(-s)
                    level_new = level + self.param * rng.standard_normal(nc)
                    inside = level_new < 0
                    level_new = np.where(inside, level_new, level)
                    s_new = -ndtri_exp(level_new)
                    log_ratio = np.where(inside, level_new - level, -np.inf)
                v = perp + s_new[:, None] * d
            gn = g(v)
            evals += nc
            ok = (np.log(rng.random(nc)) < log_ratio) & (gn <= b)
            u[t] = np.where(ok[:, None], v, x)
            gv[t] = np.where(ok, gn, gv[t - 1])
            self.lam = math.exp(math.log(self.lam) + (ok.mean() - self.target) / math.sqrt(t))
        return u.reshape(-1, n), gv.reshape(-1), evals


class Plane(Directional):
    """``dir-exp`` along the steepest descent of the least-squares plane of every evaluation
    (``subset`` passes every evaluated point to :meth:`record`)."""

    def __init__(self, margin: float = 0.0):
        super().__init__("exp", "plane", 0.0, None)
        self.margin = margin
        self.hist_u, self.hist_g = [], []

    def record(self, u, gv):
        self.hist_u.append(u)
        self.hist_g.append(gv)

    def _plane(self):
        """Coefficients (b0, b) of the least-squares plane of every evaluation and the standard
        deviation of its residuals."""
        x = np.concatenate(self.hist_u)
        a = np.hstack([np.ones((x.shape[0], 1)), x])
        g_all = np.concatenate(self.hist_g)
        coef, *_ = np.linalg.lstsq(a, g_all, rcond=None)
        return coef, float(np.std(g_all - a @ coef, ddof=a.shape[1]))

    def _fit(self, y):
        coef, _ = self._plane()
        d = -coef[1:] / np.linalg.norm(coef[1:])
        return d, y @ d


class PlaneTruncated(Plane):
    """Along the plane's direction, the standard normal truncated at the plane's own boundary of
    the level less ``k`` residual standard deviations (no seed enters the proposal)."""

    def __init__(self, k: float = 2.0, alternate: bool = False):
        super().__init__()
        self.k, self.alternate, self.lam_acs = k, alternate, 0.6

    def run(self, seeds, gseeds, labels, b, ns, g, rng):
        nc, n = seeds.shape
        coef, resid_sd = self._plane()
        norm = np.linalg.norm(coef[1:])
        d = -coef[1:] / norm
        low = (coef[0] - b) / norm - self.k * resid_sd / norm    # g_plane = b0 - |b| s = b
        log_tail = log_ndtr(-low)
        spread = seeds.std(axis=0, ddof=1)
        u, gv = _chain_arrays(seeds, gseeds, ns)
        evals = 0
        for t in range(1, ns):
            x = u[t - 1]
            if self.alternate and t % 2 == 1:                 # an aCS step (class ACS)
                sigma = np.minimum(1.0, self.lam_acs * spread)
                v = np.sqrt(1.0 - sigma * sigma) * x + sigma * rng.standard_normal((nc, n))
                gn = g(v)
                evals += nc
                ok = gn <= b
                u[t] = np.where(ok[:, None], v, x)
                gv[t] = np.where(ok, gn, gv[t - 1])
                self.lam_acs = math.exp(math.log(self.lam_acs) + (ok.mean() - 0.44) / math.sqrt(t))
                continue
            s = x @ d
            sig = min(1.0, self.lam)
            xi = rng.standard_normal((nc, n))
            xi -= (xi @ d)[:, None] * d
            perp = math.sqrt(1 - sig * sig) * (x - s[:, None] * d) + sig * xi
            s_new = -ndtri_exp(log_tail + np.log(rng.random(nc)))   # N(0, 1) beyond low
            v = perp + s_new[:, None] * d
            gn = g(v)
            evals += nc
            # independence proposal proportional to the prior beyond low: the ratio is 1 when
            # the current state is beyond low too, else 0 (it cannot be proposed back)
            ok = (s >= low) & (gn <= b)
            u[t] = np.where(ok[:, None], v, x)
            gv[t] = np.where(ok, gn, gv[t - 1])
            self.lam = math.exp(math.log(self.lam) + (ok.mean() - self.target) / math.sqrt(t))
        return u.reshape(-1, n), gv.reshape(-1), evals


def subset(g, n_dims, seed, kernel, n_per_level=1000, p0=0.1, max_levels=30):
    """One run; returns (P, evaluations, lineage variance of ln P, mean gamma over levels >= 1)."""
    rng = np.random.default_rng(seed)
    nc = round(p0 * n_per_level)
    ns = n_per_level // nc
    if hasattr(kernel, "record"):
        g_model = g

        def g(points):
            values = g_model(points)
            kernel.record(points, values)
            return values
    u = rng.standard_normal((n_per_level, n_dims))
    gv = g(u)
    evals = n_per_level
    halves = np.arange(n_per_level) % 2               # lineage half of every state (cross-fits)
    indicators, parents, probs, gammas = [], [None], [], []
    for level in range(max_levels):
        order = np.lexsort((np.arange(gv.size), gv))
        final = gv[order[nc - 1]] <= 0 or level == max_levels - 1
        if final:
            ind = gv <= 0
        else:
            ind = np.zeros(gv.size, bool)
            ind[order[:nc]] = True
        indicators.append(ind)
        probs.append(ind.mean())
        if level:
            gammas.append(indicator_gamma(ind.reshape(ns, nc)))
        if final:
            break
        b = 0.5 * (gv[order[nc - 1]] + gv[order[nc]])
        seeds = order[:nc]
        parents.append(seeds.copy() if level == 0 else seeds % nc)
        labels = halves[seeds]
        u, gv, e = kernel.run(u[seeds], gv[seeds], labels, b, ns, g, rng)
        evals += e
        halves = labels[np.arange(gv.size) % nc]
    p = float(np.prod(probs))
    var = lineage_variance(indicators, parents, probs, nc, 2)
    return p, evals, var, float(np.mean(gammas)) if gammas else 0.0


def make_kernel(spec: str, direction):
    name, *args = spec.split(":")
    if name == "acs":
        return ACS(target=float(args[0]) if args else 0.44)
    if name == "acs-antithetic":
        return ACS(antithetic="pairs")
    if name == "acs-branches":
        return ACS(antithetic="branches")
    if name == "ess":
        return ESS(width=float(args[0]) if args else 2 * math.pi)
    if name == "plane":
        return Plane(float(args[0]) if args else 0.0)
    if name in ("plane-trunc", "plane-trunc-acs"):
        return PlaneTruncated(float(args[0]) if args else 2.0, name.endswith("-acs"))
    if name.startswith("dir-"):
        kind = name[4:]
        default = {"gauss": 2.0, "exp": 0.0, "trunc": 0.5, "logrw": 2.0}[kind]
        return Directional(kind, args[0] if args else "cross",
                           float(args[1]) if len(args) > 1 else default, direction)
    raise ValueError(f"unknown kernel {spec!r}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("kernels", nargs="+", help="acs[:target], acs-antithetic, acs-branches, "
                        "ess[:width], dir-{gauss,exp,trunc,logrw}[:oracle|self|cross[:param]], "
                        "plane[:margin]")
    parser.add_argument("--case", default="linear",
                        help="linear, parabolic:beta:kappa or chi2:probability:k")
    parser.add_argument("--beta", type=float, default=4.75)
    parser.add_argument("--n-dims", type=int, default=200)
    parser.add_argument("--n-per-level", type=int, default=1000)
    parser.add_argument("--seeds", type=int, default=200)
    args = parser.parse_args()
    direction = np.ones(args.n_dims) / np.sqrt(args.n_dims)
    if args.case == "linear":
        exact = float(stats.norm.sf(args.beta))
        label = f"linear limit state, beta = {args.beta:g}"

        def g(u):
            return args.beta - u @ direction
    elif args.case.startswith("parabolic"):
        from scipy import integrate

        _, beta, kappa = args.case.split(":")
        beta, kappa = float(beta), float(kappa)
        exact = integrate.quad(
            lambda x: stats.norm.sf(beta + 0.5 * kappa * x) * stats.chi2.pdf(x, 10),
            0.0, np.inf, epsabs=0.0, epsrel=1e-10, limit=200)[0]
        label = f"parabolic limit state, beta = {beta:g}, kappa = {kappa:g}"
        direction = np.zeros(args.n_dims)
        direction[0] = 1.0          # the oracle rows: the parabola's axis

        def g(u):
            return beta - u[:, 0] + 0.5 * kappa * np.sum(u[:, 1:11] ** 2, axis=1)
    elif args.case.startswith("chi2"):
        _, probability, k = args.case.split(":")
        exact, k = float(probability), int(k)
        radius2 = float(stats.chi2.isf(exact, k))
        label = f"chi-square limit state, k = {k}"

        def g(u):
            return radius2 - np.sum(u[:, :k] ** 2, axis=1)
    else:
        raise SystemExit(f"unknown --case {args.case!r}")

    print(f"{label}, {args.n_dims} dimensions, "
          f"N = {args.n_per_level}, p0 = 0.1, {args.seeds} seeds; exact P = {exact:.4g}")
    print("| kernel | evaluations | mean / exact | c.o.v. observed | c.o.v. reported (lineage) "
          "| coverage of the 95 % interval | gamma |")
    print("|---|---|---|---|---|---|---|")
    for spec in args.kernels:
        t0 = time.time()
        runs = [subset(g, args.n_dims, s, make_kernel(spec, direction), args.n_per_level)
                for s in range(args.seeds)]
        p = np.array([r[0] for r in runs])
        covs = np.sqrt([r[2] for r in runs])
        cover = [lo <= exact <= hi for lo, hi in
                 (lognormal_interval(r[0], c, 0.95) for r, c in zip(runs, covs))]
        gamma = "–" if spec == "acs-branches" else f"{np.mean([r[3] for r in runs]):.2f}"
        print(f"| {spec} | {np.mean([r[1] for r in runs]):.0f} | {p.mean() / exact:.2f} ± "
              f"{p.std(ddof=1) / exact / np.sqrt(args.seeds):.2f} | "
              f"{p.std(ddof=1) / p.mean():.2f} | {np.nanmean(np.where(np.isfinite(covs), covs, np.nan)):.2f} | "
              f"{np.mean(cover):.2f} | {gamma} |  <!-- {time.time() - t0:.0f} s -->", flush=True)


if __name__ == "__main__":
    main()
