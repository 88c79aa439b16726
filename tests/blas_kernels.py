"""OpenBLAS kernel families the tests may force with ``OPENBLAS_CORETYPE`` on this processor.

Forcing a kernel the processor cannot execute kills the process with SIGILL (OpenBLAS's
SkylakeX kernels on a processor without AVX-512, e.g. the AMD EPYC machines of the shared pool),
so the tests that compare results across kernels ask here which ones run. numpy reports the
processor's features (``__cpu_features__``: ``AVX512_SKX`` is the Skylake-X group OpenBLAS's
SkylakeX kernels need, ``AVX2`` and ``FMA3`` Haswell's, ``SSE3`` Prescott's).
"""

from __future__ import annotations

import platform

#: OpenBLAS core type -> the numpy CPU features it needs (x86-64 only).
CORE_FEATURES = {"SkylakeX": ("AVX512_SKX",), "Haswell": ("AVX2", "FMA3"), "Prescott": ("SSE3",)}


def cpu_features() -> dict[str, bool]:
    try:
        from numpy._core._multiarray_umath import __cpu_features__
    except ImportError:   # numpy < 2
        from numpy.core._multiarray_umath import __cpu_features__
    return dict(__cpu_features__)


def runnable_cores(wanted=("Haswell", "SkylakeX", "Prescott")) -> list[str]:
    """The core types of ``wanted`` (in that order) this processor can run; none off x86-64,
    where OpenBLAS names other kernels."""
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return []
    features = cpu_features()
    return [core for core in wanted if all(features.get(f, False) for f in CORE_FEATURES[core])]
