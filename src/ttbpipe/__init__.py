"""ttbpipe: probabilistic dynamic assessment of railway train-track-bridge systems.

Conventions used everywhere inside the package (see ``docs/conventions.md``):

* SI units inside (m, s, kg, N, Pa); irregularities may be mm at file boundaries, where
  column names carry the unit (``vertical_left_mm``).
* Track axes: x along the track in the direction of increasing chainage (the direction of
  travel), y lateral positive to the **left** when looking in the direction of travel, z vertical
  positive **up**.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version as _version

try:
    __version__ = _version("ttbpipe")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0+unknown"

__all__ = ["__version__", "code_version"]

_CODE_SUFFIXES = (".py", ".json", ".yaml", ".csv")


def code_version() -> str:
    """``<version>+<digest>``: the release plus a SHA-256 digest (12 hex digits) of the package's
    code and data files (.py, .json, .yaml, .csv under ``ttbpipe/``, sorted by path).

    Snakemake does not track package code for reruns, so every rule passes this through
    ``params:``: a changed model reruns what it made, even between releases, and every table's
    provenance says exactly which code made it.
    """
    global _CODE_VERSION
    if _CODE_VERSION is None:
        import hashlib
        from pathlib import Path

        root = Path(__file__).resolve().parent
        digest = hashlib.sha256()
        for path in sorted(p for p in root.rglob("*") if p.suffix in _CODE_SUFFIXES
                           and "__pycache__" not in p.parts):
            digest.update(path.relative_to(root).as_posix().encode() + b"\0")
            digest.update(path.read_bytes() + b"\0")
        _CODE_VERSION = f"{__version__}+{digest.hexdigest()[:12]}"
    return _CODE_VERSION


_CODE_VERSION: str | None = None


def _refresh_kernel_cache() -> None:
    # numba does not see a change in another module than a kernel's own (ttbpipe.kernel_cache)
    try:
        from .kernel_cache import refresh

        refresh()
    except OSError:
        pass


_refresh_kernel_cache()
