"""The random inputs of a study sample as a function of independent standard normals u ~ N(0, I).

Rare-event methods (subset simulation, Au & Beck 2001, Prob. Eng. Mech. 16:263) work in the
standard-normal space; :class:`StandardNormalInputs` is the map from that space to what the
coupled run takes: an irregularity profile (four spectral channels, mm) and the random-field
factors of the structure (``run_coupled(case, track=profile, factors=factors)``, as
:func:`ttbpipe.study.samples.run_sample` hands them over).

* Irregularity: :class:`ttbpipe.irregularity.gaussian.GaussianIrregularityModel` -- the
  Gaussian spectral representation (random Fourier coefficients, Shinozuka & Deodatis 1991) of a
  standard spectrum, or of a PSD population's per-frequency fits with a random spectral level
  (seed paper §3.2 step 3).
* Fields: :class:`ttbpipe.fields.sampling.GroupFieldSampler.factors_from_normals` of every
  enabled group on the structure's carriers (KLE or full-rank basis, Nataf marginals; one field
  per rail for C1/C2 when ``fields.left_right_correlation`` < 1).

The map is deterministic and pure (no random state; BLAS pinned to one thread as for the study's
samples). u = 0 gives a zero profile at the median spectral level and the factors F^-1(1/2) of
every marginal -- the mean field for the symmetric (normal) marginals of the paper's case 2.

Dimension of the default study (config/config.yaml: TB/T 3352 at dx 0.25 m over the default
structure's rails, -20 to 256.5 m with the 20 m lead-in; groups C1-C4, KLE 95 %, one field
shared by both rails), as ``tests/test_reliability_inputs.py::test_default_study_dimension``
prints it: n_dims = 2144 = 4 x 278 irregularity coefficients (139 FFT frequencies in 2-200 m)
+ C1 396 + C2 396 (99 KL coefficients x 4 parameters each) + C3 100 + C4 140. With
``fields.left_right_correlation`` < 1 the C1 and C2 slices double (2936).
"""

from __future__ import annotations

import copy
from typing import Any, Mapping

import numpy as np
import pandas as pd

from ..configuration import validate_section
from ..irregularity.gaussian import GaussianIrregularityModel, standard_normal_point
from ..irregularity.spectra import TrackSpectrum
from ..threads import pinned

__all__ = ["StandardNormalInputs"]


class StandardNormalInputs:
    """u -> (profile, field factors) of one study configuration.

    Parameters
    ----------
    config
        The study configuration (at least ``structure:``; ``simulation.irregularity``
        (spectrum, dx_m, lead_in_m) and ``fields:`` as in the study; without a ``fields:``
        section the structure is deterministic).
    spectrum
        The spectrum source: a standard spectrum name or :class:`TrackSpectrum` (default: the
        study's ``simulation.irregularity.spectrum``), a
        :class:`ttbpipe.tipm.population.PSDPopulation` (fitted here,
        :meth:`GaussianIrregularityModel.from_population`), or a fits table of
        :func:`ttbpipe.tipm.distribution.fit_ordinate_distributions`.
    condition
        ``"all"`` (every enabled group) or one group (``C1`` ... ``C4``), as the study's
        fields scenarios.
    length_m
        Profile length; default: the structure's rails plus ``lead_in_m`` (the profile starts
        ``lead_in_m`` before the first rail node, as the study's profiles do).
    wavelength_band_m
        Synthesis band; default: the spectrum's valid band (2-200 m for a population).
    irregularity_options
        Further keywords of :class:`GaussianIrregularityModel` (or of ``from_population``):
        ``level_split_wavelengths_m``, ``frequency_score_correlation``, ``family``, ...

    Attributes
    ----------
    n_dims
        Length of u.
    slices
        {name: slice of u}, disjoint and covering 0..n_dims: ``irregularity/<channel>/level``,
        ``irregularity/<channel>/coefficients`` (:class:`GaussianIrregularityModel`), then per
        field group ``fields/<group>`` (shared field of both rails, or a slab/girder group) or
        ``fields/<group>/left`` and ``fields/<group>/right_innovation`` (the independent part Z2
        of the right rail, right = rho·left + sqrt(1 − rho²)·Z2). A field slice holds the
        (n_coefficients, P) normals of the group row-major (coefficient-major).

    Example
    -------
    >>> inputs = StandardNormalInputs(config)                  # doctest: +SKIP
    >>> profile, factors = inputs.map(np.zeros(inputs.n_dims))  # doctest: +SKIP
    >>> run_coupled(case, track=profile, factors=factors)      # doctest: +SKIP

    where ``case = build_case(sim, structure, irregularity=inputs.irregularity_settings)``
    (:func:`ttbpipe.study.samples.build_case`).
    """

    def __init__(self, config: Mapping[str, Any], *, spectrum: Any = None,
                 condition: str = "all", length_m: float | None = None,
                 wavelength_band_m: tuple[float, float] | None = None,
                 **irregularity_options: Any) -> None:
        from ..fields.sampling import FieldSampler
        from ..structure import build_structure
        from ..structure import carrier_positions as structure_carrier_positions

        sim = validate_section(config.get("simulation"), "simulation")
        irr = sim["irregularity"]
        structure_config = copy.deepcopy(dict(config.get("structure") or {}))
        model = build_structure(structure_config)
        x_min, x_max = (float(v) for v in model.rail_x_range)
        self.dx_m = float(irr["dx_m"])
        self.lead_in_m = float(irr["lead_in_m"])
        self.chainage_start_m = x_min - self.lead_in_m
        self.length_m = float(length_m) if length_m is not None else \
            (x_max - self.chainage_start_m + 2 * self.dx_m)
        #: the case's irregularity section for a profile handed over in memory
        self.irregularity_settings = {"fade_in_m": float(irr["fade_in_m"])}

        source = irr["spectrum"] if spectrum is None else spectrum
        if isinstance(source, (str, TrackSpectrum)):
            self.irregularity = GaussianIrregularityModel(
                self.length_m, self.dx_m, wavelength_band_m, spectrum=source,
                **irregularity_options)
        elif isinstance(source, pd.DataFrame):
            self.irregularity = GaussianIrregularityModel(
                self.length_m, self.dx_m, wavelength_band_m, fits=source, **irregularity_options)
        elif hasattr(source, "psd_mm2_m") and hasattr(source, "frequency_per_m"):
            self.irregularity = GaussianIrregularityModel.from_population(
                source, self.length_m, self.dx_m,
                wavelength_band_m if wavelength_band_m is not None else (2.0, 200.0),
                **irregularity_options)
        else:
            raise TypeError(f"spectrum: {type(source).__name__}; expected a spectrum name, a "
                            "TrackSpectrum, a PSDPopulation or a fits table")

        self.slices: dict[str, slice] = dict(self.irregularity.slices)
        start = self.irregularity.n_dims
        self.field_samplers = []
        fields = config.get("fields")
        if fields is not None:
            fields = copy.deepcopy(dict(fields))
            if condition != "all":
                groups = fields.get("groups", {})
                if condition not in groups:
                    raise ValueError(f"fields.groups has no group {condition}")
                fields["groups"] = {n: {**g, "enabled": n == condition}
                                    for n, g in groups.items()}
            positions = {k: np.asarray(v, dtype=float)
                         for k, v in structure_carrier_positions(model).items()}
            # carriers of the structure's mesh, as the study's fields scenarios use them
            sampler = FieldSampler(fields, 0, positions=positions)
            for group_sampler in sampler.samplers:
                name = group_sampler.group.name
                size = group_sampler.n_coefficients * len(group_sampler.group.parameters)
                parts = ([f"fields/{name}"] if group_sampler.n_rails == 1 else
                         [f"fields/{name}/left", f"fields/{name}/right_innovation"])
                for part in parts:
                    self.slices[part] = slice(start, start + size)
                    start += size
                self.field_samplers.append(group_sampler)
        self.n_dims = start

    def describe(self) -> dict[str, int]:
        """{slice name: number of dimensions}."""
        return {k: s.stop - s.start for k, s in self.slices.items()}

    def _check(self, u: np.ndarray) -> np.ndarray:
        return standard_normal_point(u, self.n_dims)

    def profile(self, u: np.ndarray) -> pd.DataFrame:
        """The irregularity profile of u, chainage from the start of the lead-in (m)."""
        u = self._check(u)
        table = self.irregularity.profile(u[:self.irregularity.n_dims])
        table["chainage_m"] = table["chainage_m"] + self.chainage_start_m
        return table

    @pinned
    def factors(self, u: np.ndarray) -> dict[str, np.ndarray]:
        """Field factors {parameter: array over the structure's carriers (2n: both rails)}.

        Raises ValueError naming the parameter when a factor is not positive (a normal marginal
        reaches 0 at u ≈ −1/cov): the limit-state code decides what such a point means.
        """
        u = self._check(u)
        out: dict[str, np.ndarray] = {}
        for sampler in self.field_samplers:
            name, n_par = sampler.group.name, len(sampler.group.parameters)
            if sampler.n_rails == 1:
                eta = u[self.slices[f"fields/{name}"]].reshape(sampler.n_coefficients, n_par)
            else:
                eta = np.concatenate([
                    u[self.slices[f"fields/{name}/left"]].reshape(sampler.n_coefficients, n_par),
                    u[self.slices[f"fields/{name}/right_innovation"]].reshape(
                        sampler.n_coefficients, n_par)])
            values = sampler.factors_from_normals(eta)
            for p, parameter in enumerate(sampler.group.parameters):
                f = values[p]
                if not np.all(np.isfinite(f) & (f > 0)):
                    raise ValueError(f"u maps {parameter} (group {name}) to a non-positive or "
                                     "non-finite factor; use a lognormal, gamma or "
                                     "truncated_normal marginal for this group")
                out[parameter] = f
        return out

    def map(self, u: np.ndarray) -> tuple[pd.DataFrame, dict[str, np.ndarray]]:
        """(profile table, field factors) of u: the coupled run's random inputs."""
        return self.profile(u), self.factors(u)

    __call__ = map
