"""Railway vehicles (35-DOF cars), 3-D wheel-rail contact, static equilibrium and ride comfort.

* :mod:`.parameters` -- the default CRH-type parameter set with sources; ``train_from_config``;
* :mod:`.model` -- mass, stiffness and damping matrices of a train (seed paper App. B);
* :mod:`.contact` -- Hertz, contact geometry (conical or tabulated), Kalker, Shen-Hedrick-Elkins,
  flange contact;
* :mod:`.profiles` -- wheel and rail profiles: S1002 and 60E1 definitions (package data),
  measured y-z files;
* :mod:`.contact_geometry` -- contact points of a rigid wheelset on real profiles, EN 15302
  equivalent conicity (``ttbpipe contact-geometry``, docs/contact_geometry.md);
* :mod:`.kernels` -- numba kernels of the contact forces for the whole train;
* :mod:`.dynamics` -- the train's equations of motion for a time loop (rail kinematics in,
  accelerations and wheel forces out);
* :mod:`.static` -- gravity-loaded equilibrium of the train on given rail heights;
* :mod:`.stability` -- the Zhai step limit of the suspension's own modes;
* :mod:`.hunting` -- linear hunting stability on rigid straight track: eigenvalues against speed,
  critical speed, closed forms (Klingel, Wickens);
* :mod:`.comfort` -- Sperling ride index.

The coupled run is :func:`ttbpipe.simulation.coupled.run_coupled`. See docs/vehicle.md.
"""
