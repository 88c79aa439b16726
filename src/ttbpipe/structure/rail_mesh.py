"""The rails as the structure shows them to a load: kinematics at points, loads at points.

This is the structure's interface to whatever runs on the rails (the coupled vehicle, the moving
loads of the validation cases, the static solve): a :class:`RailMesh` (a small tuple: the rails'
uniform mesh and where their DOFs start) and three kernels,

* :func:`rail_point_kinematics`: (z, dz/dt, y, dy/dt, roll, droll/dt) of a rail's shear centre at
  abscissa x (Hermite cubic for z and y, linear for roll, in the element containing x);
* :func:`rail_head_kinematics`: (z, dz/dt, y, dy/dt) of the rail head, the shear centre moved up
  by the head height h under the roll (y_head = y - h roll), where a wheel touches;
* :func:`add_rail_point_load` / :func:`add_rail_head_load`: the consistent nodal loads of a point
  force (Fz, Fy) and moment Mx, the transposes of the two above (virtual work); a lateral force at
  the head adds the moment -h Fy about the shear centre (:func:`add_rail_contact_load`: and a
  given moment, the vertical force's off the rail's axis).

Callers know nothing of the rail's DOF layout (5 DOF per node: z, dz/dx, y, dy/dx, roll; node 0
of rail r at ``dof0[r]``): that stays here and in the structure's assembly. The tuple is small on
purpose: a numba function receiving the structure's whole packed tuple (about 45 arrays) pays
their reference counting on every call (measured ~0.3 us, 80 calls per coupled step); a
RailMesh holds one array. Outside the rails (or without rails) kinematics are zero and loads
are dropped.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..jit import kernel
from .shape_functions import hermite

#: n_rails (0, 2, or 4 on a double-track deck: track k has rails 2k, 2k + 1), first node x0 (m),
#: spacing dx (m), nodes per rail, first DOF of each rail's node 0 (int64 array of n_rails, at
#: least 2), rail head height above the shear centre (m).
RailMesh = namedtuple("RailMesh", ["n_rails", "x0", "dx", "n_nodes", "dof0", "head_height"])

#: DOFs per rail node and the offsets of its lateral displacement and roll.
NODE_DOFS, Y_OFFSET, ROLL_OFFSET = 5, 2, 4


def rail_mesh(packed, head_height: float) -> RailMesh:
    """The RailMesh of a packed structure (``StructureModel.packed``)."""
    return RailMesh(int(packed.n_rails), float(packed.rail_x0), float(packed.rail_dx),
                    int(packed.rail_n_nodes) if int(packed.n_rails) else 0,
                    np.asarray(packed.rail_dof0, dtype=np.int64), float(head_height))


def no_rails(head_height: float) -> RailMesh:
    """Rails fixed in space (``track: rigid``): no DOF, zero kinematics, loads dropped."""
    return RailMesh(0, 0.0, 1.0, 0, np.zeros(2, dtype=np.int64), float(head_height))


def rail_node_dofs(mesh: RailMesh, rail: int) -> np.ndarray:
    """First DOF (vertical displacement) of every node of rail ``rail``; the node's lateral
    displacement and roll are at +:data:`Y_OFFSET` and +:data:`ROLL_OFFSET`."""
    return int(mesh.dof0[rail]) + NODE_DOFS * np.arange(int(mesh.n_nodes))


def rail_inverse_masses(mesh: RailMesh, inv_mass: np.ndarray) -> tuple[float, float]:
    """Largest inverse mass of a rail node vertically and of the rail head laterally
    (1/m_y + h^2/I_roll), from the structure's lumped inverse masses (0, 0 without rails)."""
    inv = np.asarray(inv_mass)
    z_max, y_max = 0.0, 0.0
    for r in range(int(mesh.n_rails)):
        base = rail_node_dofs(mesh, r)
        z_max = max(z_max, float(inv[base].max()))
        y_max = max(y_max, float((inv[base + Y_OFFSET]
                                  + mesh.head_height ** 2 * inv[base + ROLL_OFFSET]).max()))
    return z_max, y_max


@kernel(inline="always")
def _locate(mesh, x):
    """Element index and local coordinate xi in [0, 1] of abscissa x; (-1, 0) outside."""
    n_el = mesh.n_nodes - 1
    if mesh.n_rails == 0 or n_el < 1:
        return -1, 0.0
    s = (x - mesh.x0) / mesh.dx
    if s < 0.0 or s > n_el:
        return -1, 0.0
    e = int(s)
    if e >= n_el:
        e = n_el - 1
    return e, s - e


@kernel(inline="always")
def rail_point_kinematics(mesh, rail, x, disp, vel):
    """(z, dz/dt, y, dy/dt, roll, droll/dt) of rail ``rail``'s shear centre at x (zeros outside)."""
    e, xi = _locate(mesh, x)
    if e < 0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    a = mesh.dof0[rail] + 5 * e
    b = a + 5
    n1, n2, n3, n4 = hermite(xi, mesh.dx)
    z = n1 * disp[a] + n2 * disp[a + 1] + n3 * disp[b] + n4 * disp[b + 1]
    vz = n1 * vel[a] + n2 * vel[a + 1] + n3 * vel[b] + n4 * vel[b + 1]
    y = n1 * disp[a + 2] + n2 * disp[a + 3] + n3 * disp[b + 2] + n4 * disp[b + 3]
    vy = n1 * vel[a + 2] + n2 * vel[a + 3] + n3 * vel[b + 2] + n4 * vel[b + 3]
    r = (1.0 - xi) * disp[a + 4] + xi * disp[b + 4]
    vr = (1.0 - xi) * vel[a + 4] + xi * vel[b + 4]
    return z, vz, y, vy, r, vr


@kernel(inline="always")
def rail_head_kinematics(mesh, rail, x, disp, vel):
    """(z, dz/dt, y, dy/dt) of rail ``rail``'s head at x: the shear centre's, the lateral ones
    moved up by the head height under the roll (y - h roll)."""
    z, vz, y, vy, r, vr = rail_point_kinematics(mesh, rail, x, disp, vel)
    h = mesh.head_height
    return z, vz, y - h * r, vy - h * vr


@kernel(inline="always")
def add_rail_point_load(mesh, rail, x, fz, fy, mx, nodal_force):
    """Add the consistent nodal loads of (Fz, Fy, Mx) at x on rail ``rail``'s shear centre
    (transpose of :func:`rail_point_kinematics`); nothing outside the rails."""
    e, xi = _locate(mesh, x)
    if e < 0:
        return
    a = mesh.dof0[rail] + 5 * e
    b = a + 5
    n1, n2, n3, n4 = hermite(xi, mesh.dx)
    nodal_force[a] += n1 * fz
    nodal_force[a + 1] += n2 * fz
    nodal_force[b] += n3 * fz
    nodal_force[b + 1] += n4 * fz
    nodal_force[a + 2] += n1 * fy
    nodal_force[a + 3] += n2 * fy
    nodal_force[b + 2] += n3 * fy
    nodal_force[b + 3] += n4 * fy
    nodal_force[a + 4] += (1.0 - xi) * mx
    nodal_force[b + 4] += xi * mx


@kernel(inline="always")
def add_rail_contact_load(mesh, rail, x, fz, fy, mx, nodal_force):
    """:func:`add_rail_head_load` plus a moment ``mx`` about the shear centre (e.g. of a vertical
    force acting off the rail's axis, F_z l_h: seed paper eq. 31)."""
    add_rail_point_load(mesh, rail, x, fz, fy, -mesh.head_height * fy + mx, nodal_force)


@kernel(inline="always")
def add_rail_head_load(mesh, rail, x, fz, fy, nodal_force):
    """Add (Fz, Fy) acting on rail ``rail``'s head at x: the lateral force's lever h about the
    shear centre gives the moment -h Fy (transpose of :func:`rail_head_kinematics`)."""
    add_rail_point_load(mesh, rail, x, fz, fy, -mesh.head_height * fy, nodal_force)
