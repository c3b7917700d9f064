"""Fin meshes: load a Gmsh ``.msh`` fin, build rectangular test plates, find the fin's plane.

A fin is a flat, all-quadrilateral surface mesh placed in 3-D (gdim = 3) in the missile body
frame B, with physical groups ``surface`` (2-D) and ``root``, ``leading_edge``, ``tip``,
``trailing_edge`` (1-D).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from mpi4py import MPI

import gmsh
from dolfinx.io import gmshio

from flexnet_fe.msh import gmsh_model  # one gmsh session per process, shared

EDGE_GROUPS = ("root", "leading_edge", "tip", "trailing_edge")


@dataclass(frozen=True)
class FinPlane:
    """Orthonormal in-plane axes e1, e2 and normal n = e1 × e2 of a flat fin, shape (3,) each.

    Convention: n is the unit normal of the mesh plane with its largest-magnitude component
    positive; e1 is the body axis +x_b projected on the plane (fins contain the missile axis
    direction), or the plane's first principal direction if +x_b is normal to it; e2 = n × e1.
    The "top" surface of the shell is its +n side.
    """

    e1: np.ndarray
    e2: np.ndarray
    n: np.ndarray
    origin: np.ndarray
    """a point of the plane [m], shape (3,)"""


@dataclass(frozen=True)
class FinMesh:
    mesh: object
    """dolfinx Mesh (tdim 2, gdim 3)"""
    facet_tags: object
    """dolfinx MeshTags of the edge groups"""
    edge_tags: dict
    """physical group name → tag value"""
    plane: FinPlane


def plane_of_points(x: np.ndarray, *, flatness_tol: float = 1e-8) -> FinPlane:
    """Fit the plane of node coordinates ``x [m], shape (n, 3)`` and check the fin is flat."""
    c = x.mean(axis=0)
    _, s, vt = np.linalg.svd(x - c, full_matrices=False)
    n = vt[2] / np.linalg.norm(vt[2])
    if s[2] > flatness_tol * max(s[0], 1e-300) * np.sqrt(len(x)):
        raise ValueError(f"fin mesh is not flat (out-of-plane singular value {s[2]:.3e})")
    if n[np.argmax(np.abs(n))] < 0:
        n = -n
    xb = np.array([1.0, 0.0, 0.0])
    e1 = xb - np.dot(xb, n) * n
    if np.linalg.norm(e1) < 1e-6:
        e1 = vt[0]
    e1 = e1 / np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    return FinPlane(e1=e1, e2=e2, n=n, origin=c)


def _model_to_fin(comm: MPI.Comm) -> FinMesh:
    """Convert the current gmsh model (on rank 0) to a distributed :class:`FinMesh`."""
    if comm.rank == 0:
        names = {gmsh.model.getPhysicalName(d, t): (d, t) for d, t in gmsh.model.getPhysicalGroups()}
        missing = [g for g in ("surface",) if g not in names]
        if missing:
            raise ValueError(f"fin mesh lacks physical group(s) {missing}")
        tags = {k: v[1] for k, v in names.items() if v[0] == 1}
        _, xyz, _ = gmsh.model.mesh.getNodes()
        plane = plane_of_points(xyz.reshape(-1, 3))
        etypes = gmsh.model.mesh.getElementTypes(2)
        if any(gmsh.model.mesh.getElementProperties(et)[0].split()[0] != "Quadrilateral"
               for et in etypes):
            raise ValueError("fin mesh must be all quadrilaterals")
    else:
        tags, plane = None, None
    tags, plane = comm.bcast((tags, plane), root=0)
    mesh, _, ftags = gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=3)
    return FinMesh(mesh=mesh, facet_tags=ftags, edge_tags=tags, plane=plane)


def load_fin_mesh(path: Path, comm: MPI.Comm = MPI.COMM_WORLD) -> FinMesh:
    """Read a fin ``.msh`` file (Gmsh, all quads, gdim = 3) on rank 0 and distribute it."""
    with gmsh_model("fin"):
        if comm.rank == 0:
            gmsh.merge(str(path))
        return _model_to_fin(comm)


def _add_plate(nx: int, ny: int, lx: float, ly: float, o, a1, a2) -> None:
    """Add a structured quadrilateral plate with its physical groups to the gmsh model."""
    geo = gmsh.model.geo
    pts = [geo.addPoint(*(o + s1 * a1 + s2 * a2)) for s1, s2 in ((0, 0), (lx, 0), (lx, ly), (0, ly))]
    lines = [geo.addLine(pts[i], pts[(i + 1) % 4]) for i in range(4)]
    surf = geo.addPlaneSurface([geo.addCurveLoop(lines)])
    geo.synchronize()
    for ln, n in zip(lines, (nx, ny, nx, ny)):
        gmsh.model.mesh.setTransfiniteCurve(ln, n + 1)
    gmsh.model.mesh.setTransfiniteSurface(surf)
    gmsh.model.mesh.setRecombine(2, surf)
    for name, ln in zip(("trailing_edge", "tip", "leading_edge", "root"), lines):
        gmsh.model.setPhysicalName(1, gmsh.model.addPhysicalGroup(1, [ln]), name)
    gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, [surf]), "surface")
    gmsh.model.mesh.generate(2)


def plate_mesh(nx: int, ny: int, lx: float, ly: float, *, origin=(0.0, 0.0, 0.0),
               a1=(1.0, 0.0, 0.0), a2=(0.0, 1.0, 0.0), comm: MPI.Comm = MPI.COMM_WORLD) -> FinMesh:
    """Structured nx × ny quadrilateral plate of size lx × ly [m] in the plane spanned by the
    orthonormal vectors a1, a2 through ``origin`` (gdim = 3), for verification and benchmarks.

    Edge groups: ``root`` (s1 = 0), ``tip`` (s1 = lx), ``leading_edge`` (s2 = ly),
    ``trailing_edge`` (s2 = 0), where s1, s2 are the coordinates along a1, a2.
    """
    o, a1, a2 = (np.asarray(v, dtype=float) for v in (origin, a1, a2))
    with gmsh_model("plate"):
        if comm.rank == 0:
            _add_plate(nx, ny, lx, ly, o, a1, a2)
        return _model_to_fin(comm)


def write_plate_msh(path: Path, nx: int, ny: int, lx: float, ly: float, *,
                    origin=(0.0, 0.0, 0.0), a1=(1.0, 0.0, 0.0), a2=(0.0, 1.0, 0.0)) -> Path:
    """Write the :func:`plate_mesh` plate as a Gmsh ``.msh`` file (serial; tests, benchmarks)."""
    o, a1, a2 = (np.asarray(v, dtype=float) for v in (origin, a1, a2))
    with gmsh_model("plate"):
        _add_plate(nx, ny, lx, ly, o, a1, a2)
        gmsh.write(str(path))
    return Path(path)
