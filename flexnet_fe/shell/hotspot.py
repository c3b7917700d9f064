"""The reported fin stress under rope contact: structural peak outside a St-Venant zone, and the
local bearing stress from its closed form (issue 10).

Why: a rope (diameter d ≈ 4.5 mm) pressing on a 4–6 mm fin loads it over a patch of about
d × t. Within about one thickness of such a load the stress is a three-dimensional contact /
bearing stress that shell theory does not describe: a shell's surface stress under a
concentrated load is singular (in-plane edge load, Flamant: σ ~ 2F/(π t r); face load, plate:
σ ~ (3F/2πt²) ln(1/r)), so the shell's peak *at* the load grows without limit as the mesh is
refined (measured on the paper fins: ×1.5–1.9 per halving of h, docs/validation.md). An engineer
splits the stress there into (DNV-RP-C203 / IIW hot-spot practice, St-Venant's principle):

1. the **structural stress** (membrane + bending, von Mises and principal at the surfaces),
   which the shell resolves and which converges under refinement, read outside a zone of radius
   ``r_ex = factor × max(t, d)`` around every load point active at that instant (St-Venant: the
   self-equilibrated part of a local load decays over about the larger of the patch size and the
   thickness; hot-spot read-out points sit at 0.4 t–1.5 t from the weld toe for the same
   reason). It is the summary's ``peak_von_mises_pa``; ``factor`` is
   ``shell.stvenant_radius_factor`` (default 2, sensitivity in docs/validation.md);
2. the **bearing / contact stress** at the load, from closed forms (:func:`bearing_stress`):
   an edge load over the projected rope area, σ_b = |F| / (d t); a face load as a Hertz line
   contact of the rope (cylinder of diameter d) on the fin face over a length d (the patch the
   load transfer spreads it on), p_0 = √(P′ E* / (π R)), P′ = F_n / d, R = d/2,
   1/E* = (1 − ν_f²)/E_f + 1/E_r. Compared with its own allowable (bearing yield ≈ 1.5 × tensile
   yield for Al 7075-T6 at e/D = 2, MMPDS; ``shell.bearing_allowable_factor``).

Departure from the paper: the paper reports one peak von Mises per fin with no treatment of the
contact singularity (its load transfer is not described).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit


class Exclusion(NamedTuple):
    """The St-Venant zones of each contact sample's loads: the events of sample k are rows
    ``ptr[k]:ptr[k+1]`` (CSR over samples), each a ball of ``radius`` around ``centre``. Which
    nodes a zone holds is found when it is needed (:func:`mark`): the nodes are bucketed on a
    cubic grid of cell ``cell`` ≥ the largest radius, so a zone looks at 3 × 3 × 3 cells. Memory
    O(events + nodes) — a list of nodes per sample grew with samples × zone area (the fin loads
    sampled every 0.156 µs are ~4e5 events per fin, each zone ~1e3 nodes)."""

    ptr: np.ndarray
    """(nt + 1,) int64 offsets into the events"""
    centre: np.ndarray
    """zone centres (ne, 3) [m] (the load points, in the frame of ``x``)"""
    radius: np.ndarray
    """zone radii (ne,) [m]"""
    x: np.ndarray
    """owned node coordinates (n, 3) [m]"""
    lo: np.ndarray
    """(3,) lower corner of the bucket grid [m]"""
    cell: float
    """bucket edge [m]"""
    dims: np.ndarray
    """(3,) int64 buckets per axis"""
    bptr: np.ndarray
    """(nb + 1,) int64 offsets into ``bnodes`` per bucket (x fastest)"""
    bnodes: np.ndarray
    """(n,) int64 node indices sorted by bucket"""


def no_exclusion(nt: int) -> Exclusion:
    return exclusion_zones(np.zeros((0, 3)), np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros(0), nt)


def exclusion_radius(thickness: float, width: np.ndarray, factor: float) -> np.ndarray:
    """r_ex = factor × max(t, d) per event [m] (width d [m], shape (ne,))."""
    return factor * np.maximum(thickness, np.asarray(width, float))


def exclusion_zones(x_nodes: np.ndarray, sample: np.ndarray, points: np.ndarray,
                    radius: np.ndarray, nt: int) -> Exclusion:
    """The zones of the contact samples 0 … nt−1: a ball of ``radius`` (ne,) [m] around each
    contact point ``points`` (ne, 3) [m] (``sample`` (ne,): its sample index), over the nodes
    ``x_nodes`` (n, 3) [m]. O(events + nodes)."""
    sample = np.asarray(sample, np.int64)
    order = np.argsort(sample, kind="stable")
    ptr = np.zeros(nt + 1, np.int64)
    ptr[1:] = np.cumsum(np.bincount(sample, minlength=nt)[:nt])
    x = np.ascontiguousarray(x_nodes, dtype=float).reshape(-1, 3)
    radius = np.asarray(radius, float)
    lo = x.min(axis=0) if len(x) else np.zeros(3)
    extent = float((x.max(axis=0) - lo).max()) if len(x) else 0.0
    cell = max(float(radius.max(initial=0.0)), extent / 256.0, 1e-9)  # ≥ every radius; ≤ 256³ buckets
    idx = np.floor((x - lo) / cell).astype(np.int64)
    dims = idx.max(axis=0) + 1 if len(x) else np.ones(3, np.int64)
    lin = idx[:, 0] + dims[0] * (idx[:, 1] + dims[1] * idx[:, 2])
    bnodes = np.argsort(lin, kind="stable").astype(np.int64)
    bptr = np.zeros(int(np.prod(dims)) + 1, np.int64)
    bptr[1:] = np.cumsum(np.bincount(lin, minlength=int(np.prod(dims))))
    return Exclusion(ptr, np.ascontiguousarray(np.asarray(points, float).reshape(-1, 3)[order]),
                     np.ascontiguousarray(radius[order]), x, lo, cell, dims.astype(np.int64), bptr, bnodes)


@njit(cache=True)
def mark(Z, k0, k1, mask, value):
    """mask[node] = value for the nodes within a zone of the samples k0 … k1 − 1 (|x − c| ≤ r)."""
    for e in range(Z.ptr[max(k0, 0)], Z.ptr[min(k1, len(Z.ptr) - 1)]):
        c0, c1, c2 = Z.centre[e, 0], Z.centre[e, 1], Z.centre[e, 2]
        r2 = Z.radius[e] * Z.radius[e]
        gx = int(np.floor((c0 - Z.lo[0]) / Z.cell))
        gy = int(np.floor((c1 - Z.lo[1]) / Z.cell))
        gz = int(np.floor((c2 - Z.lo[2]) / Z.cell))
        for bz in range(max(gz - 1, 0), min(gz + 2, Z.dims[2])):
            for by in range(max(gy - 1, 0), min(gy + 2, Z.dims[1])):
                for bx in range(max(gx - 1, 0), min(gx + 2, Z.dims[0])):
                    b = bx + Z.dims[0] * (by + Z.dims[1] * bz)
                    for p in range(Z.bptr[b], Z.bptr[b + 1]):
                        i = Z.bnodes[p]
                        d0, d1, d2 = Z.x[i, 0] - c0, Z.x[i, 1] - c1, Z.x[i, 2] - c2
                        if d0 * d0 + d1 * d1 + d2 * d2 <= r2:
                            mask[i] = value


def zone_mask(Z: Exclusion, k0: int, k1: int) -> np.ndarray:
    """Boolean mask (n,) of the nodes within a zone of the samples k0 … k1 − 1."""
    m = np.zeros(len(Z.x), np.int8)
    mark(Z, k0, k1, m, 1)
    return m.astype(bool)


class Bearing(NamedTuple):
    peak_pa: float
    """largest bearing/contact stress over the events [Pa] (0 without events)"""
    time_s: float
    kind: str
    """"edge" (F/(d t)) or "face" (Hertz line contact), "" without events"""
    location_m: list | None
    force_n: float
    """|F| of that event [N]"""


def hertz_line_pressure(force_n: np.ndarray, diameter: np.ndarray, length: np.ndarray,
                        e_star: float) -> np.ndarray:
    """Peak Hertz pressure of a cylinder of ``diameter`` [m] pressed with ``force_n`` [N] on a
    flat over ``length`` [m] (Johnson, Contact Mechanics, Eq. 4.45): p_0 = √(P′E*/(πR)),
    P′ = F/L, R = d/2 [Pa]."""
    P = np.maximum(np.asarray(force_n, float), 0.0) / np.asarray(length, float)
    return np.sqrt(P * e_star / (math.pi * 0.5 * np.asarray(diameter, float)))


def contact_modulus(e_fin: float, nu_fin: float, e_rope: float) -> float:
    """E* [Pa] of the fin (E, ν) against the rope's transverse modulus (its ν taken 0)."""
    return 1.0 / ((1.0 - nu_fin ** 2) / e_fin + 1.0 / e_rope)


def bearing_stress(t: np.ndarray, points: np.ndarray, forces: np.ndarray, widths: np.ndarray,
                   edge_distance: np.ndarray, normal: np.ndarray, thickness: float,
                   e_star: float) -> Bearing:
    """Largest local contact stress over the events of one fin (module doc, item 2): events whose
    point lies within d/2 + t of the planform boundary (``edge_distance`` (ne,) [m]) bear on the
    edge, σ_b = |F| / (d t); the others press the face, Hertz p_0 with F_n = |F·n|. t (ne,) [s],
    points (ne, 3) [m], forces (ne, 3) [N], widths (ne,) [m]."""
    if len(t) == 0:
        return Bearing(0.0, 0.0, "", None, 0.0)
    widths = np.asarray(widths, float)
    fmag = np.linalg.norm(forces, axis=1)
    edge = np.asarray(edge_distance) <= 0.5 * widths + thickness
    s_edge = fmag / (widths * thickness)
    s_face = hertz_line_pressure(np.abs(forces @ np.asarray(normal, float)), widths, widths,
                                 e_star)
    s = np.where(edge, s_edge, s_face)
    k = int(np.argmax(s))
    return Bearing(float(s[k]), float(t[k]), "edge" if edge[k] else "face",
                   [float(v) for v in points[k]], float(fmag[k]))


def excluded_points(times: np.ndarray, t: float, sample: np.ndarray, points: np.ndarray,
                    radius: np.ndarray):
    """Load points (m, 3) [m] and radii (m,) [m] whose St-Venant zone is active at time ``t``
    [s]: the events of the two contact samples bracketing t (the load is interpolated linearly
    between them), as in the kernel's sampling."""
    n = len(times)
    if n == 0 or t < times[0] or t > times[-1]:
        return np.zeros((0, 3)), np.zeros(0)
    k = int(np.clip(np.searchsorted(times, t, side="right") - 1, 0, max(n - 2, 0)))
    sel = (sample == k) | (sample == k + 1)
    return points[sel], radius[sel]
