"""Parameter groups of the paper's case 2, their marginals and the line geometry of the carriers.

Xu, Zhai & Li, section 5.2: four computational conditions, each a group of four random parameters
on one structural component, "all following normal distribution with coefficients of variation of
0.1 and correlation coefficient of 0.7-0.9":

* C1 rail:          ``rail_E``, ``rail_mass``, ``rail_Iy`` (vertical bending), ``rail_Iz`` (lateral)
* C2 rail pads:     ``pad_kz``, ``pad_cz``, ``pad_ky``, ``pad_cy``
* C3 CA mortar:     ``ca_kz``, ``ca_cz``, ``ca_ky``, ``ca_cy``
* C4 girder:        ``girder_E``, ``girder_mass``, ``girder_Iy``, ``girder_Iz``

(The paper's C4 bullet repeats the CA-mortar list by a copy slip; its text and Fig. 9 treat the
girder's dynamic characteristics, so C4 holds the girder's beam properties, as in C1.)

Every parameter is a dimensionless multiplicative factor on its nominal value (mean 1 unless
configured otherwise), carried by the elements or supports of one kind along the line.

The rail (C1) and rail-pad (C2) groups live on both rails. With ``left_right_correlation``
rho = 1 (default) the two rails share one field (an array of n values, applied to both); with
rho < 1 each rail has its own field, correlated by rho in the Gaussian (Nataf) space
(docs/random_fields.md, "Left and right rails"), and the factors are 2n arrays, left rail then
right rail (ttbpipe.structure.apply_factors).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np
from scipy import optimize, special, stats

from .. import streams
from ..configuration import section_defaults

# Carrier kinds: where along the line each parameter lives.
CARRIER_KINDS = ("rail_element", "fastener", "slab_element", "girder_element")

#: Carrier kinds present on each rail (a field per rail when left_right_correlation < 1).
RAIL_CARRIERS = ("rail_element", "fastener")


@dataclass(frozen=True)
class GroupDefinition:
    """A built-in parameter group (names are the interface with the structure model)."""

    name: str
    component: str
    carrier: str
    parameters: tuple[str, ...]


GROUP_DEFINITIONS: dict[str, GroupDefinition] = {
    "C1": GroupDefinition("C1", "rail", "rail_element",
                          ("rail_E", "rail_mass", "rail_Iy", "rail_Iz")),
    "C2": GroupDefinition("C2", "rail pads", "fastener",
                          ("pad_kz", "pad_cz", "pad_ky", "pad_cy")),
    "C3": GroupDefinition("C3", "CA mortar", "slab_element",
                          ("ca_kz", "ca_cz", "ca_ky", "ca_cy")),
    "C4": GroupDefinition("C4", "girder", "girder_element",
                          ("girder_E", "girder_mass", "girder_Iy", "girder_Iz")),
}

# Spawn key of each group (ttbpipe.streams.FIELD_GROUPS): a group's random numbers do not depend
# on which other groups are enabled (sampling.py spawns one child seed per group from (study seed,
# stream, sample)).
GROUP_STREAM = streams.FIELD_GROUPS

DISTRIBUTIONS = ("normal", "lognormal", "uniform", "gamma", "weibull", "truncated_normal")


def make_marginal(distribution: str, mean: float, cov: float, *, lower: float | None = None,
                  upper: float | None = None, name: str = "parameter"):
    """Frozen scipy.stats distribution of a factor from its mean and coefficient of variation.

    * normal            N(mean, (cov mean)^2)
    * lognormal         s = sqrt(ln(1 + cov^2)), scale = mean / sqrt(1 + cov^2)
    * uniform           mean +- sqrt(3) cov mean
    * gamma             shape 1/cov^2, scale mean cov^2
    * weibull           shape k from cov^2 = Gamma(1 + 2/k) / Gamma(1 + 1/k)^2 - 1 (brentq),
                        scale mean / Gamma(1 + 1/k)
    * truncated_normal  parent N(mean, (cov mean)^2) truncated to [lower, upper] (absolute factor
                        bounds; either may be omitted). mean and cov are the PARENT's: the
                        truncated mean and COV differ when the bounds cut into the bulk.
    """
    if not (np.isfinite(mean) and mean > 0):
        raise ValueError(f"{name}: mean must be a positive factor, got {mean}")
    if not (np.isfinite(cov) and cov > 0):
        raise ValueError(f"{name}: cov must be > 0, got {cov}")
    sd = cov * mean
    if distribution == "normal":
        return stats.norm(loc=mean, scale=sd)
    if distribution == "lognormal":
        s = np.sqrt(np.log1p(cov * cov))
        return stats.lognorm(s, scale=mean / np.sqrt(1 + cov * cov))
    if distribution == "uniform":
        half = np.sqrt(3.0) * sd
        if half >= mean:
            raise ValueError(f"{name}: uniform with cov {cov} reaches factor <= 0; "
                             "lower the cov (< 1/sqrt(3))")
        return stats.uniform(loc=mean - half, scale=2 * half)
    if distribution == "gamma":
        return stats.gamma(1.0 / cov ** 2, scale=mean * cov ** 2)
    if distribution == "weibull":
        def cov_gap(log_k: float) -> float:
            k = np.exp(log_k)
            g1, g2 = special.gammaln(1 + 1 / k), special.gammaln(1 + 2 / k)
            return np.sqrt(np.expm1(g2 - 2 * g1)) - cov
        k = np.exp(optimize.brentq(cov_gap, np.log(0.05), np.log(500.0), xtol=1e-14))
        return stats.weibull_min(k, scale=mean / special.gamma(1 + 1 / k))
    if distribution == "truncated_normal":
        lo = -np.inf if lower is None else (lower - mean) / sd
        hi = np.inf if upper is None else (upper - mean) / sd
        if not lo < hi:
            raise ValueError(f"{name}: truncation bounds lower={lower} >= upper={upper}")
        return stats.truncnorm(lo, hi, loc=mean, scale=sd)
    raise ValueError(f"{name}: unknown distribution {distribution!r}; expected one of "
                     f"{DISTRIBUTIONS}")


@dataclass
class ParameterGroup:
    """A configured group: marginals, target correlation and spatial correlation model."""

    name: str
    carrier: str
    parameters: list[str]
    marginals: list
    correlation: np.ndarray
    kernel: str
    correlation_length_m: float
    stream: int
    specs: list[dict[str, Any]] = field(default_factory=list)
    #: Gaussian-space correlation of the left- and right-rail fields (rail carriers only;
    #: None for slab and girder groups): 1 = one shared field.
    left_right_correlation: float | None = None


def build_groups(fields_config: Mapping[str, Any]) -> list[ParameterGroup]:
    """Configured, enabled groups from the ``fields:`` section (config/config.yaml)."""
    schema_defaults = section_defaults("fields")   # the study schema: their only home
    defaults = {key: fields_config.get(key, schema_defaults[key])
                for key in ("kernel", "correlation_length_m", "left_right_correlation")}
    groups = []
    for name, gconf in (fields_config.get("groups") or {}).items():
        if name not in GROUP_DEFINITIONS:
            raise ValueError(f"fields.groups.{name}: unknown group; expected one of "
                             f"{list(GROUP_DEFINITIONS)}")
        gconf = dict(gconf or {})
        if not gconf.get("enabled", True):
            continue
        definition = GROUP_DEFINITIONS[name]
        params = list(definition.parameters)
        overrides = dict(gconf.get("parameters") or {})
        unknown = set(overrides) - set(params)
        if unknown:
            raise ValueError(f"fields.groups.{name}.parameters: unknown {sorted(unknown)}; "
                             f"expected names from {params}")
        marginals, specs = [], []
        for p in params:
            spec = {"distribution": gconf.get("distribution", "normal"),
                    "mean": gconf.get("mean", 1.0), "cov": gconf.get("cov", 0.1),
                    "lower": gconf.get("lower"), "upper": gconf.get("upper")}
            spec.update(overrides.get(p) or {})
            specs.append(spec)
            marginals.append(make_marginal(spec["distribution"], float(spec["mean"]),
                                           float(spec["cov"]), lower=spec.get("lower"),
                                           upper=spec.get("upper"),
                                           name=f"fields.groups.{name}.{p}"))
        corr = np.asarray(gconf.get("correlation", np.eye(len(params))), dtype=float)
        if corr.shape != (len(params), len(params)):
            raise ValueError(f"fields.groups.{name}.correlation: shape {corr.shape}, expected "
                             f"{len(params)}x{len(params)} in the order {params}")
        if definition.carrier in RAIL_CARRIERS:
            left_right = float(gconf.get("left_right_correlation",
                                         defaults["left_right_correlation"]))
            if not -1.0 <= left_right <= 1.0:
                raise ValueError(f"fields.groups.{name}.left_right_correlation: {left_right}; "
                                 "expected a correlation in [-1, 1]")
        elif "left_right_correlation" in gconf:
            raise ValueError(f"fields.groups.{name}.left_right_correlation: group {name} "
                             f"({definition.component}) is not on the rails; only the groups on "
                             f"{RAIL_CARRIERS} carriers have a field per rail")
        else:
            left_right = None
        groups.append(ParameterGroup(
            name=name, carrier=definition.carrier, parameters=params, marginals=marginals,
            correlation=corr, kernel=gconf.get("kernel", defaults["kernel"]),
            correlation_length_m=float(gconf.get("correlation_length_m",
                                                 defaults["correlation_length_m"])),
            stream=GROUP_STREAM[name], specs=specs, left_right_correlation=left_right))
    if not groups:
        raise ValueError("fields.groups: no enabled group; enable at least one of "
                         f"{list(GROUP_DEFINITIONS)}")
    return groups


def _element_midpoints(start_m: float, length_m: float, element_m: float) -> np.ndarray:
    """Midpoints of the equal elements (count = round(length / element)) of [start, start+length]."""
    count = max(1, int(round(length_m / element_m)))
    return start_m + (np.arange(count) + 0.5) * (length_m / count)


def carrier_positions(geometry: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """Positions x (m) of every carrier kind along the line, from the ``fields.geometry`` config.

    The line starts (x = 0) at the beginning of the first approach: approach, spans, approach.
    (With ``source: structure`` the workflow takes the positions from ``ttbpipe.structure``
    instead; see :func:`ttbpipe.fields.sampling.positions_from_structure`.)

    * ``fastener``: supports every ``fastener_spacing_m`` (default 0.63 m), the first half a
      spacing from x = 0, over the whole line;
    * ``rail_element`` / ``slab_element``: midpoints of equal elements of about
      ``rail_element_m`` / ``slab_element_m`` over the whole line;
    * ``girder_element``: midpoints of equal elements of about ``girder_element_m`` in each span
      (no girder on the approaches).

    ``line_length_m`` may replace ``spans_m`` for a line without a bridge (then no girder
    elements).
    """
    approach = float(geometry.get("approach_length_m", 0.0))
    spans = [float(s) for s in geometry.get("spans_m", [])]
    total = line_length_m(geometry)
    spacing = float(geometry.get("fastener_spacing_m", 0.63))
    fasteners = np.arange(int(np.floor(total / spacing + 1e-9))) * spacing + spacing / 2
    out = {
        "fastener": fasteners[fasteners < total],
        "rail_element": _element_midpoints(0.0, total, float(geometry.get("rail_element_m",
                                                                          spacing))),
        "slab_element": _element_midpoints(0.0, total, float(geometry.get("slab_element_m",
                                                                          spacing))),
    }
    girder_element = float(geometry.get("girder_element_m", 1.0))
    starts = approach + np.concatenate([[0.0], np.cumsum(spans)[:-1]]) if spans else []
    out["girder_element"] = (np.concatenate([_element_midpoints(s, length, girder_element)
                                             for s, length in zip(starts, spans)])
                             if spans else np.empty(0))
    return out


def line_length_m(geometry: Mapping[str, Any]) -> float:
    """Total line length (m): spans + two approaches, or ``line_length_m``."""
    approach = float(geometry.get("approach_length_m", 0.0))
    spans = [float(s) for s in geometry.get("spans_m", [])]
    if spans:
        if any(s <= 0 for s in spans):
            raise ValueError(f"fields.geometry.spans_m must be positive, got {spans}")
        if "line_length_m" in geometry:
            raise ValueError("fields.geometry: give spans_m (+ approach_length_m) or "
                             "line_length_m, not both")
        total = float(np.sum(spans)) + 2 * approach
    else:
        if "line_length_m" not in geometry:
            raise ValueError("fields.geometry: give spans_m or line_length_m")
        total = float(geometry["line_length_m"])
    if not total > 0:
        raise ValueError(f"fields.geometry: line length must be > 0, got {total}")
    return total


def segment_index(positions_m: np.ndarray, total_length_m: float, n_segments: int) -> np.ndarray:
    """Segment of each position for the longitudinal division of the line (paper eq. 34).

    The line (0, S_tot] is cut into N equal segments (0, S/N], (S/N, 2S/N], ...; the random field
    of each segment is generated independently of the others (the paper's device for lines too
    long for one calculation). Returns integers in [0, N).
    """
    if n_segments < 1:
        raise ValueError(f"number of segments must be >= 1, got {n_segments}")
    x = np.asarray(positions_m, dtype=float)
    seg = np.ceil(x / (total_length_m / n_segments)).astype(np.int64) - 1
    return np.clip(seg, 0, n_segments - 1)
