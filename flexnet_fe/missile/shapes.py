"""Contact geometry of the rigid missile, callable from numba ``@njit`` kernels.

Everything is in the missile body frame B (:mod:`flexnet_fe.frames`: origin at the nose apex,
``+x_b`` forward, body in ``x_b ∈ [-L, 0]``), SI units [m].

Shapes (the same parameters as the Gmsh meshes of :mod:`flexnet_fe.missile.mesh`)
    * part 0 ``body``: the cylinder of radius R from station L_n to L, closed by the flat base;
    * part 1 ``nose``: cone, tangent ogive or hemisphere from the apex to station L_n;
    * part 2+i: fin ``missile.fins[i]`` (wing_1..wing_4, rudder_1..rudder_4): a flat trapezoidal
      plate of its real thickness h (a prism ``trapezoid × [-h/2, h/2]`` along the fin normal).
      For contact the plate's root edge is extended into the body by δ = min(R/2, room on the
      cylinder) along the leading/trailing-edge lines, so that the plate's root face (which is
      glued to the body, not a free surface) is never reported as the nearest surface; outside
      the body the union of shapes is unchanged.

    Body and nose are one convex solid of revolution, described in the meridian half-plane
    (s = -x_b, r = sqrt(y_b² + z_b²)) by a profile of segments and circular arcs; the 3-D
    distance to a surface of revolution equals the 2-D distance to its profile in the point's meridian plane.

The scalar queries the collide kernel calls per contact point (``body_closest_scalar``,
``segment_body_closest``, ``segment_core_closest``, ``point_core_closest`` and their helpers) are
compiled with ``_nrt=False``: no reference counting of their array arguments, which cost more than
the queries themselves (``collide.kernel``, "Call cost"); they allocate nothing.

Packed arrays (``pack_shapes(missile) -> ShapeArrays``, a NamedTuple; pass ``*shapes`` to the
``@njit`` functions, in this order):
    prof_kind  int64 (m,)      0 segment, 1 circular arc
    prof_data  float64 (m, 6)  segment (s0, r0, s1, r1, 0, 0); arc (s_c, r_c, ρ, θ0, θ1, 0) [m, rad]
    prof_part  int64 (m,)      part id of each profile piece (0 body, 1 nose)
    fin_origin float64 (nf, 3) fin-frame origin (root leading edge on the body surface) [m]
    fin_axes   float64 (nf, 3, 3) rows e1 (span, outward), e2 (chord, leading→trailing), n = e1×e2
    fin_poly   float64 (nf, 4, 2) contact trapezoid in fin-plane coordinates (u, v) [m],
               counter-clockwise: root TE, root LE, tip LE, tip TE; edge k joins corner k and k+1:
               0 root (extended by δ into the body), 1 leading edge, 2 tip, 3 trailing edge
    fin_half_thickness float64 (nf,) h/2 [m]
    fin_part   int64 (nf,)     part id 2 + i
    fin_bound  float64 (nf, 4) bounding sphere of each contact plate: centre (3,) [m], radius [m]
               (lets the queries skip fins that cannot be nearest / cannot be touched)
    fin_core   float64 (nf, kc, 2) the rope-contact core: ``fin_poly`` with its tip corners
               rounded to the fin set's ``tip_corner_radius`` (``missile.planform``; the first
               fin_ncore[i] rows, counter-clockwise; equal to ``fin_poly`` for sharp corners).
               It lies inside ``fin_poly``, so bounds computed on ``fin_poly`` hold for it. Used
               by the rope contact (``segment_core_closest`` in the collide kernel); the point
               queries below keep the sharp prism of ``fin_poly``
    fin_ncore  int64 (nf,)     vertices of each fin's core

``@njit`` functions (usable inside other ``@njit`` code):

``closest_point(p, shapes) -> (d, normal, q, part)``
    p [m] (3,) a point in B. d [m]: signed distance to the missile's surface (negative inside;
    it is the minimum of the parts' own signed distances: outside all parts this is the exact
    distance to their union; inside, it is the depth in the part the point is deepest in, exact
    for a point inside one part only — e.g. a point inside the body within h/2 of a fin's plane
    near its root reports that fin's face). normal (3,): unit outward normal at the closest point
    (for a point off the surface, ±(p - q)/|p - q|, i.e. the direction that reduces the
    penetration). q [m] (3,): the closest surface point. part: int part id (0 body, 1 nose,
    2+i fin i). A point exactly on the axis gets its radial direction from +y_b (documented
    choice; any is correct there).

``segment_core_closest(a, b, fin_origin[i], fin_axes[i], fin_core[i, :fin_ncore[i]]) -> (dist, s, q_u, q_v, crossed)``
    Closest pair of a rope segment (a capsule's centre line) and a fin's core polygon (module
    section "capsule contact"); ``segment_body_closest(a, b, prof_kind, prof_data, prof_part)``
    the deepest / nearest point of a segment for the body of revolution.

Allocation-free variants for hot loops return the vectors as scalars:
``closest_point_scalar(p, shapes) -> (d, n_x, n_y, n_z, q_x, q_y, q_z, part)``,
``body_closest_scalar(p, prof_kind, prof_data, prof_part) -> (d, n_x, n_y, n_z, q_x, q_y, q_z,
part)``, ``fin_closest_scalar(p, fin_origin[i], ...) -> (d, n_x, n_y, n_z, q_x, q_y, q_z)``.

The parts separately (same outputs, for kernels with their own broad phase):
``body_closest_point(p, prof_kind, prof_data, prof_part) -> (d, normal, q, part)`` and
``fin_closest_point(p, fin_origin[i], fin_axes[i], fin_poly[i], fin_half_thickness[i])
-> (d, normal, q)``.

Python wrapper for many points at once (tests, plots): ``closest_points(points, shapes)``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from flexnet_fe.missile.geometry import Missile
from flexnet_fe.missile.planform import round_tip_corners

PART_BODY = 0
PART_NOSE = 1
FIN_PART_OFFSET = 2


class ShapeArrays(NamedTuple):
    """Packed contact shapes of one missile (see the module docstring for fields and units)."""

    prof_kind: np.ndarray
    prof_data: np.ndarray
    prof_part: np.ndarray
    fin_origin: np.ndarray
    fin_axes: np.ndarray
    fin_poly: np.ndarray
    fin_half_thickness: np.ndarray
    fin_part: np.ndarray
    fin_bound: np.ndarray
    fin_core: np.ndarray
    fin_ncore: np.ndarray


def part_names(missile: Missile) -> list[str]:
    """Names of the part ids: ``["body", "nose", fin names...]``."""
    return ["body", "nose"] + [f.name for f in missile.fins]


def _root_extension(missile: Missile, fin) -> float:
    """Depth δ [m] by which the contact plate's root edge is extended into the body (≥ 0):
    R/2, or less if the extended root would leave the cylinder [L_n, L]."""
    le_station = -fin.origin[0]
    uv = fin.uv
    slope_le = (uv[2, 1] - uv[1, 1]) / fin.span  # dv/du of the leading edge
    slope_te = (uv[3, 1] - uv[0, 1]) / fin.span
    delta = 0.5 * missile.radius
    # moving the root to u = -δ shifts the root LE station by -δ slope_le and the TE by -δ slope_te
    if slope_le > 0:
        delta = min(delta, (le_station - missile.nose_length) / slope_le)
    te_station = le_station + uv[0, 1]
    if slope_te < 0:
        delta = min(delta, (missile.length - te_station) / -slope_te)
    return max(delta, 0.0)


def pack_shapes(missile: Missile) -> ShapeArrays:
    """The contact shapes of ``missile`` as plain arrays for ``@njit`` code."""
    m = len(missile.profile)
    kind = np.empty(m, np.int64)
    data = np.zeros((m, 6))
    part = np.empty(m, np.int64)
    for i, prim in enumerate(missile.profile):
        kind[i] = int(prim.kind)
        data[i, : len(prim.data)] = prim.data
        part[i] = prim.part
    nf = len(missile.fins)
    origin = np.empty((nf, 3))
    axes = np.empty((nf, 3, 3))
    poly = np.empty((nf, 4, 2))
    half = np.empty(nf)
    fpart = np.empty(nf, np.int64)
    bound = np.empty((nf, 4))
    cores = []
    for i, fin in enumerate(missile.fins):
        origin[i] = fin.origin
        axes[i] = np.stack([fin.e1, fin.e2, fin.n])
        uv = np.array(fin.uv)
        delta = _root_extension(missile, fin)
        for root_k, tip_k in ((0, 3), (1, 2)):  # root TE along the TE line, root LE along the LE
            slope = (uv[tip_k, 1] - uv[root_k, 1]) / fin.span
            uv[root_k] = (-delta, uv[root_k, 1] - delta * slope)
        poly[i] = uv
        half[i] = 0.5 * fin.thickness
        fpart[i] = FIN_PART_OFFSET + i
        corners = fin.origin + uv[:, :1] * fin.e1 + uv[:, 1:] * fin.e2
        centre = corners.mean(axis=0)
        bound[i, :3] = centre
        bound[i, 3] = np.linalg.norm(corners - centre, axis=1).max() + half[i]
        cores.append(round_tip_corners(uv, fin.tip_corner_radius))
    ncore = np.array([len(c) for c in cores], np.int64)
    core = np.zeros((nf, int(ncore.max(initial=4)), 2))
    for i, c in enumerate(cores):
        core[i, :len(c)] = c
    return ShapeArrays(kind, data, part, origin, axes, poly, half, fpart, bound, core, ncore)


# ----------------------------------------------------------------------------- body of revolution


NOSE_CONES = 4
"""Tangent cones per nose arc in :func:`nose_cones` (bounds for the contact's broad phase)."""


def nose_cones(prof_kind: np.ndarray, prof_data: np.ndarray, n: int = NOSE_CONES) -> np.ndarray:
    """Cones that contain the body of revolution (n per profile arc): (nc, 2) rows (r0 [m], k [-])
    of the solids ρ ≤ r0 + k s (station s [m] from the apex, ρ [m] from the axis), each tangent to
    an arc at one of n stations strictly inside it. The body is convex, so its profile r(s) is
    concave and lies under every tangent line: each cone contains the whole body. In the
    meridian half-plane a cone is a half-plane, so a point's distance to it is at least
    (ρ − r0 − k s)/√(1 + k²) — a lower bound of its distance to the body that the collision's
    broad phase uses (``collide.kernel._clearance``) where the bounding cylinder is loose: around
    the nose. Arc rows: (s_c, r_c, radius, θ0, θ1), points (s_c + ρ cos θ, r_c + ρ sin θ), slope
    dr/ds = −cot θ (> 0 for θ in (π/2, π): a nose)."""
    rows = []
    for kind, d in zip(prof_kind, prof_data):
        if kind != 1:
            continue
        for i in range(n):
            th = d[3] + (d[4] - d[3]) * (i + 0.5) / n
            if not (0.5 * np.pi < th < np.pi):
                continue
            k = -np.cos(th) / np.sin(th)
            s_t, r_t = d[0] + d[2] * np.cos(th), d[1] + d[2] * np.sin(th)
            rows.append((r_t - k * s_t, k))
    return np.array(rows, dtype=np.float64).reshape(-1, 2)


@njit(cache=True, _nrt=False)
def _closest_on_segment_2d(ps, pr, s0, r0, s1, r1):
    """Closest point (s, r) on the segment (s0, r0)–(s1, r1) to (ps, pr)."""
    ds, dr = s1 - s0, r1 - r0
    ll = ds * ds + dr * dr
    t = ((ps - s0) * ds + (pr - r0) * dr) / ll
    t = min(max(t, 0.0), 1.0)
    return s0 + t * ds, r0 + t * dr


@njit(cache=True, _nrt=False)
def _closest_on_arc_2d(ps, pr, sc, rc, rho, th0, th1):
    """Closest point (s, r) on the arc of centre (sc, rc), radius rho, angles [th0, th1]."""
    th = np.arctan2(pr - rc, ps - sc)
    if th < 0.0:
        th += 2.0 * np.pi
    if th0 <= th <= th1 and (ps - sc) ** 2 + (pr - rc) ** 2 > 0.0:
        return sc + rho * np.cos(th), rc + rho * np.sin(th)
    s_a, r_a = sc + rho * np.cos(th0), rc + rho * np.sin(th0)
    s_b, r_b = sc + rho * np.cos(th1), rc + rho * np.sin(th1)
    if (ps - s_a) ** 2 + (pr - r_a) ** 2 <= (ps - s_b) ** 2 + (pr - r_b) ** 2:
        return s_a, r_a
    return s_b, r_b


@njit(cache=True, _nrt=False)
def _profile_radius(s, prof_kind, prof_data):
    """Body radius r(s) [m] at station s, or -1 where s is outside [0, L]."""
    for i in range(prof_kind.shape[0]):
        d = prof_data[i]
        if prof_kind[i] == 0:
            if d[2] > d[0] and d[0] <= s <= d[2]:
                return d[1] + (s - d[0]) * (d[3] - d[1]) / (d[2] - d[0])
        else:
            s_lo = d[0] + d[2] * np.cos(d[4])  # apex end of the arc
            s_hi = d[0] + d[2] * np.cos(d[3])
            if s_lo <= s <= s_hi:
                return d[1] + np.sqrt(max(d[2] * d[2] - (s - d[0]) ** 2, 0.0))
    return -1.0


@njit(cache=True, _nrt=False)
def _profile_normal_2d(i, qs, qr, prof_kind, prof_data):
    """Outward unit normal (n_s, n_r) of profile piece i at its point (qs, qr)."""
    d = prof_data[i]
    if prof_kind[i] == 0:
        ts, tr = d[2] - d[0], d[3] - d[1]
        ln = np.sqrt(ts * ts + tr * tr)
        return -tr / ln, ts / ln  # tangent (apex → base) rotated by +90°
    return (qs - d[0]) / d[2], (qr - d[1]) / d[2]


@njit(cache=True, _nrt=False)
def body_closest_scalar(p, prof_kind, prof_data, prof_part):
    """Allocation-free :func:`body_closest_point`: (d, n_x, n_y, n_z, q_x, q_y, q_z, part)."""
    s = -p[0]
    r = np.sqrt(p[1] * p[1] + p[2] * p[2])
    if r > 0.0:
        ay, az = p[1] / r, p[2] / r
    else:
        ay, az = 1.0, 0.0  # on the axis: meridian plane through +y_b
    best = np.inf
    best_i = 0
    bs, br = 0.0, 0.0
    for i in range(prof_kind.shape[0]):
        d = prof_data[i]
        if prof_kind[i] == 0:
            qs, qr = _closest_on_segment_2d(s, r, d[0], d[1], d[2], d[3])
        else:
            qs, qr = _closest_on_arc_2d(s, r, d[0], d[1], d[2], d[3], d[4])
        dist2 = (s - qs) ** 2 + (r - qr) ** 2
        if dist2 < best:
            best, best_i, bs, br = dist2, i, qs, qr
    dist = np.sqrt(best)
    r_prof = _profile_radius(s, prof_kind, prof_data)
    inside = r_prof >= 0.0 and r <= r_prof
    if dist > 1e-12:
        sign = -1.0 if inside else 1.0
        ns, nr = sign * (s - bs) / dist, sign * (r - br) / dist
    else:
        ns, nr = _profile_normal_2d(best_i, bs, br, prof_kind, prof_data)
    return ((-dist if inside else dist), -ns, nr * ay, nr * az, -bs, br * ay, br * az,
            prof_part[best_i])


@njit(cache=True)
def body_closest_point(p, prof_kind, prof_data, prof_part):
    """Signed distance [m], outward normal (3,), closest point (3,) [m] and part id (0 or 1) of
    the body of revolution for a point p [m] (3,) in B (see the module docstring)."""
    d, nx, ny, nz, qx, qy, qz, part = body_closest_scalar(p, prof_kind, prof_data, prof_part)
    return d, np.array([nx, ny, nz]), np.array([qx, qy, qz]), part


# ----------------------------------------------------------------------------- thin fin plates


@njit(cache=True)
def fin_closest_scalar(p, origin, axes, poly, half):
    """Allocation-free :func:`fin_closest_point`: (d, n_x, n_y, n_z, q_x, q_y, q_z) in B."""
    d0, d1, d2_ = p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]
    u = d0 * axes[0, 0] + d1 * axes[0, 1] + d2_ * axes[0, 2]
    v = d0 * axes[1, 0] + d1 * axes[1, 1] + d2_ * axes[1, 2]
    w = d0 * axes[2, 0] + d1 * axes[2, 1] + d2_ * axes[2, 2]
    # 2-D signed distance to the convex polygon: max of edge-line distances inside (exact),
    # distance to the nearest edge segment outside.
    nv_ = poly.shape[0]
    d2_in = -np.inf
    k_in = 0
    nu_in, nv_in = 0.0, 0.0
    d2_out = np.inf
    qu_out, qv_out = u, v
    for k in range(nv_):
        au, av = poly[k, 0], poly[k, 1]
        bu, bv = poly[(k + 1) % nv_, 0], poly[(k + 1) % nv_, 1]
        tu, tv = bu - au, bv - av
        ln = np.sqrt(tu * tu + tv * tv)
        nu, nv = tv / ln, -tu / ln
        dk = (u - au) * nu + (v - av) * nv
        if dk > d2_in:
            d2_in, k_in, nu_in, nv_in = dk, k, nu, nv
        qu, qv = _closest_on_segment_2d(u, v, au, av, bu, bv)
        dd = (u - qu) ** 2 + (v - qv) ** 2
        if dd < d2_out:
            d2_out, qu_out, qv_out = dd, qu, qv
    inside2 = d2_in <= 0.0
    dw = abs(w) - half
    sw = 1.0 if w >= 0.0 else -1.0
    if inside2 and dw <= 0.0:
        if dw >= d2_in:  # nearest: a face (top or bottom)
            qu_, qv_, qw_ = u, v, sw * half
            nlu, nlv, nlw = 0.0, 0.0, sw
            sd = dw
        else:  # nearest: a side face (edge k_in)
            qu_, qv_, qw_ = u - d2_in * nu_in, v - d2_in * nv_in, w
            nlu, nlv, nlw = nu_in, nv_in, 0.0
            sd = d2_in
    else:
        if inside2:
            qu_out, qv_out = u, v
        qu_, qv_, qw_ = qu_out, qv_out, min(max(w, -half), half)
        nlu, nlv, nlw = u - qu_, v - qv_, w - qw_
        sd = np.sqrt(nlu * nlu + nlv * nlv + nlw * nlw)
        if sd > 0.0:
            nlu, nlv, nlw = nlu / sd, nlv / sd, nlw / sd
        elif dw >= d2_in:  # on the surface to round-off: the normal of the face it lies on
            nlu, nlv, nlw = 0.0, 0.0, sw
        else:
            nlu, nlv, nlw = nu_in, nv_in, 0.0
    qx = origin[0] + qu_ * axes[0, 0] + qv_ * axes[1, 0] + qw_ * axes[2, 0]
    qy = origin[1] + qu_ * axes[0, 1] + qv_ * axes[1, 1] + qw_ * axes[2, 1]
    qz = origin[2] + qu_ * axes[0, 2] + qv_ * axes[1, 2] + qw_ * axes[2, 2]
    nx = nlu * axes[0, 0] + nlv * axes[1, 0] + nlw * axes[2, 0]
    ny = nlu * axes[0, 1] + nlv * axes[1, 1] + nlw * axes[2, 1]
    nz = nlu * axes[0, 2] + nlv * axes[1, 2] + nlw * axes[2, 2]
    return sd, nx, ny, nz, qx, qy, qz


@njit(cache=True)
def fin_closest_point(p, origin, axes, poly, half):
    """Signed distance [m], outward normal (3,), closest point (3,) [m] of one fin plate
    (a convex prism: ``poly`` (4, 2) in the fin plane × [-half, half] along the normal)."""
    sd, nx, ny, nz, qx, qy, qz = fin_closest_scalar(p, origin, axes, poly, half)
    return sd, np.array([nx, ny, nz]), np.array([qx, qy, qz])


# ----------------------------------------------------------------------------- whole missile


@njit(cache=True)
def closest_point_scalar(p, shapes):
    """Allocation-free :func:`closest_point`: (d, n_x, n_y, n_z, q_x, q_y, q_z, part)."""
    d, nx, ny, nz, qx, qy, qz, part = body_closest_scalar(p, shapes.prof_kind, shapes.prof_data, shapes.prof_part)
    fin_bound = shapes.fin_bound
    for i in range(shapes.fin_origin.shape[0]):
        # |p - c| - r_bound is a lower bound of the plate's distance: skip plates that cannot win
        dc = np.sqrt((p[0] - fin_bound[i, 0]) ** 2 + (p[1] - fin_bound[i, 1]) ** 2
                     + (p[2] - fin_bound[i, 2]) ** 2)
        if dc - fin_bound[i, 3] >= d:
            continue
        di, mx, my, mz, sx, sy, sz = fin_closest_scalar(p, shapes.fin_origin[i], shapes.fin_axes[i],
                                                        shapes.fin_poly[i], shapes.fin_half_thickness[i])
        if di < d:
            d, nx, ny, nz, qx, qy, qz, part = di, mx, my, mz, sx, sy, sz, shapes.fin_part[i]
    return d, nx, ny, nz, qx, qy, qz, part


@njit(cache=True)
def closest_point(p, shapes):
    """(signed distance [m], outward normal (3,), closest surface point [m] (3,), part id) of the
    whole missile (``shapes``: :class:`ShapeArrays`) for a point p [m] (3,) in B; the part with
    the smallest signed distance wins."""
    d, nx, ny, nz, qx, qy, qz, part = closest_point_scalar(p, shapes)
    return d, np.array([nx, ny, nz]), np.array([qx, qy, qz]), part


# ----------------------------------------------------------------------------- vectorised wrappers


@njit(cache=True)
def _closest_points_kernel(pts, shapes, d, nrm, q, part):
    for k in range(pts.shape[0]):
        dk, nk, qk, pk = closest_point(pts[k], shapes)
        d[k], nrm[k], q[k], part[k] = dk, nk, qk, pk


def closest_points(points: np.ndarray, shapes: ShapeArrays):
    """Vectorised :func:`closest_point`: points [m] (n, 3) in B -> signed distances [m] (n,),
    normals (n, 3), closest points [m] (n, 3), part ids (n,) int64."""
    pts = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    n = pts.shape[0]
    d, nrm, q, part = np.empty(n), np.empty((n, 3)), np.empty((n, 3)), np.empty(n, np.int64)
    _closest_points_kernel(pts, shapes, d, nrm, q, part)
    return d, nrm, q, part


# ----------------------------------------------------------------------------- capsule contact
# A rope segment is a capsule: the segment a–b [m] swept by a sphere of the rope radius. A fin is
# a rounded plate: its planform polygon (the "core", in the fin's mid-plane, root extended into
# the body as ``fin_poly``) swept by a sphere of the half-thickness h/2. The body of revolution is
# used as it is. The gap of a capsule and a part is then (distance between the segment and the
# part's core) − the radii; the closest pair (p on the segment at parameter s, q on the core)
# gives the normal n = (p − q)/|p − q|, which turns continuously from face to edge to corner
# wherever the pair is unique (the closest-point map of a convex set is continuous).


@njit(cache=True, _nrt=False)
def _clamp01(t):
    return 0.0 if t < 0.0 else (1.0 if t > 1.0 else t)


@njit(cache=True, _nrt=False)
def _segment_edge_2d(ra, rb, cu, cv, du, dv):
    """Closest points of the 3-D segment a–b (ra, rb [m] (3,), fin coordinates u, v, w) and the
    in-plane edge (cu, cv)–(du, dv) (w = 0). Returns (squared distance [m²], s on a–b, t on c–d) (Ericson, Real-Time Collision Detection
    §5.1.9; a parallel pair returns one of its closest pairs)."""
    au, av, aw = ra[0], ra[1], ra[2]
    d1u, d1v, d1w = rb[0] - au, rb[1] - av, rb[2] - aw
    d2u, d2v = du - cu, dv - cv
    ru, rv, rw = au - cu, av - cv, aw
    a = d1u * d1u + d1v * d1v + d1w * d1w
    e = d2u * d2u + d2v * d2v
    f = d2u * ru + d2v * rv
    if a <= 1e-30:
        s = 0.0
        t = _clamp01(f / e)
    else:
        c = d1u * ru + d1v * rv + d1w * rw
        b = d1u * d2u + d1v * d2v
        den = a * e - b * b
        s = _clamp01((b * f - c * e) / den) if den > 1e-30 * a * e else 0.0
        t = (b * s + f) / e
        if t < 0.0:
            t = 0.0
            s = _clamp01(-c / a)
        elif t > 1.0:
            t = 1.0
            s = _clamp01((b - c) / a)
    pu, pv, pw = au + s * d1u, av + s * d1v, aw + s * d1w
    qu, qv = cu + t * d2u, cv + t * d2v
    return (pu - qu) ** 2 + (pv - qv) ** 2 + pw * pw, s, t


@njit(cache=True, _nrt=False)
def _inside_polygon(u, v, poly):
    """Is (u, v) inside (or on) the counter-clockwise convex polygon ``poly`` (k, 2)?"""
    k = poly.shape[0]
    for i in range(k):
        au, av = poly[i, 0], poly[i, 1]
        bu, bv = poly[(i + 1) % k, 0], poly[(i + 1) % k, 1]
        if (u - au) * (bv - av) - (v - av) * (bu - au) > 0.0:
            return False
    return True


@njit(cache=True, _nrt=False)
def _to_fin(p, origin, axes):
    """Fin coordinates (u, v, w) [m] of the point p [m] (3,) in B: ((p − origin)·e1, ·e2, ·n)."""
    return ((p[0] - origin[0]) * axes[0, 0] + (p[1] - origin[1]) * axes[0, 1] + (p[2] - origin[2]) * axes[0, 2],
            (p[0] - origin[0]) * axes[1, 0] + (p[1] - origin[1]) * axes[1, 1] + (p[2] - origin[2]) * axes[1, 2],
            (p[0] - origin[0]) * axes[2, 0] + (p[1] - origin[1]) * axes[2, 1] + (p[2] - origin[2]) * axes[2, 2])


@njit(cache=True, _nrt=False)
def segment_core_closest(a, b, origin, axes, poly):
    """Closest pair of the segment a–b [m] (3,) in B and a fin's core polygon (its planform in
    the mid-plane). origin (3,), axes (3, 3) rows e1, e2, n, poly (k, 2) counter-clockwise in
    (u, v) [m] (``ShapeArrays`` fields of one fin).

    Returns (dist [m] ≥ 0, s ∈ [0, 1] on the segment, q_u, q_v [m] fin coordinates of the
    closest core point, crossed). crossed = True when the segment passes through the core
    (dist = 0; s and q are the crossing). Exact: the closest pair of a segment and a convex
    polygon is a crossing, an end point over the polygon, or a segment–edge pair."""
    ra = _to_fin(a, origin, axes)  # (u, v, w) tuples: no allocation in the kernel's narrow phase
    rb = _to_fin(b, origin, axes)
    aw, bw = ra[2], rb[2]
    if (aw <= 0.0 <= bw or bw <= 0.0 <= aw) and aw != bw:
        sc = aw / (aw - bw)
        cu = ra[0] + sc * (rb[0] - ra[0])
        cv = ra[1] + sc * (rb[1] - ra[1])
        if _inside_polygon(cu, cv, poly):
            return 0.0, sc, cu, cv, True
    best = np.inf
    bs, bu, bv = 0.0, 0.0, 0.0
    if _inside_polygon(ra[0], ra[1], poly):
        best, bs, bu, bv = aw * aw, 0.0, ra[0], ra[1]
    if _inside_polygon(rb[0], rb[1], poly) and bw * bw < best:
        best, bs, bu, bv = bw * bw, 1.0, rb[0], rb[1]
    k = poly.shape[0]
    for i in range(k):
        cu, cv = poly[i, 0], poly[i, 1]
        du, dv = poly[(i + 1) % k, 0], poly[(i + 1) % k, 1]
        d2, s, t = _segment_edge_2d(ra, rb, cu, cv, du, dv)
        if d2 < best:
            best, bs, bu, bv = d2, s, cu + t * (du - cu), cv + t * (dv - cv)
    return np.sqrt(best), bs, bu, bv, best == 0.0


@njit(cache=True, _nrt=False)
def point_core_closest(p, origin, axes, poly):
    """Closest point of a fin's core polygon to the point p [m] (3,) in B (``segment_core_closest``
    for a point). Returns (dist [m] ≥ 0, q_u, q_v [m] fin coordinates of the closest core point):
    the projection when it lies in the polygon, else the nearest point of its boundary."""
    u, v, w = _to_fin(p, origin, axes)
    if _inside_polygon(u, v, poly):
        return abs(w), u, v
    best, bu, bv = np.inf, u, v
    k = poly.shape[0]
    for i in range(k):
        qu, qv = _closest_on_segment_2d(u, v, poly[i, 0], poly[i, 1], poly[(i + 1) % k, 0], poly[(i + 1) % k, 1])
        d2 = (u - qu) ** 2 + (v - qv) ** 2
        if d2 < best:
            best, bu, bv = d2, qu, qv
    return np.sqrt(best + w * w), bu, bv


@njit(cache=True, _nrt=False)
def segment_body_closest(a, b, prof_kind, prof_data, prof_part, cutoff=np.inf):
    """Point of the segment a–b [m] (3,) in B deepest in (or nearest to) the body of revolution.

    The body's signed distance d(p) is convex (convex solid), so along the segment
    φ(s) = d(a + s (b − a)) is convex with derivative φ'(s) = n(p(s))·(b − a) (n the outward
    normal of the closest surface point). Its minimum is at an end where φ' does not change
    sign, otherwise at the root of φ', found by the Illinois (modified regula falsi) method
    to |Δs| < 1e-9 (at most 60 evaluations; typically 5–10).

    A convex φ lies above its tangents at both ends, so max(φ(0) + φ'(0) s, φ(1) − φ'(1) (1 − s))
    has its minimum L ≤ min φ. When L ≥ ``cutoff`` [m] the search is skipped and L is
    returned as d (a lower bound, not the distance; s and the rest are those of the nearer end):
    a caller that only needs to know whether d < cutoff (the contact's rope radius) gets the same
    answer for a fraction of the cost.

    Returns (d [m] signed, s, n_x, n_y, n_z outward normal, q_x, q_y, q_z [m] surface point,
    part id 0 or 1)."""
    ab0, ab1, ab2 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    d0, nx0, ny0, nz0, qx0, qy0, qz0, pt0 = body_closest_scalar(a, prof_kind, prof_data, prof_part)
    g0 = nx0 * ab0 + ny0 * ab1 + nz0 * ab2
    if g0 >= 0.0:
        return d0, 0.0, nx0, ny0, nz0, qx0, qy0, qz0, pt0
    d1, nx1, ny1, nz1, qx1, qy1, qz1, pt1 = body_closest_scalar(b, prof_kind, prof_data, prof_part)
    g1 = nx1 * ab0 + ny1 * ab1 + nz1 * ab2
    if g1 <= 0.0:
        return d1, 1.0, nx1, ny1, nz1, qx1, qy1, qz1, pt1
    # tangents' crossing: d0 + g0 s = d1 + g1 (s − 1), g0 < 0 < g1
    lower = d0 + g0 * (d1 - g1 - d0) / (g0 - g1)
    if lower >= cutoff:
        if d0 <= d1:
            return lower, 0.0, nx0, ny0, nz0, qx0, qy0, qz0, pt0
        return lower, 1.0, nx1, ny1, nz1, qx1, qy1, qz1, pt1
    s0, s1 = 0.0, 1.0
    side = 0
    sm = 0.5
    dm, nxm, nym, nzm, qxm, qym, qzm, ptm = d0, nx0, ny0, nz0, qx0, qy0, qz0, pt0
    for _ in range(60):
        sm = (s0 * g1 - s1 * g0) / (g1 - g0)
        if not (s0 < sm < s1):
            sm = 0.5 * (s0 + s1)
        p = (a[0] + sm * ab0, a[1] + sm * ab1, a[2] + sm * ab2)  # a tuple: no allocation per iteration
        dm, nxm, nym, nzm, qxm, qym, qzm, ptm = body_closest_scalar(p, prof_kind, prof_data, prof_part)
        gm = nxm * ab0 + nym * ab1 + nzm * ab2
        if gm > 0.0:
            s1, g1 = sm, gm
            if side == 1:
                g0 *= 0.5
            side = 1
        elif gm < 0.0:
            s0, g0 = sm, gm
            if side == -1:
                g1 *= 0.5
            side = -1
        else:
            break
        if s1 - s0 < 1e-9:
            break
    return dm, sm, nxm, nym, nzm, qxm, qym, qzm, ptm
