"""ttbpipe: probabilistic dynamic assessment of railway train-track-bridge systems.

Conventions used everywhere inside the package (see ``docs/conventions.md``):

* SI units inside (m, s, kg, N, Pa); irregularities may be mm at file boundaries, where
  column names carry the unit (``vertical_left_mm``).
* Track axes: x along the track in the direction of increasing chainage (the direction of
  travel), y lateral positive to the **left** when looking in the direction of travel, z vertical
  positive **up**.
"""

from importlib.metadata import PackageNotFoundError, version as _version

try:
    __version__ = _version("ttbpipe")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0+unknown"

__all__ = ["__version__"]
