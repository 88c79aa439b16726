"""Samples of cross-correlated random fields of track and bridge parameters (paper sec. 3.1).

Construction of one group of P parameters on its carriers x_1..x_n (docs/random_fields.md):

1. Nataf (eqs. 37-42): the target Pearson correlation R_x of the group's factors at one point gives
   the Gaussian correlation R_g with Cholesky factor C_g;
2. spatial basis A (n x m): ``kle`` -> truncated, variance-rescaled KL modes (eq. 46);
   ``mc`` -> a full-rank factor of the spatial correlation matrix (Cholesky, m = n; the paper's
   plain Monte-Carlo field of eq. 36);
3. independent standard normals eta (m x P) -> coefficients Xi = eta C_g^T (each mode's P-vector
   has correlation R_g, eq. 44) -> Gaussian fields G = A Xi (n x P), whose covariance is
   Cov(G_p(x), G_q(y)) = R_g[p, q] rho(x, y) (separable);
4. factors X = F_p^-1(Phi(G)) per parameter (eq. 45).

Rail carriers (C1, C2) with ``left_right_correlation`` rho < 1: a second set of normals gives a
second Gaussian field G2 (same basis, same R_g), and the rails get G_left = G,
G_right = rho G + sqrt(1 - rho^2) G2 before step 4; the factors are then 2n arrays (left rail,
then right rail). rho = 1 draws no extra numbers: today's single shared field, bit for bit.

Long lines may be divided into N independent segments (eq. 34, ``segments``).

Determinism: sample i of group g uses numpy.random.default_rng(SeedSequence([study_seed,
STREAM_ID, i], spawn_key=(stream_g,))) -- the g-th child of SeedSequence([seed, STREAM_ID, i]) --
so a sample never depends on the batch, the number of samples drawn or the other groups enabled.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass
from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd
from scipy import linalg

from .. import streams
from ..configuration import validate_section
from ..threads import pinned
from .covariance import correlation_matrix
from .groups import ParameterGroup, build_groups, carrier_positions, line_length_m, segment_index
from .kle import KarhunenLoeve
from .nataf import NatafTransform

log = logging.getLogger(__name__)

#: Stream id of the fields stage in the study's seed tree (:data:`ttbpipe.streams.FIELDS`).
STREAM_ID = streams.FIELDS

METHODS = ("kle", "mc")
TABLE_COLUMNS = ("sample_index", "parameter", "carrier_index", "x_m", "factor")


def full_rank_factor(positions_m: np.ndarray, correlation_length_m: float,
                     kernel: str) -> np.ndarray:
    """Matrix A with A A^T = the spatial correlation matrix (plain Monte Carlo, eq. 36).

    Cholesky when the matrix is numerically positive definite; otherwise (squared-exponential
    kernel on a fine grid is numerically singular) the symmetric square root V sqrt(L) V^T with
    eigenvalues clipped at zero, logged: unique, so independent of the eigenvectors' signs
    (which the LAPACK build chooses).
    """
    corr = correlation_matrix(positions_m, correlation_length_m, kernel)
    try:
        return linalg.cholesky(corr, lower=True)
    except linalg.LinAlgError:
        values, vectors = linalg.eigh(corr)
        clipped = int(np.sum(values < 0))
        log.info("spatial correlation matrix (%d points, %s, b = %g m) is numerically singular; "
                 "using its eigen-factor (%d negative round-off eigenvalues clipped to 0)",
                 corr.shape[0], kernel, correlation_length_m, clipped)
        return (vectors * np.sqrt(np.maximum(values, 0.0))) @ vectors.T


@dataclass
class _Segment:
    """Carriers of one segment and their spatial basis."""

    carrier_indices: np.ndarray
    basis: np.ndarray  # (n_segment_points, n_coefficients)
    captured_fraction: float


class GroupFieldSampler:
    """Random fields of one parameter group on its carriers.

    Parameters
    ----------
    group:
        a :class:`~ttbpipe.fields.groups.ParameterGroup`.
    positions_m:
        strictly increasing positions of the group's carriers (m).
    method:
        ``"kle"`` (truncated KL basis) or ``"mc"`` (full-rank spatial factor).
    variance_fraction, rescale_variance:
        KLE truncation, see :class:`~ttbpipe.fields.kle.KarhunenLoeve`.
    segments, total_length_m:
        longitudinal division into independent segments (eq. 34).
    """

    def __init__(self, group: ParameterGroup, positions_m: np.ndarray, *, method: str = "kle",
                 variance_fraction: float = 0.95, rescale_variance: bool = True,
                 segments: int = 1, total_length_m: float | None = None,
                 quadrature_nodes: int = 64) -> None:
        if method not in METHODS:
            raise ValueError(f"unknown sampling method {method!r}; expected one of {METHODS}")
        self.group = group
        self.method = method
        self.positions_m = np.asarray(positions_m, dtype=float)
        if self.positions_m.size == 0:
            raise ValueError(f"group {group.name}: no {group.carrier} carriers on this line "
                             "(a girder group needs spans_m in fields.geometry)")
        self.nataf = NatafTransform(group.marginals, group.correlation, names=group.parameters,
                                    quadrature_nodes=quadrature_nodes)
        total = float(total_length_m if total_length_m is not None else self.positions_m[-1])
        seg_of = segment_index(self.positions_m, total, segments)
        self.segments: list[_Segment] = []
        cache: dict[bytes, tuple[np.ndarray, float]] = {}
        for s in range(segments):
            idx = np.flatnonzero(seg_of == s)
            if idx.size == 0:
                continue
            local = self.positions_m[idx] - self.positions_m[idx[0]]
            key = np.round(local, 9).tobytes()  # identical segment grids share one basis
            if key not in cache:
                if method == "kle":
                    kle = KarhunenLoeve(local, group.correlation_length_m, group.kernel,
                                        variance_fraction=variance_fraction,
                                        rescale_variance=rescale_variance)
                    cache[key] = (kle.modes_matrix, kle.captured_fraction)
                else:
                    cache[key] = (full_rank_factor(local, group.correlation_length_m,
                                                   group.kernel), 1.0)
            basis, fraction = cache[key]
            self.segments.append(_Segment(idx, basis, fraction))
        self.n_coefficients = sum(seg.basis.shape[1] for seg in self.segments)
        rho = group.left_right_correlation
        #: 2 when each rail has its own field (rail carriers with rho < 1), else 1
        self.n_rails = 2 if rho is not None and rho < 1.0 else 1
        self.left_right_correlation = rho
        #: independent standard normals per parameter of one realisation
        self.n_normals = self.n_rails * self.n_coefficients
        log.info("group %s (%s, %d carriers, %s, b = %g m, %d segment(s)): %s with %d "
                 "coefficients per parameter%s", group.name, group.carrier,
                 self.positions_m.size, group.kernel, group.correlation_length_m,
                 len(self.segments), method, self.n_coefficients,
                 "" if method == "mc" else
                 f", captured variance {min(s.captured_fraction for s in self.segments):.4f}")

    def gaussian_fields(self, independent_normals: np.ndarray) -> np.ndarray:
        """Independent standard normals (n_coefficients, P) -> Gaussian fields (n_carriers, P)."""
        eta = np.asarray(independent_normals, dtype=float)
        out = np.empty((self.positions_m.size, len(self.group.parameters)))
        start = 0
        for seg in self.segments:
            m = seg.basis.shape[1]
            out[seg.carrier_indices] = seg.basis @ self.nataf.correlate(eta[start:start + m])
            start += m
        return out

    def factors_from_normals(self, independent_normals: np.ndarray) -> np.ndarray:
        """Independent standard normals (n_normals, P) -> factors (P, n_rails * n_carriers).

        Rows 0..n_coefficients-1 give the (left-rail or shared) field; with two rails the next
        n_coefficients rows give the independent part of the right rail's field (module
        docstring). Pure: the map the rare-event code evaluates.
        """
        eta = np.asarray(independent_normals, dtype=float)
        shape = (self.n_normals, len(self.group.parameters))
        if eta.shape != shape:
            raise ValueError(f"group {self.group.name}: normals of shape {eta.shape}, expected "
                             f"{shape}")
        m = self.n_coefficients
        gaussian = self.gaussian_fields(eta[:m])
        if self.n_rails == 2:
            rho = float(self.left_right_correlation)
            right = rho * gaussian + np.sqrt(1.0 - rho * rho) * self.gaussian_fields(eta[m:])
            gaussian = np.concatenate([gaussian, right])
        return self.nataf.to_physical(gaussian).T

    def sample(self, rng: np.random.Generator) -> np.ndarray:
        """One realisation: factors (P, n_rails * n_carriers).

        The shared (or left-rail) normals are drawn first, exactly as for one field, so that
        rho = 1 reproduces the single shared field and rho < 1 keeps the left rail's field of
        the same sample and seed."""
        eta = rng.standard_normal((self.n_coefficients, len(self.group.parameters)))
        if self.n_rails == 2:
            eta = np.concatenate([eta, rng.standard_normal(eta.shape)])
        return self.factors_from_normals(eta)


def sample_generator(study_seed: int, sample_index: int, stream: int) -> np.random.Generator:
    """Generator of one sample and one group: child ``stream`` of SeedSequence([seed, STREAM_ID, i])."""
    return np.random.default_rng(np.random.SeedSequence([int(study_seed), STREAM_ID,
                                                         int(sample_index)],
                                                        spawn_key=(int(stream),)))


class FieldSampler:
    """All configured groups of a study (the ``fields:`` section of config/config.yaml).

    Parameters
    ----------
    fields_config:
        the ``fields:`` mapping.
    study_seed:
        ``study.seed``.
    positions:
        optional carrier positions {carrier_kind: array}; default: built from
        ``fields_config["geometry"]`` by :func:`~ttbpipe.fields.groups.carrier_positions`.
    method:
        overrides ``fields_config["method"]``.
    """

    @pinned   # the KL bases' eigen-decompositions: one BLAS thread (ttbpipe.threads)
    def __init__(self, fields_config: Mapping[str, Any], study_seed: int, *,
                 positions: Mapping[str, np.ndarray] | None = None,
                 method: str | None = None) -> None:
        # validated, defaults filled from the study schema (their only home)
        self.config = validate_section(fields_config, "fields")
        self.study_seed = int(study_seed)
        self.method = method or self.config["method"]
        geometry = self.config.get("geometry", {})
        if positions is None:
            positions = carrier_positions(geometry)
            total = line_length_m(geometry)
        else:
            positions = {k: np.asarray(v, dtype=float) for k, v in positions.items()}
            total = max(float(np.max(v)) for v in positions.values() if len(v))
        self.positions = dict(positions)
        self.groups = build_groups(self.config)
        self.samplers: list[GroupFieldSampler] = []
        for group in self.groups:
            if group.carrier not in self.positions:
                raise ValueError(f"group {group.name}: no positions for carrier kind "
                                 f"{group.carrier!r}")
            self.samplers.append(GroupFieldSampler(
                group, self.positions[group.carrier], method=self.method,
                variance_fraction=float(self.config["variance_fraction"]),
                rescale_variance=bool(self.config["rescale_variance"]),
                segments=int(self.config["segments"]), total_length_m=total,
                quadrature_nodes=int(self.config["quadrature_nodes"])))

    @property
    def parameters(self) -> list[str]:
        return [p for g in self.groups for p in g.parameters]

    @pinned
    def sample(self, sample_index: int) -> dict[str, np.ndarray]:
        """Factors of sample ``sample_index``: {parameter: (n_carriers,) array}."""
        if sample_index < 0:
            raise ValueError(f"sample index must be >= 0, got {sample_index}")
        out: dict[str, np.ndarray] = {}
        for sampler in self.samplers:
            rng = sample_generator(self.study_seed, sample_index, sampler.group.stream)
            factors = sampler.sample(rng)
            bad = ~(np.isfinite(factors) & (factors > 0))
            if np.any(bad):
                p, c = np.argwhere(bad)[0]
                raise ValueError(
                    f"sample {sample_index}: factor {factors[p, c]} of "
                    f"{sampler.group.parameters[p]} at carrier {c} is not a positive finite "
                    f"number ({int(bad.sum())} such values); use a lognormal, gamma or "
                    "truncated_normal marginal, or a smaller cov, for this group")
            for p, name in enumerate(sampler.group.parameters):
                out[name] = factors[p]
        return out

    def table(self, sample_indices: Iterable[int]) -> pd.DataFrame:
        """Long table (TABLE_COLUMNS) of the given samples, one row per sample/parameter/carrier.

        With a field per rail, carrier_index n..2n-1 are the right rail's carriers at the same
        x_m as 0..n-1 (the 2n layout ttbpipe.structure.apply_factors reads)."""
        columns: dict[str, list[np.ndarray]] = {c: [] for c in TABLE_COLUMNS}
        for i in sample_indices:
            factors = self.sample(int(i))
            for sampler in self.samplers:
                x = np.tile(sampler.positions_m, sampler.n_rails)
                for name in sampler.group.parameters:
                    columns["sample_index"].append(np.full(x.size, i, dtype=np.int64))
                    columns["parameter"].append(np.full(x.size, name, dtype=object))
                    columns["carrier_index"].append(np.arange(x.size, dtype=np.int64))
                    columns["x_m"].append(x)
                    columns["factor"].append(factors[name])
        if not columns["factor"]:
            return pd.DataFrame({c: [] for c in TABLE_COLUMNS})
        df = pd.DataFrame({c: np.concatenate(v) for c, v in columns.items()})
        df["parameter"] = df["parameter"].astype(str)
        return df

    def summary(self) -> dict[str, Any]:
        """Per-group description stored in the table's provenance."""
        return {s.group.name: {"carrier": s.group.carrier, "parameters": s.group.parameters,
                               "n_carriers": int(s.positions_m.size),
                               "coefficients_per_parameter": s.n_coefficients,
                               "rails": s.n_rails,
                               "left_right_correlation": s.left_right_correlation,
                               "captured_variance": min(seg.captured_fraction
                                                        for seg in s.segments),
                               "gaussian_correlation": s.nataf.gaussian_correlation}
                for s in self.samplers}


def positions_from_structure(structure_config: Mapping[str, Any] | None) -> dict[str, np.ndarray]:
    """Carrier positions of the structure model (``ttbpipe.structure``, docs/dev/structure_interface.md).

    Used when ``fields.geometry.source: structure`` so that the samples' carrier_index matches the
    mesh that ``ttbpipe.structure.apply_factors`` multiplies.
    """
    from ..structure import build_structure
    from ..structure import carrier_positions as structure_carrier_positions

    model = build_structure(dict(structure_config or {}))
    return {k: np.asarray(v, dtype=float) for k, v in structure_carrier_positions(model).items()}


def sample_study(config: Mapping[str, Any], out_path: str | os.PathLike[str], *,
                 n_samples: int | None = None, method: str | None = None,
                 first_sample: int = 0) -> pd.DataFrame:
    """Draw a study's field samples from its resolved configuration and write the Parquet table."""
    from ..io import write_table

    if "fields" not in config:
        raise ValueError("configuration has no 'fields:' section; copy the one in "
                         "config/config.yaml")
    fields_config = validate_section(config["fields"], "fields")
    positions = None
    if fields_config.get("geometry", {}).get("source", "fields") == "structure":
        positions = positions_from_structure(config.get("structure"))
    sampler = FieldSampler(fields_config, config["study"]["seed"], method=method,
                           positions=positions)
    n = int(n_samples if n_samples is not None else fields_config["samples"])
    if n < 1:
        raise ValueError(f"number of samples must be >= 1, got {n}")
    df = sampler.table(range(first_sample, first_sample + n))
    write_table(df, out_path, config=config, kind="field_samples", method=sampler.method,
                n_samples=n, first_sample=first_sample, stream_id=STREAM_ID,
                groups=sampler.summary())
    log.info("wrote %d samples x %d parameters (%d rows) to %s", n, len(sampler.parameters),
             len(df), out_path)
    return df


def load_field_factors(path_or_df: str | os.PathLike[str] | pd.DataFrame,
                       sample_index: int) -> dict[str, np.ndarray]:
    """Factors of one sample: {parameter: array over carrier_index 0..n-1}.

    Reads only that sample's rows from a Parquet file (predicate push-down). Raises KeyError when
    the sample is not in the table and ValueError when a parameter's carriers are not exactly
    0..n-1 (a corrupt or hand-edited table).
    """
    source = "table"
    if isinstance(path_or_df, pd.DataFrame):
        df = path_or_df[path_or_df["sample_index"] == sample_index]
    else:
        import pyarrow.parquet as pq

        source = str(path_or_df)
        df = pq.read_table(path_or_df, filters=[("sample_index", "==", int(sample_index))],
                           columns=["parameter", "carrier_index", "factor"]).to_pandas()
    if df.empty:
        raise KeyError(f"{source}: no rows for sample_index {sample_index}")
    out: dict[str, np.ndarray] = {}
    for name, rows in df.groupby("parameter", sort=False):
        rows = rows.sort_values("carrier_index")
        carriers = rows["carrier_index"].to_numpy()
        if not np.array_equal(carriers, np.arange(carriers.size)):
            raise ValueError(f"{source}: sample {sample_index}, parameter {name}: carrier_index "
                             "is not 0..n-1 without gaps or duplicates")
        out[str(name)] = rows["factor"].to_numpy(dtype=float)
    return out
