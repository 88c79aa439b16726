"""Track-bridge structure: rails on fasteners, slab/ballasted track, girders, piers.

Linear part of the Xu-Zhai-Li train-track-bridge model (paper sections 2.2.4-2.2.10). Entry points:

* :func:`build_structure` -- config dict -> :class:`StructureModel` (packed arrays for numba);
* :func:`apply_factors` / :func:`carrier_positions` -- random-field factors per carrier
  (a case's ``properties:`` section: :mod:`.random_properties`);
* :mod:`.kernels` (``structure_accelerations``) and :mod:`.rail_mesh` (kinematics and loads at
  points of the rails): the interface of whatever runs on the rails
  (docs/dev/structure_interface.md); :mod:`.monitors` (recorded points), :mod:`.static`
  (K u = f);
* :func:`~ttbpipe.structure.moving_loads.simulate` -- moving point loads, Zhai time loop;
* :func:`~ttbpipe.structure.modal.modal_analysis` -- frequencies and mode shapes;
* :mod:`.plate` -- Kirchhoff thin-plate element (the slab measured as a plate against the beam,
  docs/structure.md section 10).

Decisions and validation: docs/structure.md.
"""

from .assembly import (CARRIER_PARAMETERS, StructureModel, apply_factors, build_structure,
                       carrier_positions)

__all__ = ["CARRIER_PARAMETERS", "StructureModel", "apply_factors", "build_structure",
           "carrier_positions"]
