"""Karhunen-Loeve expansion: analytical eigenvalues, convergence order, truncation, rescaling.

Reference: exact eigenvalues of the exponential kernel on [-a, a] (Ghanem & Spanos 1991,
sec. 2.3.3; classic value lambda_1 = 1.14931 at a = b = 1, reference/uq.md); the mode counts of
reference/uq.md for L/b = 10 (about 41 modes for 95 %).
"""

import numpy as np
import pytest

from ttbpipe.fields.covariance import correlation_matrix
from ttbpipe.fields.kle import (KarhunenLoeve, exponential_kernel_eigenvalues,
                                modes_for_fractions, trapezoid_weights)


def test_reference_eigenvalues_published_value():
    """The transcendental-equation solver gives the classic lambda_1 = 1.14931 (5 digits)."""
    values = exponential_kernel_eigenvalues(10, 1.0, 1.0)
    assert values[0] == pytest.approx(1.14931, abs=1e-5)
    assert 2.0 / (0.860334 ** 2 + 1.0) == pytest.approx(values[0], abs=1e-6)
    assert np.all(np.diff(values) < 0)


@pytest.mark.parametrize("half_length, correlation_length, n",
                         [(1.0, 1.0, 401), (50.0, 10.0, 501)])
def test_first_ten_eigenvalues_within_0p1_percent(half_length, correlation_length, n):
    """Trapezoid Nystrom: first ten eigenvalues within 0.1 % of the exact ones.

    Grids: h = b/200 for a = b = 1 (w_10 h = 0.07), h = b/50 for L/b = 10 (w_10 h = 0.06).
    """
    x = np.linspace(-half_length, half_length, n)
    kle = KarhunenLoeve(x, correlation_length, n_modes=10)
    exact = exponential_kernel_eigenvalues(10, half_length, correlation_length)
    assert np.max(np.abs(kle.eigenvalues / exact - 1)) < 1e-3


def test_second_order_convergence():
    """Halving the grid step divides the eigenvalue error by about 4 (ratio in [3.6, 4.4])."""
    exact = exponential_kernel_eigenvalues(10, 1.0, 1.0)
    errors = []
    for n in (101, 201, 401):
        kle = KarhunenLoeve(np.linspace(-1, 1, n), 1.0, n_modes=10)
        errors.append(np.abs(kle.eigenvalues / exact - 1))
    for coarse, fine in zip(errors[:-1], errors[1:]):
        ratio = coarse / fine
        assert np.all((ratio > 3.6) & (ratio < 4.4)), ratio


def test_nonuniform_grid_converges():
    """Trapezoid weights on a jittered grid (steps 0.5h..1.5h) still give 0.1 % accuracy."""
    rng = np.random.default_rng(7)
    steps = 0.005 * (0.5 + rng.random(400))
    x = np.concatenate([[0.0], np.cumsum(steps)])
    x = x / x[-1] * 2.0 - 1.0
    kle = KarhunenLoeve(x, 1.0, n_modes=5)
    exact = exponential_kernel_eigenvalues(5, 1.0, 1.0)
    assert np.max(np.abs(kle.eigenvalues / exact - 1)) < 1e-3


def test_weighted_orthonormality_and_full_reconstruction():
    """sum_i w_i phi_k phi_l = delta_kl; with all modes Phi Lambda Phi^T equals C (round-off)."""
    x = np.sort(np.random.default_rng(3).uniform(0, 50, 80))
    kle = KarhunenLoeve(x, 8.0, n_modes=80, rescale_variance=False)
    w = trapezoid_weights(x)
    gram = kle.eigenfunctions.T @ (w[:, None] * kle.eigenfunctions)
    np.testing.assert_allclose(gram, np.eye(80), atol=1e-10)
    rebuilt = (kle.eigenfunctions * kle.eigenvalues) @ kle.eigenfunctions.T
    np.testing.assert_allclose(rebuilt, correlation_matrix(x, 8.0), atol=1e-10)
    assert kle.captured_fraction == pytest.approx(1.0, abs=1e-12)


def test_variance_fraction_and_mode_counts_against_reference():
    """L/b = 10 on a fine grid: about 41 modes for 95 %, about 200 for 99 % (reference/uq.md).

    Also the asymptotic count 2 L / (pi^2 b (1 - f)) from lambda_k ~ 2b / (1 + (k pi b / L)^2).
    """
    x = np.linspace(0, 100, 1001)
    counts = modes_for_fractions(x, 10.0, "exponential")
    assert 39 <= counts[0.95] <= 43
    assert 190 <= counts[0.99] <= 210
    kle = KarhunenLoeve(x, 10.0, variance_fraction=0.95)
    assert kle.n_modes == counts[0.95]
    assert kle.captured_fraction >= 0.95
    assert np.sum(kle.eigenvalues[:-1]) / kle.total_variance < 0.95
    # The squared-exponential kernel needs far fewer modes.
    assert modes_for_fractions(x, 10.0, "squared_exponential")[0.95] < counts[0.95] / 2


def test_truncated_variance_and_rescaling():
    """Truncation lowers the pointwise variance most at the ends; rescaling restores exactly 1."""
    x = np.linspace(0, 100, 501)
    raw = KarhunenLoeve(x, 10.0, variance_fraction=0.95, rescale_variance=False)
    v = raw.pointwise_variance
    assert v.max() < 1.0 and v[0] < v[250]
    rows = np.sum(raw.modes_matrix ** 2, axis=1)
    np.testing.assert_allclose(rows, v, rtol=1e-12)
    scaled = KarhunenLoeve(x, 10.0, variance_fraction=0.95, rescale_variance=True)
    np.testing.assert_allclose(np.sum(scaled.modes_matrix ** 2, axis=1), 1.0, rtol=1e-12)


def test_leading_subset_path_matches_full_solution(monkeypatch):
    """The doubling subset search (large grids) selects the same modes as the full solution."""
    import ttbpipe.fields.kle as kle_module

    x = np.linspace(0, 60, 301)
    full = KarhunenLoeve(x, 5.0, variance_fraction=0.9)
    monkeypatch.setattr(kle_module, "_FULL_EIGH_LIMIT", 10)
    subset = KarhunenLoeve(x, 5.0, variance_fraction=0.9)
    assert subset.n_modes == full.n_modes
    np.testing.assert_allclose(subset.eigenvalues, full.eigenvalues, rtol=1e-10)


def test_bad_grid_raises():
    with pytest.raises(ValueError, match="strictly increasing"):
        KarhunenLoeve(np.array([0.0, 1.0, 1.0, 2.0]), 1.0)


def test_kle_basis_does_not_depend_on_the_lapack_build():
    """The same KLE basis (hence the same field for the same coefficients), to 1e-9, under
    OpenBLAS's AVX-512, AVX2 and SSE3 kernels (those the processor runs) and with one or two
    BLAS threads: eigenvector signs
    are fixed by ttbpipe.fields.kle.fix_eigenvector_signs. Without it the signs followed the
    build and a study's pad factors changed by 2 % between thread settings."""
    import json
    import os
    import subprocess
    import sys

    code = ("import json, numpy as np; from ttbpipe.fields.kle import KarhunenLoeve; "
            "k = KarhunenLoeve(np.arange(0.0, 150.0, 0.63), 10.0, variance_fraction=0.95); "
            "print(json.dumps(k.modes_matrix.tolist()))")
    from blas_kernels import runnable_cores

    # every kernel family this processor can run (tests/blas_kernels.py: forcing AVX-512 kernels
    # without AVX-512 is SIGILL), each with one thread, and the first also with two
    cores = runnable_cores() or [None]
    settings = [(core, "1") for core in cores] + [(cores[0], "2")]
    bases = []
    for core, threads in settings:
        env = {**os.environ, "OPENBLAS_NUM_THREADS": threads, "OMP_NUM_THREADS": threads}
        if core is not None:
            env["OPENBLAS_CORETYPE"] = core
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                             text=True, check=True).stdout
        bases.append(np.array(json.loads(out)))
    assert bases[0].shape[1] > 10
    for other in bases[1:]:
        np.testing.assert_allclose(other, bases[0], rtol=0, atol=1e-9)
