"""Surface stresses at the nodes by lumped L2 projection of the Gauss-point strains (recovery).

The raw stresses of the bilinear shell are discontinuous across elements and accurate only at
special points (the old output took cell centres, h/√2 from a node, so a peak's error swung
with the mesh). Here the membrane strain ε and the curvature κ (the 6 in-plane strain measures,
fin basis e1, e2) are projected onto the continuous P1 space with the lumped (row-sum) mass:

    ε*_i = Σ_e ∫_e N_i ε_h dA / ∫ N_i dA        (2 × 2 Gauss points per cell)

and the same for κ. Lumped L2 projection of Q1 gradients is the nodal averaging of
Zienkiewicz & Zhu (1987); at interior nodes of smooth meshes it is superconvergent (O(h²), the
deflection's order), at boundary nodes O(h). The surface stresses follow pointwise,

    σ(z) = C (ε* + z κ*),  z = +t/2 (top, +n side) and −t/2 (bottom)     (plane stress)

von Mises σ_vm = √(σ11² + σ22² − σ11σ22 + 3σ12²), max principal σ_1 = (σ11+σ22)/2 +
√(((σ11−σ22)/2)² + σ12²). Transverse shear stress is not included (zero at the surfaces).

Peak: the largest nodal von Mises over the instants the kernel evaluates it (every
``shell.peak_interval``, 0.25 µs by default: a rope-load stress peak is 3–5 µs wide), outside
the St-Venant zones of the active contact loads (:mod:`flexnet_fe.shell.hotspot`); at the peak's
instant the recovered field
σ* = Σ N_i σ*_i is searched inside the cells around that node (:func:`locate_peak`), so the
reported location lies within the element where the peak occurs. Error estimate: the
Zienkiewicz–Zhu estimator at the peak, max over the Gauss points of those cells of
vm(σ* − σ_h) / σ_peak — the local error of the raw stress σ_h; the recovered value is more
accurate (higher order), so this estimate is conservative (validated against the plate series
in docs/validation.md).

All functions on arrays are numba-compiled so that the explicit kernel calls them per sample.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit
from scipy import sparse

NB = 5
_G = 0.5 / np.sqrt(3.0)
GAUSS = np.array([[0.5 - _G, 0.5 - _G], [0.5 + _G, 0.5 - _G], [0.5 - _G, 0.5 + _G],
                  [0.5 + _G, 0.5 + _G]])
"""2 × 2 Gauss points on the reference square [0, 1]², weights 1/4"""


class RecoveryData(NamedTuple):
    """Geometry of the recovery (what never changes), local to a process."""

    cells: np.ndarray
    """node indices of the owned cells, dolfinx order (0,0),(1,0),(0,1),(1,1), (nc, 4) int32"""
    dN: np.ndarray
    """∂N_j/∂s_α at the Gauss points, fin basis, (nc, 4 points, 4 nodes, 2) [1/m]"""
    wN: np.ndarray
    """N_i(g) w_g det J_g, (nc, 4 points, 4 nodes) [m²]"""
    winv: np.ndarray
    """1 / ∫ N_i dA, (n_nodes,) [1/m²] (0 for nodes without owned cells)"""
    e1: np.ndarray
    e2: np.ndarray
    material: np.ndarray
    """(E' [Pa], ν [-], t [m])"""
    num: np.ndarray
    """scratch (n_nodes, 6): projected numerators"""
    C: np.ndarray
    """∫ N_i ∂N_j/∂s_α dA per cell, (nc, 4, 4, 2) [m]"""
    gptr: np.ndarray
    """assembled recovery operator (serial): node-row pointer (n_nodes + 1,)"""
    gind: np.ndarray
    """column nodes (nnz,)"""
    g: np.ndarray
    """Σ_cells ∫ N_i ∂N_j/∂s_α dA / ∫ N_i dA, (nnz, 2) [1/m]"""
    proj: np.ndarray
    """scratch (n_nodes, 4): each node's (u·e1, u·e2, θ1, θ2) of the sample (:func:`sample_nodes`)"""


def shape_q1(xi: np.ndarray, eta: np.ndarray) -> np.ndarray:
    """Bilinear shape functions on [0,1]², dolfinx vertex order; shape (len(xi), 4)."""
    return np.column_stack([(1 - xi) * (1 - eta), xi * (1 - eta), (1 - xi) * eta, xi * eta])


def shape_q1_grad(xi: np.ndarray, eta: np.ndarray) -> np.ndarray:
    """Reference gradients (len, 4 nodes, 2)."""
    dxi = np.column_stack([-(1 - eta), 1 - eta, -eta, eta])
    deta = np.column_stack([-(1 - xi), -xi, 1 - xi, xi])
    return np.stack([dxi, deta], axis=2)


def cell_geometry(xc2: np.ndarray, ref: np.ndarray):
    """At reference points ``ref`` (m, 2) of bilinear cells with in-plane vertex coordinates
    ``xc2`` (nc, 4, 2): physical gradients ∂N/∂s (nc, m, 4, 2), det J (nc, m), N (m, 4)."""
    N = shape_q1(ref[:, 0], ref[:, 1])
    dR = shape_q1_grad(ref[:, 0], ref[:, 1])  # (m, 4, 2)
    J = np.einsum("cja,mjb->cmab", xc2, dR)  # J[a, b] = ∂x_a/∂ξ_b
    det = J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]
    # a cell may be numbered clockwise in (e1, e2): only its area |det J| matters, but the sign
    # must not change inside a cell (that would be a folded quadrilateral)
    if np.any(det[:, :1] * det <= 0):
        raise ValueError("fin mesh has a folded or degenerate quadrilateral")
    det = np.abs(det)
    Jinv = np.stack([np.stack([J[..., 1, 1], -J[..., 0, 1]], -1),
                     np.stack([-J[..., 1, 0], J[..., 0, 0]], -1)], -2) / det[..., None, None]
    dN = np.einsum("mjb,cmba->cmja", dR, Jinv)
    return dN, det, N


def build_recovery(cells: np.ndarray, x: np.ndarray, n_nodes: int, e1, e2, origin,
                   material: tuple[float, float, float]) -> RecoveryData:
    """Recovery data for ``cells`` (nc, 4) node indices into node coordinates ``x`` (n, 3) [m]
    of a flat fin with in-plane basis e1, e2; material = (E' [Pa], ν, t [m]). ``winv`` is the
    local lumped weight only: in parallel, complete it with :func:`complete_weights`."""
    rel = x[cells] - np.asarray(origin)
    xc2 = np.stack([rel @ np.asarray(e1), rel @ np.asarray(e2)], axis=2)
    dN, det, N = cell_geometry(xc2, GAUSS)
    wN = 0.25 * det[:, :, None] * N[None, :, :]
    w = np.zeros(n_nodes)
    np.add.at(w, cells.ravel(), wN.sum(axis=1).ravel())
    winv = np.where(w > 0, 1.0 / np.where(w > 0, w, 1.0), 0.0)
    C = np.ascontiguousarray(np.einsum("cgi,cgja->cija", wN, dN))
    rows = np.repeat(cells, 4, axis=1).ravel()  # (c, i, j) order
    cols = np.tile(cells, (1, 4)).ravel()
    G = [sparse.csr_matrix((C[..., a].ravel(), (rows, cols)), shape=(n_nodes, n_nodes))
         for a in range(2)]
    for Ga in G:
        Ga.sum_duplicates()
        Ga.sort_indices()
    if not (np.array_equal(G[0].indptr, G[1].indptr) and np.array_equal(G[0].indices,
                                                                         G[1].indices)):
        raise RuntimeError("recovery operator patterns differ")
    scale = np.repeat(winv, np.diff(G[0].indptr))
    g = np.column_stack([G[0].data * scale, G[1].data * scale])
    return RecoveryData(cells=np.ascontiguousarray(cells, dtype=np.int32), dN=dN, wN=wN,
                        winv=winv, e1=np.asarray(e1, float), e2=np.asarray(e2, float),
                        material=np.array(material, float), num=np.zeros((n_nodes, 6)),
                        C=C, gptr=G[0].indptr.astype(np.int64),
                        gind=G[0].indices.astype(np.int32), g=np.ascontiguousarray(g),
                        proj=np.zeros((n_nodes, 4)))


@njit(cache=True)
def gauss_strains(R, u, c, out):
    """Raw strains (ε11, ε22, γ12, κ11, κ22, 2κ12) at the 4 Gauss points of cell ``c`` from
    the nodal DOFs ``u`` (5 per node: u in frame B, θ in (e1, e2)); out (4, 6)."""
    e1, e2 = R.e1, R.e2
    out[:, :] = 0.0
    for j in range(4):
        n = R.cells[c, j]
        b = NB * n
        u1 = e1[0] * u[b] + e1[1] * u[b + 1] + e1[2] * u[b + 2]
        u2 = e2[0] * u[b] + e2[1] * u[b + 1] + e2[2] * u[b + 2]
        t1 = u[b + 3]
        t2 = u[b + 4]
        for g in range(4):
            d1 = R.dN[c, g, j, 0]
            d2 = R.dN[c, g, j, 1]
            out[g, 0] += d1 * u1
            out[g, 1] += d2 * u2
            out[g, 2] += d2 * u1 + d1 * u2
            out[g, 3] += d1 * t1
            out[g, 4] += d2 * t2
            out[g, 5] += d2 * t1 + d1 * t2


@njit(cache=True)
def accumulate_cells(R, u):
    """R.num[i] = Σ_cells ∫ N_i ε_h dA (local numerators of the projection) with the cell
    matrices C[c, i, j, α] = ∫ N_i ∂N_j/∂s_α dA (2 × 2 Gauss), so ε-numerators of node i are
    Σ_j C_ij·(nodal values of j) — 8 products per node pair."""
    num = R.num
    num[:, :] = 0.0
    e1, e2, C = R.e1, R.e2, R.C
    for c in range(R.cells.shape[0]):
        for j in range(4):
            b = NB * R.cells[c, j]
            u1 = e1[0] * u[b] + e1[1] * u[b + 1] + e1[2] * u[b + 2]
            u2 = e2[0] * u[b] + e2[1] * u[b + 1] + e2[2] * u[b + 2]
            t1 = u[b + 3]
            t2 = u[b + 4]
            for i in range(4):
                n = R.cells[c, i]
                d1 = C[c, i, j, 0]
                d2 = C[c, i, j, 1]
                num[n, 0] += d1 * u1
                num[n, 1] += d2 * u2
                num[n, 2] += d2 * u1 + d1 * u2
                num[n, 3] += d1 * t1
                num[n, 4] += d2 * t2
                num[n, 5] += d2 * t1 + d1 * t2


@njit(cache=True, inline="always")
def _measures(E, nu, z, a, b, g):
    """(von Mises, max principal) [Pa] of the strain (a, b, g) = (ε11, ε22, γ12) at height z."""
    s11 = E * (a + nu * b)
    s22 = E * (b + nu * a)
    s12 = E * (1.0 - nu) * 0.5 * g
    vm = np.sqrt(max(s11 * s11 + s22 * s22 - s11 * s22 + 3.0 * s12 * s12, 0.0))
    return vm, 0.5 * (s11 + s22) + np.sqrt(0.25 * (s11 - s22) ** 2 + s12 * s12)


@njit(cache=True)
def _surfaces(E, nu, z, m, k, nodal, i):
    """Top and bottom surface measures of node ``i`` from its membrane strains m = (ε11, ε22, γ12)
    and curvatures k [1/m] at z = ±t/2: writes (vm_top, vm_bot, p1_top, p1_bot) [Pa] into
    ``nodal[i]`` and returns (max von Mises, max principal) of the two surfaces."""
    vt, pt = _measures(E, nu, z, m[0] + z * k[0], m[1] + z * k[1], m[2] + z * k[2])
    vb, pb = _measures(E, nu, z, m[0] - z * k[0], m[1] - z * k[1], m[2] - z * k[2])
    nodal[i, 0], nodal[i, 1], nodal[i, 2], nodal[i, 3] = vt, vb, pt, pb
    return max(vt, vb), max(pt, pb)


@njit(cache=True)
def nodal_from_numerators(R, u, nodal, n_owned):
    """Nodal (vm_top, vm_bot, p1_top, p1_bot) [Pa] of the owned nodes from R.num (plane
    stress at z = ±t/2 of the recovered ε*, κ*); returns (max vm, its node, max p1, max |u|
    over translations) over the owned nodes."""
    E, nu, t = R.material[0], R.material[1], R.material[2]
    z = 0.5 * t
    vmax, node, p1max, umax = 0.0, -1, -np.inf, 0.0
    num, winv = R.num, R.winv
    for i in range(n_owned):
        w = winv[i]
        e0, e1, e2 = num[i, 0] * w, num[i, 1] * w, num[i, 2] * w
        k0, k1, k2 = num[i, 3] * w, num[i, 4] * w, num[i, 5] * w
        vm, p1 = _surfaces(E, nu, z, (e0, e1, e2), (k0, k1, k2), nodal, i)
        if vm > vmax:
            vmax, node = vm, i
        p1max = max(p1max, p1)
        b = NB * i
        umax = max(umax, u[b] * u[b] + u[b + 1] * u[b + 1] + u[b + 2] * u[b + 2])
    return vmax, node, p1max, np.sqrt(umax)


@njit(cache=True)
def sample_nodes(R, u, nodal):
    """Serial: nodal surface measures of all nodes into ``nodal`` (n_nodes, 4) with the
    assembled operator (node rows, ~9 neighbours × 8 products, no scattered writes); returns
    (max vm, node, max p1, max |u|). Same values as :func:`accumulate_cells` +
    :func:`nodal_from_numerators` up to summation order. Each node's in-plane displacement and
    rotations are projected once (into ``R.proj``), not once per neighbour row that reads them:
    the same products, so the same digits (1e5-DOF plate: 12.4 → 10.4 ns per DOF and sample,
    side by side; docs/performance.md, "Shell: selective mass scaling and the stress sample")."""
    E, nu, t = R.material[0], R.material[1], R.material[2]
    z = 0.5 * t
    e1, e2, g, gind, pr = R.e1, R.e2, R.g, R.gind, R.proj
    vmax, node, p1max, umax = 0.0, -1, -np.inf, 0.0
    for i in range(min(pr.shape[0], u.shape[0] // NB)):  # every node a row may read
        b = NB * i
        pr[i, 0] = e1[0] * u[b] + e1[1] * u[b + 1] + e1[2] * u[b + 2]
        pr[i, 1] = e2[0] * u[b] + e2[1] * u[b + 1] + e2[2] * u[b + 2]
        pr[i, 2] = u[b + 3]
        pr[i, 3] = u[b + 4]
        if i < nodal.shape[0]:
            umax = max(umax, u[b] * u[b] + u[b + 1] * u[b + 1] + u[b + 2] * u[b + 2])
    for i in range(nodal.shape[0]):
        s0 = s1 = s2 = s3 = s4 = s5 = 0.0
        for pp in range(R.gptr[i], R.gptr[i + 1]):
            p = np.uint64(pp)  # unsigned: no wrap-around test on the gathered index (kernel.U1)
            k = np.uint64(gind[p])
            u1, u2, t1, t2 = pr[k, 0], pr[k, 1], pr[k, 2], pr[k, 3]
            d1, d2 = g[p, 0], g[p, 1]
            s0 += d1 * u1
            s1 += d2 * u2
            s2 += d2 * u1 + d1 * u2
            s3 += d1 * t1
            s4 += d2 * t2
            s5 += d2 * t1 + d1 * t2
        vm, p1 = _surfaces(E, nu, z, (s0, s1, s2), (s3, s4, s5), nodal, i)
        if vm > vmax:
            vmax, node = vm, i
        p1max = max(p1max, p1)
    return vmax, node, p1max, np.sqrt(umax)


def nodal_strains(R: RecoveryData, u: np.ndarray) -> np.ndarray:
    """Recovered (ε*, κ*) at the local nodes from a state with ghost values, (n_nodes, 6)
    (numerators of owned cells: complete at owned nodes of this process)."""
    accumulate_cells(R, u)
    return R.num * R.winv[:, None]


def stress_tensors(s6: np.ndarray, R: RecoveryData, z: float) -> np.ndarray:
    """(σ11, σ22, σ12) [Pa] at fibre height z [m] of strain measures s6 (..., 6)."""
    E, nu, _ = R.material
    a = s6[..., 0] + z * s6[..., 3]
    b = s6[..., 1] + z * s6[..., 4]
    g = s6[..., 2] + z * s6[..., 5]
    return np.stack([E * (a + nu * b), E * (b + nu * a), E * (1 - nu) * 0.5 * g], axis=-1)


def von_mises(s: np.ndarray) -> np.ndarray:
    """Plane-stress von Mises of (σ11, σ22, σ12) arrays (..., 3) [Pa]."""
    return np.sqrt(np.maximum(s[..., 0] ** 2 + s[..., 1] ** 2 - s[..., 0] * s[..., 1]
                              + 3 * s[..., 2] ** 2, 0.0))


class Peak(NamedTuple):
    value: float
    """von Mises of the recovered field at the located point [Pa]"""
    location: np.ndarray
    """(3,) [m]"""
    surface: str
    """"top" or "bottom\""""
    error_estimate_rel: float
    """ZZ estimate at the peak [-] (see module doc)"""
    cell: int


def locate_peak(R: RecoveryData, u: np.ndarray, node: int, x: np.ndarray, origin, *,
                grid: int = 17, exclude: tuple[np.ndarray, np.ndarray] | None = None) -> Peak:
    """Peak of the recovered von Mises σ* = Σ N_i σ*_i around ``node`` at state ``u`` (serial):
    searched on a grid×grid lattice of each cell containing the node, skipping lattice points
    inside the St-Venant zones ``exclude`` = (load points (m, 3) [m], radii (m,) [m]); plus its
    ZZ error estimate over the Gauss points of those cells (module doc). x: node coordinates
    (n, 3) [m]."""
    s_nodes = nodal_strains(R, u)
    cells = np.flatnonzero((R.cells == node).any(axis=1))
    t = R.material[2]
    g = (np.arange(grid) + 0.0) / (grid - 1)
    ref = np.column_stack([np.repeat(g, grid), np.tile(g, grid)])
    N = shape_q1(ref[:, 0], ref[:, 1])  # (m, 4)
    best = (-1.0, None, None, None)
    for c in cells:
        sc = N @ s_nodes[R.cells[c]]  # (m, 6)
        xq = N @ x[R.cells[c]]
        out = np.ones(len(xq), bool)
        if exclude is not None and len(exclude[0]):
            d = np.linalg.norm(xq[:, None, :] - exclude[0][None], axis=2)
            out = ~(d < exclude[1][None]).any(axis=1)
        if not out.any():
            continue
        for z, name in ((0.5 * t, "top"), (-0.5 * t, "bottom")):
            vm = np.where(out, von_mises(stress_tensors(sc, R, z)), -1.0)
            k = int(np.argmax(vm))
            if vm[k] > best[0]:
                best = (float(vm[k]), xq[k], name, int(c))
    value, loc, surf, cbest = best
    z = 0.5 * t if surf == "top" else -0.5 * t
    eta = 0.0
    g6 = np.empty((4, 6))
    Ng = shape_q1(GAUSS[:, 0], GAUSS[:, 1])
    for c in cells:
        gauss_strains(R, u, int(c), g6)
        diff = Ng @ s_nodes[R.cells[c]] - g6
        eta = max(eta, float(von_mises(stress_tensors(diff, R, z)).max()))
    return Peak(value=value, location=np.asarray(loc, float), surface=surf,
                error_estimate_rel=eta / value if value > 0 else float("nan"), cell=cbest)
