"""Railway vehicles (35-DOF cars), 3-D wheel-rail contact, static equilibrium and ride comfort.

* :mod:`.parameters` -- the default CRH-type parameter set with sources; ``train_from_config``;
* :mod:`.model` -- mass, stiffness and damping matrices of a train (seed paper App. B);
* :mod:`.contact` -- Hertz, contact geometry (conical or tabulated), Kalker, Shen-Hedrick-Elkins,
  flange contact;
* :mod:`.kernels` -- numba kernels of the contact forces for the whole train;
* :mod:`.static` -- gravity-loaded equilibrium (rigid track or coupled to the structure);
* :mod:`.comfort` -- Sperling ride index.

The coupled time loop is :func:`ttbpipe.simulation.coupled.run_coupled`. See docs/vehicle.md.
"""
