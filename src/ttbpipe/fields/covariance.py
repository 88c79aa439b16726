"""Stationary correlation kernels of 1-D random fields along the track.

Both kernels are functions of the separation d = |x - y| and a correlation length b (m):

* ``exponential``          rho(d) = exp(-d / b)         (Ornstein-Uhlenbeck / Markov field;
  analytical KL eigenpairs in Ghanem & Spanos 1991, "Stochastic finite elements", sec. 2.3.3);
* ``squared_exponential``  rho(d) = exp(-(d / b)^2)     (smooth field; note: b here, not the
  sqrt(2) l of the "exp(-d^2 / 2 l^2)" convention).

An infinite correlation length gives a fully correlated field (one random value per line).
"""

from __future__ import annotations

import numpy as np

KERNELS = ("exponential", "squared_exponential")


def correlation_function(distance: np.ndarray, correlation_length_m: float,
                         kernel: str = "exponential") -> np.ndarray:
    """Correlation rho(d) of the named kernel at separations ``distance`` (m)."""
    if not correlation_length_m > 0:
        raise ValueError(f"correlation length must be > 0 m, got {correlation_length_m}")
    scaled = np.abs(np.asarray(distance, dtype=float)) / correlation_length_m
    if kernel == "exponential":
        return np.exp(-scaled)
    if kernel == "squared_exponential":
        return np.exp(-scaled * scaled)
    raise ValueError(f"unknown kernel {kernel!r}; expected one of {KERNELS}")


def correlation_matrix(positions_m: np.ndarray, correlation_length_m: float,
                       kernel: str = "exponential") -> np.ndarray:
    """Correlation matrix rho(|x_i - x_j|) of a field at the given positions."""
    x = np.asarray(positions_m, dtype=float)
    return correlation_function(x[:, None] - x[None, :], correlation_length_m, kernel)
