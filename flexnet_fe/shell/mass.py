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


def cell_edges(x: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Edge lengths (nc, 4) [m] of quadrilaterals ``cells`` (nc, 4) indexing points ``x`` (n, 3),
    dolfinx vertex order (0,0),(1,0),(0,1),(1,1): edges 0–1, 0–2, 1–3, 2–3."""
    P = x[cells]
    return np.stack([np.linalg.norm(P[:, j] - P[:, i], axis=1)
                     for i, j in ((0, 1), (0, 2), (1, 3), (2, 3))], axis=1).reshape(-1, 4)


def min_edge_length(mesh) -> float:
    """Shortest cell edge of the whole (distributed) quadrilateral mesh [m]."""
    e = cell_edges(mesh.geometry.x, mesh.geometry.dofmap.array.reshape(-1, 4))
    return mesh.comm.allreduce(float(e.min(initial=np.inf)), op=MPI.MIN)


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


def cell_step_lengths(V: fem.FunctionSpace) -> tuple[np.ndarray, np.ndarray]:
    """(cells (nc, 4) local node blocks of V, dolfinx order (0,0),(1,0),(0,1),(1,1); L (nc,) [m])
    of the process's cells: L = area / longest edge, the characteristic length whose L/c_p is the
    element's explicit step estimate (the shell form of explicit codes, e.g. LS-DYNA's default;
    for a square cell L = h, for a thin or kite-shaped one it falls with its shortest height)."""
    cells = V.dofmap.list.array.reshape(-1, 4)
    x = V.tabulate_dof_coordinates()
    P = x[cells]
    area = 0.5 * np.linalg.norm(np.cross(P[:, 3] - P[:, 0], P[:, 2] - P[:, 1]), axis=1)
    return cells, area / cell_edges(x, cells).max(axis=1, initial=0.0)


def selective_mass_scaling(V: fem.FunctionSpace, m: PETSc.Vec, ratio: float) -> dict:
    """Raise the explicit step of the worst-shaped cells by adding mass to their nodes, in place
    on the lumped mass ``m`` (block size 5, ghosted; every DOF of a node scaled alike).

    A cell whose step estimate L/c_p (:func:`cell_step_lengths`) is below ``ratio`` × the
    smallest one has the factor f_e = (ratio L_min / L_e)² (≥ 1); each node takes the largest
    f_e of its cells (over all processes: a ghost update with MAX). This is an upper bound on
    the cell's own frequency: λ_max(M_e⁻¹K_e) ∝ 1/mass, and every node of the cell now carries
    ≥ f_e × its mass, so the element bound of the step rises by ≥ √f_e, i.e. to ``ratio`` ×
    L_min/c_p for every cell. The stage's step still comes from the Lanczos estimate of
    λ_max(M⁻¹K) with this mass: stability does not rest on the estimate. ``ratio`` = 1: nothing
    changes. Explicit codes call this mass scaling to a target step (e.g. LS-DYNA's DT2MS);
    its cost is the added inertia, returned for the summary:

    {"cells": cells scaled (global), "nodes": nodes scaled, "max_factor": largest f,
     "added_mass_rel": added translational mass / fin mass [-]}."""
    if ratio < 1.0:
        raise ValueError(f"mass scaling ratio must be >= 1, got {ratio}")
    comm = V.mesh.comm
    cells, L = cell_step_lengths(V)
    l_min = comm.allreduce(float(L.min(initial=np.inf)), op=MPI.MIN)
    f_cell = np.maximum(1.0, (ratio * l_min / L) ** 2)
    fac = fem.Function(V)
    with fac.vector.localForm() as loc:
        node = np.ones(loc.getSize() // NDOF_NODE)
        np.maximum.at(node, cells.ravel(), np.repeat(f_cell, 4))
        loc.setArray(np.repeat(node, NDOF_NODE))
    fac.vector.ghostUpdate(addv=PETSc.InsertMode.MAX_VALUES, mode=PETSc.ScatterMode.REVERSE)
    fac.vector.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    n_own = V.dofmap.index_map.size_local
    before = mass_totals(m, comm)[0]
    with fac.vector.localForm() as f_loc, m.localForm() as m_loc:
        f = f_loc.getArray(readonly=True)
        m_loc.setArray(m_loc.getArray(readonly=True) * f)
        f_node = f[::NDOF_NODE][:n_own]
    after = mass_totals(m, comm)[0]
    return {"cells": comm.allreduce(int(np.count_nonzero(f_cell > 1.0)), op=MPI.SUM),
            "nodes": comm.allreduce(int(np.count_nonzero(f_node > 1.0)), op=MPI.SUM),
            "max_factor": comm.allreduce(float(f_node.max(initial=1.0)), op=MPI.MAX),
            "added_mass_rel": float(after / before - 1.0)}
