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
from typing import NamedTuple

import numpy as np
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
    form (Cramer); at most ``iters`` steps, ending once a step moves (ξ, η) by less than 1e-14
    (2–4 steps in the fins' cells; a point outside the cell may take all of them)."""
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
        d_xi, d_eta = (je1 * r0 - je0 * r1) / det, (jx0 * r1 - jx1 * r0) / det
        xi, eta = xi - d_xi, eta - d_eta
        if abs(d_xi) + abs(d_eta) < 1e-14:  # converged (quadratically: the next step is round-off)
            break
    return xi, eta


class Buckets(NamedTuple):
    """Boxes bucketed on a uniform 2-D grid: corner lo (2,) [m], bucket edge size [m], buckets
    per axis shape (2,); start (nb + 1,) and items (k,): the boxes overlapping each bucket (CSR,
    ascending; bucket index ix · shape[1] + iy)."""

    lo: np.ndarray
    size: float
    shape: np.ndarray
    start: np.ndarray
    items: np.ndarray


def buckets(box: np.ndarray, size: float) -> Buckets:
    """:class:`Buckets` of the boxes ``box`` (k, 4) [m] (min x, min y, max x, max y): the bucket
    edge ``size`` [m], enlarged until there are at most 4 buckets per box."""
    lo, hi = box[:, :2].min(axis=0), box[:, 2:].max(axis=0)
    extent = np.maximum(hi - lo, 1e-12)
    size = max(float(size), math.sqrt(extent[0] * extent[1] / (4.0 * len(box))), 1e-12)
    shape = np.maximum(np.ceil(extent / size).astype(np.int64), 1)
    start, items = _bucket_items(np.ascontiguousarray(box, dtype=np.float64), lo, size, shape)
    return Buckets(lo, size, shape, start, items)


class CellGrid(NamedTuple):
    """This rank's owned cells of a planar fin mesh, bucketed in the fin plane (e1, e2) — the
    point location of the load transfer, built once per transfer (linear in the cells). xy (ng, 2)
    [m] the geometry nodes in the plane; cg (nc, 4) the cells' vertex geometry nodes; box (nc, 4)
    [m] each cell's (min e1, min e2, max e1, max e2), padded by :data:`PAD`; grid the cells'
    :class:`Buckets` (bucket edge: the median cell size)."""

    xy: np.ndarray
    cg: np.ndarray
    box: np.ndarray
    grid: Buckets


PAD = 1e-9
"""Padding of the cells' boxes [m] (the bounding-box tree's, before): a point on a cell's edge is
a candidate of both cells that share it."""


def cell_grid(fg: FinGeometry) -> CellGrid:
    """The :class:`CellGrid` of this rank's owned cells (a locally refined fin: a few large cells
    span many small buckets, the buckets stay ~1–4 cells deep)."""
    mesh = fg.mesh
    n_owned = mesh.topology.index_map(2).size_local
    cg = np.ascontiguousarray(mesh.geometry.dofmap.array.reshape(-1, 4)[:n_owned], dtype=np.int64)
    rel = mesh.geometry.x - fg.origin
    xy = np.ascontiguousarray(np.column_stack([rel @ fg.e1, rel @ fg.e2]))
    corners = xy[cg]  # (nc, 4, 2)
    box = np.ascontiguousarray(np.concatenate([corners.min(axis=1) - PAD, corners.max(axis=1) + PAD], axis=1))
    if not n_owned:
        return CellGrid(xy, cg, box.reshape(0, 4), Buckets(np.zeros(2), 1.0, np.ones(2, np.int64),
                                                           np.zeros(2, np.int64), np.zeros(0, np.int64)))
    return CellGrid(xy, cg, box, buckets(box, float(np.median(np.max(box[:, 2:] - box[:, :2], axis=1)))))


@njit(cache=True)
def _bucket_range(a, b, lo, size, n):
    """Buckets [i0, i1] along one axis overlapped by the interval [a, b] [m]."""
    i0 = min(max(int((a - lo) / size), 0), n - 1)
    i1 = min(max(int((b - lo) / size), 0), n - 1)
    return i0, i1


@njit(cache=True)
def _bucket_items(box, lo, size, shape):
    """CSR (start (nb + 1,), items (k,)) of the boxes overlapping each bucket (bucket index
    ix · shape[1] + iy)."""
    nb = shape[0] * shape[1]
    count = np.zeros(nb + 1, np.int64)
    for c in range(box.shape[0]):
        x0, x1 = _bucket_range(box[c, 0], box[c, 2], lo[0], size, shape[0])
        y0, y1 = _bucket_range(box[c, 1], box[c, 3], lo[1], size, shape[1])
        for ix in range(x0, x1 + 1):
            for iy in range(y0, y1 + 1):
                count[ix * shape[1] + iy + 1] += 1
    start = np.cumsum(count)
    fill = start[:-1].copy()
    items = np.empty(start[-1], np.int64)
    for c in range(box.shape[0]):
        x0, x1 = _bucket_range(box[c, 0], box[c, 2], lo[0], size, shape[0])
        y0, y1 = _bucket_range(box[c, 1], box[c, 3], lo[1], size, shape[1])
        for ix in range(x0, x1 + 1):
            for iy in range(y0, y1 + 1):
                b = ix * shape[1] + iy
                items[fill[b]] = c
                fill[b] += 1
    return start, items


@njit(cache=True)
def _locate_kernel(cg_, p2, tol):
    """For each 2-D point of ``p2`` (m, 2) [m]: the first cell of its bucket in the
    :class:`CellGrid` ``cg_`` whose padded box holds it and whose bilinear map contains it within
    ``tol`` in reference coordinates, and its reference coordinates clipped to [0, 1]. Returns
    (cell (m,) int32, −1 where none; X (m, 2))."""
    xy, cg, box, g = cg_.xy, cg_.cg, cg_.box, cg_.grid
    m = p2.shape[0]
    cell = np.full(m, -1, np.int32)
    X = np.zeros((m, 2))
    xc = np.empty((4, 2))
    for p in range(m):
        y0, y1 = p2[p, 0], p2[p, 1]
        ix, iy = (y0 - g.lo[0]) / g.size, (y1 - g.lo[1]) / g.size
        if not (0.0 <= ix < g.shape[0] and 0.0 <= iy < g.shape[1]):
            continue
        b = int(ix) * g.shape[1] + int(iy)
        for k in range(g.start[b], g.start[b + 1]):
            c = g.items[k]
            if y0 < box[c, 0] or y0 > box[c, 2] or y1 < box[c, 1] or y1 > box[c, 3]:
                continue
            for v in range(4):
                xc[v, 0] = xy[cg[c, v], 0]
                xc[v, 1] = xy[cg[c, v], 1]
            xi, eta = _pull_back(xc, y0, y1)
            if -tol <= xi <= 1.0 + tol and -tol <= eta <= 1.0 + tol:
                cell[p] = c
                X[p, 0] = min(max(xi, 0.0), 1.0)
                X[p, 1] = min(max(eta, 0.0), 1.0)
                break
    return cell, X


def _locate(fg: FinGeometry, grid: CellGrid, p2: np.ndarray, tol: float = 1e-9):
    """Owned cell and reference coordinates of the points ``p2`` (m, 2) [m] in the fin plane
    (coordinates along e1, e2 from the origin).

    Returns (cell, X, mine, found): cell index (−1 where this rank does not claim the point),
    reference coordinates (m, 2), whether this rank claims the point, and whether any rank found
    it. Each point is claimed by exactly one rank (the lowest owning a containing cell)."""
    comm = fg.mesh.comm
    cell, X = _locate_kernel(grid, np.ascontiguousarray(p2, dtype=np.float64).reshape(-1, 2), tol)
    here = cell >= 0
    rank_claim = np.where(here, comm.rank, comm.size)
    owner = np.empty_like(rank_claim)
    comm.Allreduce(rank_claim, owner, op=MPI.MIN)
    mine = here & (owner == comm.rank)
    cell[~mine] = -1
    return cell, X, mine, owner < comm.size


def _in_plane(fg: FinGeometry, points3: np.ndarray) -> np.ndarray:
    """Coordinates (m, 2) [m] along e1, e2 of points (m, 3) [m] (their normal part dropped)."""
    rel = np.asarray(points3, dtype=float).reshape(-1, 3) - fg.origin
    return np.column_stack([rel @ fg.e1, rel @ fg.e2])


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
    distance (m,) [m] and the unit direction of that boundary segment (m, 2) (the lowest-numbered
    nearest segment on a tie). Compiled, the segments bucketed on a grid searched in rings around
    each point: the edge contacts of finely sampled fin loads are ~3e5 points against ~1e3
    boundary segments (numpy broadcasting took 90 s per fin at 0.156 µs; every segment for every
    point, 1.5 s)."""
    y2 = np.ascontiguousarray(y2, dtype=np.float64).reshape(-1, 2)
    segs = np.ascontiguousarray(segs, dtype=np.float64).reshape(-1, 2, 2)
    near, dist, tdir = np.zeros((len(y2), 2)), np.zeros(len(y2)), np.zeros((len(y2), 2))
    if not len(segs):
        raise ValueError("the fin has no boundary segments")
    box = np.concatenate([segs.min(axis=1), segs.max(axis=1)], axis=1)
    _nearest_kernel(segs, y2, buckets(box, float(np.median(np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1)))),
                    near, dist, tdir)
    return near, dist, tdir


@njit(cache=True, inline="always")
def _segment_point(segs, k, y0, y1):
    """Nearest point (q0, q1) of segment k to (y0, y1) and its squared distance."""
    a0, a1 = segs[k, 0, 0], segs[k, 0, 1]
    d0, d1 = segs[k, 1, 0] - a0, segs[k, 1, 1] - a1
    L2 = max(d0 * d0 + d1 * d1, 1e-300)
    s = min(max(((y0 - a0) * d0 + (y1 - a1) * d1) / L2, 0.0), 1.0)
    q0, q1 = a0 + s * d0, a1 + s * d1
    return q0, q1, (q0 - y0) ** 2 + (q1 - y1) ** 2


@njit(cache=True)
def _nearest_kernel(segs, y2, g, near, dist, tdir):
    """Ring search: the buckets at Chebyshev distance R = 0, 1, … from the point's (clamped)
    bucket, until the best squared distance is below that of the nearest point outside the
    searched block (a segment not yet seen lies wholly outside it) or the block is the grid."""
    lo, size, start, cells = g.lo, g.size, g.start, g.items
    nx, ny = g.shape[0], g.shape[1]
    for i in range(y2.shape[0]):
        y0, y1 = y2[i, 0], y2[i, 1]
        ix = min(max(int(math.floor((y0 - lo[0]) / size)), 0), nx - 1)
        iy = min(max(int(math.floor((y1 - lo[1]) / size)), 0), ny - 1)
        best, bq0, bq1, bk = np.inf, 0.0, 0.0, -1
        R = 0
        while True:
            for bx in range(ix - R, ix + R + 1):
                if bx < 0 or bx >= nx:
                    continue
                edge = bx == ix - R or bx == ix + R
                by = iy - R
                while by <= iy + R:
                    if 0 <= by < ny:
                        b = bx * ny + by
                        for t in range(start[b], start[b + 1]):
                            k = cells[t]
                            q0, q1, d2 = _segment_point(segs, k, y0, y1)
                            if d2 < best or (d2 == best and k < bk):
                                best, bq0, bq1, bk = d2, q0, q1, k
                    by = by + 1 if edge else (iy + R if by == iy - R else iy + R + 1)
            whole = ix - R <= 0 and ix + R >= nx - 1 and iy - R <= 0 and iy + R >= ny - 1
            if whole:
                break
            bound = np.inf  # distance from the point to the searched block's open sides
            if ix - R > 0:
                bound = min(bound, y0 - (lo[0] + (ix - R) * size))
            if ix + R < nx - 1:
                bound = min(bound, lo[0] + (ix + R + 1) * size - y0)
            if iy - R > 0:
                bound = min(bound, y1 - (lo[1] + (iy - R) * size))
            if iy + R < ny - 1:
                bound = min(bound, lo[1] + (iy + R + 1) * size - y1)
            if bound > 0.0 and best < bound * bound:
                break
            R += 1
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
    p2 = _in_plane(fg, points)
    r = 0.5 * widths
    segs = _boundary_segments(fg)
    grid = cell_grid(fg)

    _snap_to_planform(fg, grid, segs, p2, points, plane_tol)

    # 1. disk stencils, spaced by the cells the loads land in (not the fin's smallest edge)
    h = _load_cell_size(fg, grid, p2)
    n_rings, n_phi, n_line = stencil_resolution(float(r.max(initial=0.0)), h)
    DISK = disk_stencil(n_rings, n_phi)
    GL = np.polynomial.legendre.leggauss(n_line)
    LINE = GL[0]
    nd = len(DISK)
    _, dist, edge_dir = _nearest_on_boundary(segs, p2)  # (the snapped centres: once for both uses)
    tried = np.flatnonzero(_disk_may_fit(segs, dist, r, DISK, n_phi))
    pts = (p2[tried, None, :] + r[tried, None, None] * DISK[None]).reshape(-1, 2)
    cell, X, mine, found = _locate(fg, grid, pts)
    ok = found.reshape(len(tried), nd).all(axis=1)
    ok_disk = np.zeros(ne, dtype=bool)
    ok_disk[tried] = ok
    ev_idx = [np.repeat(tried, nd)]
    wts = [np.full(len(tried) * nd, 1.0 / nd)]
    keep = [np.repeat(ok, nd) & mine]
    cells, Xs = [cell], [X]
    todo = np.flatnonzero(~ok_disk)
    if len(todo):
        tdir = edge_dir[todo]
        half = r[todo].copy()
        nl = len(LINE)
        for _ in range(12):
            if not len(todo):
                break
            pts = (p2[todo, None, :] + (half[:, None] * LINE[None])[..., None] * tdir[:, None, :])
            c, Xl, mi, fo = _locate(fg, grid, pts.reshape(-1, 2))
            ok = fo.reshape(-1, nl).all(axis=1)
            ev_idx.append(np.repeat(todo, nl))
            wts.append(np.tile(GL[1] / 2.0, len(todo)))
            keep.append(np.repeat(ok, nl) & mi)
            cells.append(c)
            Xs.append(Xl)
            todo, tdir, half = todo[~ok], tdir[~ok], 0.5 * half[~ok]
        if len(todo):  # last resort: point load at p
            c, Xp, mi, fo = _locate(fg, grid, p2[todo])
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


def _disk_may_fit(segs: np.ndarray, dist: np.ndarray, r: np.ndarray, disk: np.ndarray, n_phi: int) -> np.ndarray:
    """Whether the disk stencil of each event (its centre at ``dist`` (ne,) [m] from the outline
    ``segs``, radius ``r`` (ne,) [m], unit stencil ``disk`` with ``n_phi`` points per ring) may lie on
    the fin; False only where it certainly does not, so that the events left out would have failed
    the disk test anyway.

    Reason: on a convex outline the tangent at a centre's nearest boundary point (distance δ) is a
    supporting line of the fin, and the outer ring (radius ρ r) has a point within π/n_phi of
    every direction, so a point beyond that line by ρ r cos(π/n_phi) − δ: off the fin when that
    exceeds 1e-9 m (the location's tolerance is ~1e-12 m). Edge contacts — most of a wing's
    finely sampled loads, centred on the outline — are thus not located a hundred times over.
    A non-convex outline: every disk is tried."""
    if not _convex(segs):
        return np.ones(len(dist), dtype=bool)
    reach = r * float(np.linalg.norm(disk, axis=1).max()) * math.cos(math.pi / n_phi)
    return dist + 1e-9 >= reach


@njit(cache=True)
def _convex(segs) -> bool:
    """Whether every boundary vertex lies on one side of each boundary segment's line (within
    1e-9 of the extent², round-off of collinear pieces): the outline is convex."""
    lo0, lo1, hi0, hi1 = np.inf, np.inf, -np.inf, -np.inf
    for k in range(segs.shape[0]):
        for e in range(2):
            lo0, hi0 = min(lo0, segs[k, e, 0]), max(hi0, segs[k, e, 0])
            lo1, hi1 = min(lo1, segs[k, e, 1]), max(hi1, segs[k, e, 1])
    eps = 1e-9 * ((hi0 - lo0) ** 2 + (hi1 - lo1) ** 2)
    for k in range(segs.shape[0]):
        a0, a1 = segs[k, 0, 0], segs[k, 0, 1]
        d0, d1 = segs[k, 1, 0] - a0, segs[k, 1, 1] - a1
        pos, neg = False, False
        for j in range(segs.shape[0]):
            for e in range(2):
                c = d0 * (segs[j, e, 1] - a1) - d1 * (segs[j, e, 0] - a0)
                pos = pos or c > eps
                neg = neg or c < -eps
        if pos and neg:
            return False
    return True


def _load_cell_size(fg: FinGeometry, grid: CellGrid, p2: np.ndarray) -> float:
    """Median over the contact points ``p2`` (ne, 2) [m, in the plane] of the shortest edge of the
    cell each lies in [m] (all ranks; the fin's shortest edge when there is no point): the size
    :func:`stencil_resolution` lays the stencils by. Not the fin's shortest edge: a few
    kite-shaped cells (docs/validation.md, "Fin mesh quality") halve it and made every stencil
    ~8× denser than the cells under the loads need (rotary wing_4: ~1e7 points to locate;
    docs/performance.md, "Shell set-up: stencils by the loaded cells")."""
    cell, _, mine, _ = _locate(fg, grid, p2)
    cg = fg.mesh.geometry.dofmap.array.reshape(-1, 4)
    edges = cell_edges(fg.mesh.geometry.x, cg[cell[mine]])
    sizes = np.concatenate(fg.mesh.comm.allgather(edges.min(axis=1, initial=np.inf)))
    sizes = sizes[np.isfinite(sizes)]
    return float(np.median(sizes)) if len(sizes) else min_edge_length(fg.mesh)


def _snap_to_planform(fg: FinGeometry, grid: CellGrid, segs, p2: np.ndarray, points: np.ndarray,
                      plane_tol: float) -> None:
    """Contact points just outside the planform (a rope on the rounded/blunt edge, round-off)
    are moved in place in ``p2`` (ne, 2) [m] to the nearest boundary point when within
    ``plane_tol`` [m]; farther is a ValueError naming the event."""
    _, _, _, inside = _locate(fg, grid, p2)
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
    the weight on the three translational DOFs of the cell's four nodes. Each event's weights
    are summed per node in a compiled pass (``_event_nodes``): one entry per node and direction,
    not 12 per quadrature point for scipy to sum (a wing's ~3e7 stencil points were ~4e8 COO
    entries)."""
    V = fg.V
    dm = np.ascontiguousarray(V.dofmap.list.array.reshape(-1, 4), dtype=np.int64)
    n_nodes = V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts
    ptr, node, val = _event_nodes(np.asarray(ev, np.int64), np.asarray(w, float), np.asarray(cl, np.int64),
                                  np.ascontiguousarray(Xa, dtype=float), dm, ne, n_nodes)
    indptr, indices, data = _transpose_rows(ptr, node, val, ne)
    GT = sparse.csr_matrix((data, indices, indptr), shape=(3 * ne, n_nodes * NDOF_NODE))
    return GT.T.tocsr()


@njit(cache=True)
def _transpose_rows(ptr, node, val, ne):
    """CSR arrays of Gᵀ (3·ne rows): row 3e + k holds event e's nodes on their DOF k (k = 0, 1, 2)."""
    nnz = len(node)
    indptr = np.zeros(3 * ne + 1, np.int64)
    indices = np.empty(3 * nnz, np.int64)
    data = np.empty(3 * nnz)
    pos = 0
    for e in range(ne):
        for k in range(3):
            for t in range(ptr[e], ptr[e + 1]):
                indices[pos] = node[t] * NDOF_NODE + k
                data[pos] = val[t]
                pos += 1
            indptr[3 * e + k + 1] = pos
    return indptr, indices, data


@njit(cache=True)
def _event_nodes(ev, w, cl, Xa, dm, ne, n_nodes):
    """Per event, its nodes and their summed weights Σ_q w_q N_i(X_q) (Q1, dolfinx vertex order):
    CSR over events (ptr (ne + 1,), node (k,), val (k,)), nodes in first-touched order."""
    q = len(ev)
    start = np.zeros(ne + 1, np.int64)
    for i in range(q):
        start[ev[i] + 1] += 1
    for e in range(ne):
        start[e + 1] += start[e]
    order = np.empty(q, np.int64)
    fill = start[:-1].copy()
    for i in range(q):
        order[fill[ev[i]]] = i
        fill[ev[i]] += 1
    slot = np.full(n_nodes, -1, np.int64)
    ptr = np.zeros(ne + 1, np.int64)
    node = np.empty(4 * q, np.int64)
    val = np.empty(4 * q)
    n = 0
    for e in range(ne):
        first = n
        for t in range(start[e], start[e + 1]):
            i = order[t]
            xi, eta = Xa[i, 0], Xa[i, 1]
            N = ((1.0 - xi) * (1.0 - eta), xi * (1.0 - eta), (1.0 - xi) * eta, xi * eta)
            for v in range(4):
                a = dm[cl[i], v]
                if slot[a] < 0:
                    slot[a] = n
                    node[n] = a
                    val[n] = 0.0
                    n += 1
                val[slot[a]] += w[i] * N[v]
        for t in range(first, n):
            slot[node[t]] = -1
        ptr[e + 1] = n
    return ptr, node[:n].copy(), val[:n].copy()


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
    cell, X, mine, found = _locate(fg, cell_grid(fg), _in_plane(fg, points))
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
