"""Reliability methods for rare exceedance probabilities of the per-passage maxima.

:mod:`ttbpipe.reliability.tail`: extreme-value tail model (GEV of the maxima or peaks over
threshold), weighted maximum likelihood, profile-likelihood or bootstrap intervals
(``docs/reliability.md``).
"""
