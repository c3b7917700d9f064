"""Lumped (row-sum) mass of the flat shell: translational ρt, rotary ρt³/12 (× scale)."""

from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem.petsc import assemble_vector
from mpi4py import MPI
from petsc4py import PETSc

from flexnet_fe.shell.forms import NDOF_NODE, ShellMaterial


def lumped_mass(V: fem.FunctionSpace, mat: ShellMaterial, rotary_scale: float) -> PETSc.Vec:
    """Row-sum lumped mass diagonal, owned DOFs, block size 5 [kg, kg, kg, kg m², kg m²].

    m_i = ∫ c_i N_i dA with c = (ρt, ρt, ρt, s ρt³/12, s ρt³/12): the row sums of the
    consistent mass ∫ c N_i N_j dA (Σ_j N_j = 1). Bilinear quadrilaterals give positive
    row sums, and the total is exactly ρ t A (translation) and s ρ t³/12 A (rotation).
    ``rotary_scale`` s >= 1 is the rotary-inertia mass scaling of explicit codes (see
    :func:`auto_rotary_scale`); s = 1 is the physical rotary inertia.
    """
    if rotary_scale < 1.0:
        raise ValueError(f"rotary_scale must be >= 1, got {rotary_scale}")
    mesh = V.mesh
    # fem.Constant, not literals: one compiled form serves every mesh, material and scale
    rt = fem.Constant(mesh, PETSc.ScalarType(mat.density * mat.thickness))
    ri = fem.Constant(mesh, PETSc.ScalarType(rotary_scale * mat.density * mat.thickness ** 3 / 12.0))
    c = ufl.as_vector([rt, rt, rt, ri, ri])
    W = ufl.TestFunction(V)
    m = assemble_vector(fem.form(ufl.inner(c, W) * ufl.dx(metadata={"quadrature_degree": 2})))
    m.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    return m


def min_edge_length(mesh) -> float:
    """Shortest cell edge of the whole (distributed) quadrilateral mesh [m]."""
    x = mesh.geometry.x
    cells = mesh.geometry.dofmap.array.reshape(-1, 4)  # dolfinx quad order (0,0),(1,0),(0,1),(1,1)
    h = np.inf
    for i, j in ((0, 1), (0, 2), (1, 3), (2, 3)):
        if len(cells):
            h = min(h, float(np.linalg.norm(x[cells[:, i]] - x[cells[:, j]], axis=1).min()))
    return mesh.comm.allreduce(h, op=MPI.MIN)


def auto_rotary_scale(h: float, mat: ShellMaterial) -> float:
    """Smallest rotary-inertia factor s >= 1 that lowers the shear–rotation frequency of an
    element to its membrane frequency (explicit-code mass scaling; departs from the paper, which
    does not describe its solver).

    Shear–rotation mode of a node: stiffness ≈ κ_s G t A, inertia s ρ t³/12 A, so
    ω_r² ≈ 12 κ_s G / (s ρ t²). Membrane (dilatational) mode of an element of size h:
    ω_m² ≈ 4 E' / (ρ h²) (dt_crit = 2/ω = h/c_p). ω_r = ω_m ⇔ s = 3 κ_s G h² / (E' t²).
    h [m] is the shortest element edge.
    """
    s = 3.0 * mat.shear_correction * mat.shear_modulus * h ** 2 / (
        mat.plane_stress_modulus * mat.thickness ** 2)
    return max(1.0, s)


def mass_totals(m: PETSc.Vec, comm: MPI.Comm) -> np.ndarray:
    """Global sums of the lumped mass per component, shape (5,) [kg ×3, kg m² ×2]."""
    local = m.getArray(readonly=True).reshape(-1, NDOF_NODE).sum(axis=0)
    return comm.allreduce(local, op=MPI.SUM)
