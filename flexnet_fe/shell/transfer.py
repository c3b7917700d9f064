"""Contact loads → consistent nodal forces on a fin's shell mesh (the shell stage's load transfer).

A rope of diameter ``width`` pressing on a fin loads an area of that size, not a point. Each
contact force F acting at point p is spread uniformly over a stencil of radius w/2 around p in
the fin plane, and each stencil point x_q (weight ω_q, Σ ω_q = 1) gives consistent nodal forces
f_i = ω_q N_i(x_q) F (N_i the bilinear shape functions). Because Σ_i N_i = 1 and
Σ_i N_i x_i = x (isoparametric), the total force is F and the total moment about any point is
(Σ_q ω_q x_q) × F = p × F exactly whenever the stencil's centroid is p (all stencils below are
symmetric about p). Spreading over the rope width keeps the peak stress finite as the mesh is
refined (a true point force gives a logarithmically unbounded bending stress).

Stencil choice (departure from the paper, which does not describe its load transfer):
1. a disk of radius w/2 (equal-area rings, points ≤ ~h/2 apart: :func:`stencil_resolution`,
   h the median shortest edge of the cells the contact points lie in, :func:`_load_cell_size`)
   when all its points lie on the fin;
2. else (contact at or near an edge) a segment of length w through p parallel to the nearest fin
   edge (Gauss points ≤ ~h/2 apart) — a rope across an edge touches it over about its width;
3. else (a corner) that segment halved until it fits; a point load at p as the last resort.
The component of p normal to the plane is dropped (mid-surface loading). A point outside the
planform by at most ``plane_tol`` (a rope on the edge face, round-off) is moved to the nearest
edge point (moment change ≤ plane_tol·|F|); farther from the plane or the fin is an error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from dolfinx import geometry
from dolfinx.mesh import exterior_facet_indices
from mpi4py import MPI
from numba import njit
from scipy import sparse

from flexnet_fe.shell.forms import NDOF_NODE  # (u_x, u_y, u_z, θ_1, θ_2); forces load the first 3
from flexnet_fe.shell.mass import cell_edges, min_edge_length
from flexnet_fe.shell.recovery import shape_q1


def disk_stencil(n_rings: int, n_phi: int) -> np.ndarray:
    """Unit-disk stencil: n_rings equal-area rings × n_phi points, equal weights, centroid 0
    (n_phi a multiple of 8: symmetric), shape (n_rings·n_phi, 2)."""
    rr = np.sqrt((np.arange(n_rings) + 0.5) / n_rings)
    phi = 2.0 * np.pi * (np.arange(n_phi) + 0.5) / n_phi
    return np.concatenate([np.column_stack([r * np.cos(phi), r * np.sin(phi)]) for r in rr])


def stencil_resolution(radius: float, h: float) -> tuple[int, int, int]:
    """(rings, points per ring, line points) so that stencil points are at most ~h/2 apart
    (at least 3 × 8 and 6): finer than the mesh, a stencil acts as the distributed load it
    stands for; coarser (a fixed 24 points), it would act as a cluster of point loads once the
    mesh is refined below the rope width, and the peak would diverge again."""
    rings = max(3, math.ceil(2.0 * radius / h))
    phi = 8 * max(1, math.ceil(math.pi * radius / (2.0 * h)))
    line = max(6, math.ceil(4.0 * radius / h))
    return rings, phi, line


@dataclass(frozen=True)
class FinGeometry:
    """What the transfer needs from a fin's shell model."""

    mesh: object
    """dolfinx Mesh (quadrilaterals, gdim 3)"""
    V: object
    """shell function space, block size 5"""
    origin: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    n: np.ndarray


@njit(cache=True, inline="always")
def _pull_back(xc, y0, y1, iters=12):
    """Reference coordinates (ξ, η) of the 2-D point (y0, y1) in the bilinear cell with 2-D vertex
    coordinates ``xc`` (4, 2), by Newton's method from the centre.

    x(ξ, η) = x0 + ξ a + η b + ξ η c (a = x1 − x0, b = x2 − x0, c = x0 − x1 − x2 + x3: the
    dolfinx vertex order of ``shape_q1``); each step solves the 2 × 2 system J ΔX = r in closed
    form (Cramer)."""
    a0, a1 = xc[1, 0] - xc[0, 0], xc[1, 1] - xc[0, 1]
    b0, b1 = xc[2, 0] - xc[0, 0], xc[2, 1] - xc[0, 1]
    c0 = xc[0, 0] - xc[1, 0] - xc[2, 0] + xc[3, 0]
    c1 = xc[0, 1] - xc[1, 1] - xc[2, 1] + xc[3, 1]
    xi, eta = 0.5, 0.5
    for _ in range(iters):
        r0 = xc[0, 0] + xi * a0 + eta * b0 + xi * eta * c0 - y0
        r1 = xc[0, 1] + xi * a1 + eta * b1 + xi * eta * c1 - y1
        jx0, jx1 = a0 + eta * c0, a1 + eta * c1  # ∂x/∂ξ
        je0, je1 = b0 + xi * c0, b1 + xi * c1  # ∂x/∂η
        det = jx0 * je1 - je0 * jx1
        xi, eta = xi - (je1 * r0 - je0 * r1) / det, eta - (jx0 * r1 - jx1 * r0) / det
    return xi, eta


@njit(cache=True)
def _first_containing(offsets, cand, xg, cg, frame, pts3, tol):
    """For each point of ``pts3`` (m, 3) [m]: the first of its candidate cells (``cand[offsets[p]:
    offsets[p + 1]]``, from the bounding-box tree) whose bilinear map contains it within ``tol``
    in reference coordinates, and its reference coordinates clipped to [0, 1]. Cells: vertex
    geometry nodes ``cg`` (nc, 4), coordinates ``xg`` (ng, 3), in the fin plane: ``frame`` (3, 3)
    rows origin [m], e1, e2.
    Returns (cell (m,) int32, −1 where none; X (m, 2)). Compiled: the rotary net's fins have
    ~1e7 candidates, whose numpy gathers and temporaries took a minute."""
    origin, e1, e2 = frame[0], frame[1], frame[2]
    m = pts3.shape[0]
    cell = np.full(m, -1, np.int32)
    X = np.zeros((m, 2))
    xc = np.empty((4, 2))
    for p in range(m):
        q0, q1, q2 = pts3[p, 0] - origin[0], pts3[p, 1] - origin[1], pts3[p, 2] - origin[2]
        y0 = q0 * e1[0] + q1 * e1[1] + q2 * e1[2]
        y1 = q0 * e2[0] + q1 * e2[1] + q2 * e2[2]
        for k in range(offsets[p], offsets[p + 1]):
            c = cand[k]
            for v in range(4):
                g = cg[c, v]
                r0, r1, r2 = xg[g, 0] - origin[0], xg[g, 1] - origin[1], xg[g, 2] - origin[2]
                xc[v, 0] = r0 * e1[0] + r1 * e1[1] + r2 * e1[2]
                xc[v, 1] = r0 * e2[0] + r1 * e2[1] + r2 * e2[2]
            xi, eta = _pull_back(xc, y0, y1)
            if -tol <= xi <= 1.0 + tol and -tol <= eta <= 1.0 + tol:
                cell[p] = c
                X[p, 0] = min(max(xi, 0.0), 1.0)
                X[p, 1] = min(max(eta, 0.0), 1.0)
                break
    return cell, X


def _locate(fg: FinGeometry, pts3: np.ndarray, tol: float = 1e-9):
    """Owned cell and reference coordinates of in-plane points ``pts3`` (m, 3).

    Returns (cell, X, mine, found): cell index (−1 where this rank does not claim the point),
    reference coordinates (m, 2), whether this rank claims the point, and whether any rank found
    it. Each point is claimed by exactly one rank (the lowest owning a containing cell)."""
    mesh = fg.mesh
    comm = mesh.comm
    n_owned = mesh.topology.index_map(2).size_local
    tree = geometry.BoundingBoxTree(mesh, 2, np.arange(n_owned, dtype=np.int32), padding=1e-9)
    cand = geometry.compute_collisions(tree, np.ascontiguousarray(pts3, dtype=np.float64))
    cg = np.ascontiguousarray(mesh.geometry.dofmap.array.reshape(-1, 4))
    cell, X = _first_containing(np.asarray(cand.offsets, dtype=np.int64), np.asarray(cand.array, dtype=np.int64),
                                np.ascontiguousarray(mesh.geometry.x), cg,
                                np.array([fg.origin, fg.e1, fg.e2], dtype=np.float64),
                                np.ascontiguousarray(pts3, dtype=np.float64), tol)
    here = cell >= 0
    rank_claim = np.where(here, comm.rank, comm.size)
    owner = np.empty_like(rank_claim)
    comm.Allreduce(rank_claim, owner, op=MPI.MIN)
    mine = here & (owner == comm.rank)
    cell[~mine] = -1
    return cell, X, mine, owner < comm.size


def _boundary_segments(fg: FinGeometry) -> np.ndarray:
    """All boundary edges of the fin as 2-D segments in (e1, e2), shape (nb, 2, 2), same on
    every rank."""
    mesh = fg.mesh
    mesh.topology.create_connectivity(1, 2)
    mesh.topology.create_connectivity(1, 0)
    facets = exterior_facet_indices(mesh.topology)
    facets = facets[facets < mesh.topology.index_map(1).size_local]
    f2v = mesh.topology.connectivity(1, 0)
    vx = mesh.geometry.x
    # vertex → geometry node (P1 geometry: via the cell maps)
    c2v = mesh.topology.connectivity(2, 0).array.reshape(-1, 4)
    cg = mesh.geometry.dofmap.array.reshape(-1, 4)
    v2g = np.empty(c2v.max() + 1 if len(c2v) else 0, dtype=np.int64)
    v2g[c2v.ravel()] = cg.ravel()
    segs = np.array([[vx[v2g[v]] for v in f2v.links(f)] for f in facets]).reshape(-1, 2, 3)
    segs = np.concatenate(mesh.comm.allgather(segs))
    rel = segs - fg.origin
    return np.stack([rel @ fg.e1, rel @ fg.e2], axis=2)


def _nearest_on_boundary(segs: np.ndarray, y2: np.ndarray):
    """For each 2-D point of y2 (m, 2): the nearest point on the fin boundary (m, 2), its
    distance (m,) [m] and the unit direction of that boundary segment (m, 2) (the first nearest
    segment on a tie). Compiled: the edge contacts of finely sampled fin loads are ~1e5 points
    against ~1e3 boundary segments (numpy broadcasting took 90 s per fin at 0.156 µs)."""
    y2 = np.ascontiguousarray(y2, dtype=np.float64).reshape(-1, 2)
    near, dist, tdir = np.zeros((len(y2), 2)), np.zeros(len(y2)), np.zeros((len(y2), 2))
    _nearest_kernel(np.ascontiguousarray(segs, dtype=np.float64), y2, near, dist, tdir)
    return near, dist, tdir


@njit(cache=True)
def _nearest_kernel(segs, y2, near, dist, tdir):
    for i in range(y2.shape[0]):
        best, bq0, bq1, bk = np.inf, 0.0, 0.0, 0
        for k in range(segs.shape[0]):
            a0, a1 = segs[k, 0, 0], segs[k, 0, 1]
            d0, d1 = segs[k, 1, 0] - a0, segs[k, 1, 1] - a1
            L2 = max(d0 * d0 + d1 * d1, 1e-300)
            s = min(max(((y2[i, 0] - a0) * d0 + (y2[i, 1] - a1) * d1) / L2, 0.0), 1.0)
            q0, q1 = a0 + s * d0, a1 + s * d1
            d2 = (q0 - y2[i, 0]) ** 2 + (q1 - y2[i, 1]) ** 2
            if d2 < best:
                best, bq0, bq1, bk = d2, q0, q1, k
        near[i, 0], near[i, 1] = bq0, bq1
        dist[i] = np.sqrt(best)
        d0, d1 = segs[bk, 1, 0] - segs[bk, 0, 0], segs[bk, 1, 1] - segs[bk, 0, 1]
        L = np.sqrt(max(d0 * d0 + d1 * d1, 1e-300))
        tdir[i, 0], tdir[i, 1] = d0 / L, d1 / L


def contact_transfer(fg: FinGeometry, points: np.ndarray, widths: np.ndarray, *,
                     plane_tol: float) -> sparse.csr_matrix:
    """Transfer matrix G, shape (n_owned·5, 3·ne): nodal forces of the owned DOFs = G @ F with
    F = forces.ravel() (ne × 3, body frame B [N]) for contact points ``points`` [m] (ne, 3) in B
    and rope widths ``widths`` [m] (ne,). Rotational DOFs get no load (forces act on the
    mid-surface). Raises ValueError for a point off the fin plane or outside the fin."""
    comm = fg.mesh.comm
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    widths = np.asarray(widths, dtype=float).ravel()
    ne = len(points)
    rel = points - fg.origin
    off = rel @ fg.n
    bad = np.flatnonzero(np.abs(off) > plane_tol)
    if len(bad):
        raise ValueError(f"contact event {bad[0]} at {points[bad[0]]} m is {off[bad[0]]:.3e} m off "
                         f"the fin plane (tolerance {plane_tol:.3e} m)")
    p2 = np.column_stack([rel @ fg.e1, rel @ fg.e2])
    plane = np.vstack([fg.e1, fg.e2])  # (2, 3)
    to3 = lambda y2: y2 @ plane + fg.origin  # noqa: E731  (one pass: ~1e7 stencil points on a rotary fin)
    r = 0.5 * widths
    segs = _boundary_segments(fg)

    _snap_to_planform(fg, segs, p2, points, plane_tol)

    # 1. disk stencils, spaced by the cells the loads land in (not the fin's smallest edge)
    h = _load_cell_size(fg, to3(p2))
    n_rings, n_phi, n_line = stencil_resolution(float(r.max(initial=0.0)), h)
    DISK = disk_stencil(n_rings, n_phi)
    GL = np.polynomial.legendre.leggauss(n_line)
    LINE = GL[0]
    nd = len(DISK)
    pts = (p2[:, None, :] + r[:, None, None] * DISK[None]).reshape(-1, 2)
    cell, X, mine, found = _locate(fg, to3(pts))
    ok_disk = found.reshape(ne, nd).all(axis=1)
    ev_idx = [np.repeat(np.arange(ne), nd)]
    wts = [np.full(ne * nd, 1.0 / nd)]
    keep = [np.repeat(ok_disk, nd) & mine]
    cells, Xs = [cell], [X]
    todo = np.flatnonzero(~ok_disk)
    if len(todo):
        tdir = _nearest_on_boundary(segs, p2[todo])[2]
        half = r[todo].copy()
        nl = len(LINE)
        for _ in range(12):
            if not len(todo):
                break
            pts = (p2[todo, None, :] + (half[:, None] * LINE[None])[..., None] * tdir[:, None, :])
            c, Xl, mi, fo = _locate(fg, to3(pts.reshape(-1, 2)))
            ok = fo.reshape(-1, nl).all(axis=1)
            ev_idx.append(np.repeat(todo, nl))
            wts.append(np.tile(GL[1] / 2.0, len(todo)))
            keep.append(np.repeat(ok, nl) & mi)
            cells.append(c)
            Xs.append(Xl)
            todo, tdir, half = todo[~ok], tdir[~ok], 0.5 * half[~ok]
        if len(todo):  # last resort: point load at p
            c, Xp, mi, fo = _locate(fg, to3(p2[todo]))
            if not fo.all():
                k = todo[np.flatnonzero(~fo)[0]]
                raise ValueError(f"contact event {k} at {points[k]} m lies outside the fin")
            ev_idx.append(todo)
            wts.append(np.ones(len(todo)))
            keep.append(mi)
            cells.append(c)
            Xs.append(Xp)
    kp = np.concatenate(keep)
    G = _assemble(fg, np.concatenate(ev_idx)[kp], np.concatenate(wts)[kp], np.concatenate(cells)[kp],
                  np.concatenate(Xs)[kp], ne)
    return _owned_rows(fg.V, G, comm)


def _load_cell_size(fg: FinGeometry, centres3: np.ndarray) -> float:
    """Median over the contact points ``centres3`` (ne, 3) [m] of the shortest edge of the cell
    each lies in [m] (all ranks; the fin's shortest edge when there is no point): the size
    :func:`stencil_resolution` lays the stencils by. Not the fin's shortest edge: a few
    kite-shaped cells (docs/validation.md, "Fin mesh quality") halve it and made every stencil
    ~8× denser than the cells under the loads need (rotary wing_4: ~1e7 points to locate;
    docs/performance.md, "Shell set-up: stencils by the loaded cells")."""
    cell, _, mine, _ = _locate(fg, centres3)
    cg = fg.mesh.geometry.dofmap.array.reshape(-1, 4)
    edges = cell_edges(fg.mesh.geometry.x, cg[cell[mine]])
    sizes = np.concatenate(fg.mesh.comm.allgather(edges.min(axis=1, initial=np.inf)))
    sizes = sizes[np.isfinite(sizes)]
    return float(np.median(sizes)) if len(sizes) else min_edge_length(fg.mesh)


def _snap_to_planform(fg: FinGeometry, segs, p2: np.ndarray, points: np.ndarray, plane_tol: float) -> None:
    """Contact points just outside the planform (a rope on the rounded/blunt edge, round-off)
    are moved in place in ``p2`` (ne, 2) [m] to the nearest boundary point when within
    ``plane_tol`` [m]; farther is a ValueError naming the event."""
    _, _, _, inside = _locate(fg, fg.origin + p2[:, :1] * fg.e1 + p2[:, 1:2] * fg.e2)
    out = np.flatnonzero(~inside)
    if len(out):
        near, dist, _ = _nearest_on_boundary(segs, p2[out])
        far = out[dist > plane_tol]
        if len(far):
            k = far[0]
            raise ValueError(f"contact event {k} at {points[k]} m lies outside the fin "
                             f"(more than {plane_tol:.3e} m from its edge)")
        p2[out] = near


def _assemble(fg: FinGeometry, ev: np.ndarray, w: np.ndarray, cl: np.ndarray, Xa: np.ndarray,
              ne: int) -> sparse.csr_matrix:
    """G (local rows incl. ghosts, 3·ne) from quadrature points: event ``ev`` (q,), weight ``w``
    (q,), cell ``cl`` (q,) and reference coordinates ``Xa`` (q, 2) — Q1 shape functions times
    the weight on the three translational DOFs of the cell's four nodes."""
    N = shape_q1(Xa[:, 0], Xa[:, 1])  # (m, 4)
    V = fg.V
    dm = V.dofmap.list.array.reshape(-1, 4)
    blocks = dm[cl]  # (m, 4) local node blocks, basix P1 order = vertex order
    rows = (blocks[:, :, None] * NDOF_NODE + np.arange(3)[None, None, :])  # (m, 4, 3)
    cols = (ev[:, None, None] * 3 + np.arange(3)[None, None, :]).repeat(4, axis=1)
    vals = (w[:, None] * N)[:, :, None].repeat(3, axis=2)
    n_loc = (V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts) * NDOF_NODE
    return sparse.csr_matrix((vals.ravel(), (rows.ravel(), cols.ravel())), shape=(n_loc, 3 * ne))


def _owned_rows(V, G: sparse.csr_matrix, comm) -> sparse.csr_matrix:
    """Add the ghost rows of the local matrix ``G`` into their owners' rows; return the owned
    rows, shape (n_owned·5, ncols)."""
    imap = V.dofmap.index_map
    n_own = imap.size_local * NDOF_NODE
    G = G.tocsr()
    own = G[:n_own]
    if comm.size == 1:
        return own
    ghost = G[n_own:].tocoo()
    gblocks = imap.local_to_global(np.arange(imap.size_local, imap.size_local + imap.num_ghosts,
                                             dtype=np.int32))
    grow = gblocks[ghost.row // NDOF_NODE] * NDOF_NODE + ghost.row % NDOF_NODE  # global DOF
    starts = np.array(comm.allgather(imap.local_range[0] * NDOF_NODE))
    dest = np.searchsorted(starts, grow, side="right") - 1
    send = [(grow[dest == r] - starts[r], ghost.col[dest == r], ghost.data[dest == r])
            for r in range(comm.size)]
    recv = comm.alltoall(send)
    rr = np.concatenate([x[0] for x in recv]).astype(np.int64)
    cc = np.concatenate([x[1] for x in recv]).astype(np.int64)
    vv = np.concatenate([x[2] for x in recv])
    return (own + sparse.csr_matrix((vv, (rr, cc)), shape=own.shape)).tocsr()


def locate_in_cells(fg: FinGeometry, points: np.ndarray, weights: np.ndarray,
                    direction: np.ndarray) -> np.ndarray:
    """Consistent nodal forces of the owned DOFs (n_owned·5,) [N] of point forces
    ``weights[q] · direction`` [N] at in-plane points ``points`` (m, 3) [m]: f_i = Σ_q w_q N_i(x_q)
    (a quadrature of a distributed load). Raises ValueError for a point outside the fin."""
    cell, X, mine, found = _locate(fg, np.asarray(points, dtype=float))
    if not found.all():
        k = int(np.flatnonzero(~found)[0])
        raise ValueError(f"load point {points[k]} m lies outside the fin")
    cl, Xa, w = cell[mine], X[mine], np.asarray(weights, dtype=float)[mine]
    N = shape_q1(Xa[:, 0], Xa[:, 1])
    V = fg.V
    blocks = V.dofmap.list.array.reshape(-1, 4)[cl]
    rows = (blocks[:, :, None] * NDOF_NODE + np.arange(3)[None, None, :]).ravel()
    vals = ((w[:, None] * N)[:, :, None] * np.asarray(direction, float)[None, None, :]).ravel()
    n_loc = (V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts) * NDOF_NODE
    G = sparse.csr_matrix((vals, (rows, np.zeros_like(rows))), shape=(n_loc, 1))
    return np.asarray(_owned_rows(V, G, fg.mesh.comm).todense()).ravel()
