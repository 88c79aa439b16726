"""Physical constants: one home for each, with its source.

Only constants of nature and conventional standard values belong here. Material properties
(rail Young's modulus, densities, ...) are parameters with their own sources and live with the
models that use them (``ttbpipe.structure.properties``, ``ttbpipe.vehicle.parameters``).
"""

from __future__ import annotations

__all__ = ["STANDARD_GRAVITY"]

#: Standard acceleration of gravity g_n (m/s^2), exact by definition: 3rd General Conference on
#: Weights and Measures (CGPM, 1901), restated in ISO 80000-3. The gravity load of the vehicles
#: and the limits given in g (EN 1990 Annex A2, TB 10621) use it.
STANDARD_GRAVITY = 9.80665
