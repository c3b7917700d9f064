"""Rope subdivision near the contact: ``[collide] rope_split`` / ``rope_split_margin`` along the
path, then ``fin_piece_length`` / ``fin_split_margin`` at the fins.

The deployed net's mesh is as coarse as the deploy needs (paper: 0.1 m bars), but the rope–fin
contact resolves a rope only at its nodes' mass: a rope bar draped over a fin is one straight
spring whose two end masses carry the whole bar. The collision headlines depend on that (docs/
collide_convergence.md: radar × traction Δv −35 % from k = 1 to 2). Two refinements, applied in
this order at collision start:

1. :func:`split_near_path` splits every rope segment whose two end nodes lie within ``margin``
   [m] of the missile's swept volume — the cylinder of the missile's bounding radius r_max (fins
   included) around the flight path through the aim point — into ``k`` equal segments;
2. :func:`refine_near_fins` cuts the part of every segment whose capsule passes within
   ``fin_split_margin`` of a fin's strip — the fin's root-to-tip trace swept along the path — into
   equal pieces of at most ``fin_piece_length``. A rope on a fin's rounded edge (radius r + h/2)
   needs pieces of about a third of that radius (benchmarks/collide_edge_lab.py), far finer than
   the body needs; cutting only where a fin passes costs a fraction of cutting the whole swept
   disk that fine, and it also reaches the long segments (rotary nets: up to 2.8 m) whose ends lie
   far outside the path, which rule 1 leaves whole. The strips start at the axis: rope the nose
   meets inside the body radius is pushed out radially and meets the fins at their roots.

How a segment is cut (:func:`split_at`, pieces of fractions f_j of the segment, Σ f_j = 1):

* new nodes on the chord of the held segment (the held net is straight between its nodes), at rest;
  their reference positions ``x0`` likewise on the chord of the model's reference segment;
* each piece keeps E·A (the rope's section); rest length and LINK167 slack offset are scaled by
  f_j, so the chain has the segment's rest length, slack and axial stiffness EA/l0;
* the rope mass ρ A l0 of the segment (Eq. (2) lumping, half to each end) is re-lumped piece by
  piece: half of f_j ρ A l0 to each end of piece j (equal pieces: each end node keeps 1/(2k),
  each new node 1/k); concentrated masses stay where they are. Total mass, centre of mass and
  (at rest) momentum are unchanged;
* dashpots (Eq. (4)), by the rope's ``damping_law`` — the same rule the net builder uses for
  ``net.subdivisions`` (``net.topology._rope_segments``), so a split at collision start and a finer
  deploy mesh make the same rope: ``"segment"`` (default, the paper's per-segment law) gives every
  piece c = 2ζ√(μK) from its own stiffness EA/(f_j l0) and its end nodes' masses after re-lumping
  (the segments left whole keep theirs); ``"material"`` keeps the rope's viscosity, the dashpots in
  series making the segment's dashpot: c_piece = c_segment / f_j (k c for equal pieces).

Hub links (rotary nets) are not split: their rest length is measured from the hub centre.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from flexnet_fe.collide.crop import free_nodes
from flexnet_fe.collide.scene import HeldNet, missile_attitude, shape_bbox
from flexnet_fe.net.topology import rope_area, segment_damping, segment_stiffness


def near_path_segments(x: np.ndarray, springs: np.ndarray, hub_link: np.ndarray, aim: np.ndarray,
                       direction: np.ndarray, radius: float) -> np.ndarray:
    """Indices (s,) int64 of the segments (springs (m, 2)) whose two end nodes (x [m] (n, 3)) are
    within ``radius`` [m] of the line through ``aim`` [m] (3,) along unit ``direction`` (3,);
    hub links (hub_link (m,) bool) excluded."""
    near = free_nodes(x, aim, direction, radius)
    return np.flatnonzero(near[springs[:, 0]] & near[springs[:, 1]] & ~hub_link)


def _cut_points(xa: np.ndarray, xb: np.ndarray, cuts: list[np.ndarray]) -> np.ndarray:
    """The points at the chord fractions ``cuts[i]`` (interior, increasing) of each chord a→b
    (xa, xb [m] (s, 3)), in segment order, shape (Σ len(cuts[i]), 3)."""
    reps = np.array([c.size for c in cuts], dtype=np.int64)
    frac = np.concatenate(cuts)[:, None]
    return np.repeat(xa, reps, axis=0) + frac * np.repeat(xb - xa, reps, axis=0)


def split_at(net: HeldNet, idx: np.ndarray, cuts: list[np.ndarray]) -> HeldNet:
    """``net`` with each segment ``idx[i]`` (s,) int64 cut at the chord fractions ``cuts[i]``
    (interior points of (0, 1), increasing): piece j spans the fraction f_j of its segment
    (module docstring: chord nodes, E·A kept, rest length and slack offset × f_j, dashpot by
    the rope's damping law (:func:`_piece_damping`), the segment's rope mass ρ A l0 re-lumped piece by piece, half of
    each piece's f_j ρ A l0 to each of its ends; total mass and centre of mass unchanged). The new
    nodes are appended after the old ones (old node ids unchanged); the pieces replace their
    segments at the end of the segment list, in segment order."""
    n_cut = np.array([c.size for c in cuts], dtype=np.int64)
    if idx.size == 0 or not n_cut.any():
        return net
    m = net.model
    a, b = m.springs[idx, 0], m.springs[idx, 1]
    frac = [np.diff(np.concatenate([[0.0], c, [1.0]])) for c in cuts]  # piece fractions f_j
    f_all = np.concatenate(frac)
    seg_mass = net.rope.density * rope_area(net.rope.diameter) * m.rest_length[idx]
    mass = np.array(m.mass, dtype=np.float64)
    np.add.at(mass, a, -0.5 * seg_mass * (1.0 - np.array([f[0] for f in frac])))  # end a keeps f_1 / 2
    np.add.at(mass, b, -0.5 * seg_mass * (1.0 - np.array([f[-1] for f in frac])))  # end b keeps f_n / 2
    n_new = int(n_cut.sum())
    new_id = m.n_nodes + np.arange(n_new)
    start = np.concatenate([[0], np.cumsum(n_cut)])
    chains = [np.concatenate([[a[i]], new_id[start[i]:start[i + 1]], [b[i]]]) for i in range(idx.size)]
    pieces = np.concatenate([np.column_stack([c[:-1], c[1:]]) for c in chains])
    new_mass = np.concatenate([0.5 * seg_mass[i] * (f[:-1] + f[1:]) for i, f in enumerate(frac)])
    keep = np.setdiff1d(np.arange(m.n_springs), idx)
    n_piece = n_cut + 1

    def per_piece(arr, scale=None):
        arr = np.asarray(arr)
        rep = np.repeat(arr[idx], n_piece, axis=0)
        return np.concatenate([arr[keep], rep if scale is None else rep * scale])

    all_mass = np.concatenate([mass, new_mass])
    model = dataclasses.replace(
        m, x0=np.concatenate([m.x0, _cut_points(m.x0[a], m.x0[b], cuts)]),
        v0=np.concatenate([m.v0, np.zeros((n_new, 3))]), mass=all_mass,
        springs=np.concatenate([m.springs[keep], pieces]).astype(np.int64),
        rest_length=per_piece(m.rest_length, f_all), stiffness_ea=per_piece(m.stiffness_ea),
        damping=np.concatenate([m.damping[keep], _piece_damping(net.rope, idx, n_piece, f_all, m, all_mass,
                                                                 pieces)]),
        slack_offset=per_piece(m.slack_offset, f_all),
        diameter=per_piece(m.diameter), drag_free=np.concatenate([m.drag_free, np.zeros(n_new, dtype=bool)]),
        hub_link=per_piece(m.hub_link), anchor_angle=per_piece(m.anchor_angle))
    return dataclasses.replace(net, model=model, x=np.concatenate([net.x, _cut_points(net.x[a], net.x[b], cuts)]),
                               rest_length=per_piece(net.rest_length, f_all))


def _piece_damping(rope, idx: np.ndarray, n_piece: np.ndarray, f_all: np.ndarray, model, mass: np.ndarray,
                   pieces: np.ndarray) -> np.ndarray:
    """Dashpot coefficients [N s/m] (p,) of the pieces (p, 2) of the split segments ``idx`` (s,) of
    ``model``, Eq. (4) read by ``rope.damping_law``; n_piece (s,) the piece counts, f_all (p,) the
    pieces' fractions of their segments, mass (n,) [kg] the node masses after re-lumping.
    "segment": c = 2ζ√(μK), K = EA/(f l0), μ the reduced mass of the piece's end nodes
    (``net.topology.segment_damping``); "material": c_segment / f (dashpots in series)."""
    if rope.damping_law == "material":
        return np.repeat(model.damping[idx], n_piece) / f_all
    stiffness = segment_stiffness(np.repeat(model.stiffness_ea[idx], n_piece),
                                  np.repeat(model.rest_length[idx], n_piece) * f_all)
    return segment_damping(stiffness, mass[pieces[:, 0]], mass[pieces[:, 1]], rope.damping_ratio)


def split_segments(net: HeldNet, idx: np.ndarray, k: int) -> HeldNet:
    """``net`` with the segments ``idx`` (s,) int64 each split into ``k`` ≥ 1 equal pieces
    (:func:`split_at` at the fractions j/k)."""
    if k == 1:
        return net
    return split_at(net, idx, [np.arange(1, k) / k] * idx.size)


def split_near_path(net: HeldNet, missile, cfg) -> HeldNet:
    """The held net with every rope segment within ``cfg.rope_split_margin`` [m] of the missile's
    swept volume (bounding radius r_max around the path through ``cfg.aim_point`` along the flight
    direction of ``cfg.incidence_angle``/``roll_angle``) split into ``cfg.rope_split`` pieces
    (:func:`split_segments`; ``rope_split = 1`` returns ``net`` itself)."""
    k = int(cfg.rope_split)
    if k == 1:
        return net
    d = missile_attitude(cfg.incidence_angle, cfg.roll_angle)[:, 0]
    aim = np.array([cfg.aim_point[0], cfg.aim_point[1], 0.0])
    radius = float(shape_bbox(missile)[2]) + cfg.rope_split_margin
    idx = near_path_segments(net.x, net.model.springs, np.asarray(net.model.hub_link, dtype=bool), aim, d, radius)
    return split_segments(net, idx, k)


def _disk_interval(a: np.ndarray, u: np.ndarray, c: np.ndarray, d: float) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) (s,) of the t where the point a + t u (a, u (s, 2)) is within d [m] of c (2,);
    lo > hi where never."""
    w = a - c
    qa = np.einsum("ij,ij->i", u, u)
    qb = np.einsum("ij,ij->i", u, w)
    disc = qb * qb - qa * (np.einsum("ij,ij->i", w, w) - d * d)
    root = np.sqrt(np.maximum(disc, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        lo, hi = (-qb - root) / qa, (-qb + root) / qa
    empty = (disc < 0.0) | (qa == 0.0)
    return np.where(empty, np.inf, lo), np.where(empty, -np.inf, hi)


def _slab_interval(p0: np.ndarray, dp: np.ndarray, lo_v: float, hi_v: float) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) (s,) of the t where p0 + t dp (s,) lies in [lo_v, hi_v]; all t when dp = 0 and
    p0 is inside, none (lo > hi) when outside."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t1, t2 = (lo_v - p0) / dp, (hi_v - p0) / dp
    inside = (p0 >= lo_v) & (p0 <= hi_v)
    flat = dp == 0.0
    lo = np.where(flat, np.where(inside, -np.inf, np.inf), np.minimum(t1, t2))
    hi = np.where(flat, np.where(inside, np.inf, -np.inf), np.maximum(t1, t2))
    return lo, hi


def stadium_interval(a: np.ndarray, u: np.ndarray, f0: np.ndarray, f1: np.ndarray,
                     d: float) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) (s,) of the t where a + t u (a, u [m] (s, 2)) is within d [m] of the plane segment
    f0–f1 [m] (2,): the line meets the stadium (segment ⊕ disk of radius d) — a convex set, so
    the t form one interval, the union of the line's intervals in its two end disks and its
    rectangle. lo > hi where the line misses it."""
    e = f1 - f0
    length = float(np.hypot(*e))
    e = e / length
    nrm = np.array([-e[1], e[0]])
    rel = a - f0
    lo_s, hi_s = _slab_interval(rel @ e, u @ e, 0.0, length)
    lo_n, hi_n = _slab_interval(rel @ nrm, u @ nrm, -d, d)
    lo_r, hi_r = np.maximum(lo_s, lo_n), np.minimum(hi_s, hi_n)
    lo_0, hi_0 = _disk_interval(a, u, f0, d)
    lo_1, hi_1 = _disk_interval(a, u, f1, d)
    los, his = np.stack([lo_r, lo_0, lo_1]), np.stack([hi_r, hi_0, hi_1])
    hit = los <= his
    return np.where(hit, los, np.inf).min(axis=0), np.where(hit, his, -np.inf).max(axis=0)


def fin_strips(missile) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """Each fin's strip in the plane across the flight path: the path sweeps the fin's planform
    (a plate in a plane through the missile axis) into a strip whose cross-section is a plane
    segment along the fin's radial line, here taken from the AXIS to the tip radius — rope that
    the nose meets inside the body radius is pushed out radially (its angle kept) and reaches the
    fin's root there. Returns [(f0 = (0, 0), f1 = the tip's (y_b, z_b) [m] (2,), half-thickness
    [m])]."""
    out = []
    for fin in missile.fins:
        yz = np.asarray(fin.corners)[:, 1:]
        tip = yz[int(np.argmax(np.hypot(yz[:, 0], yz[:, 1])))]
        out.append((np.zeros(2), tip.copy(), 0.5 * fin.thickness))
    return out


def _merge(intervals: list[tuple[float, float]], gap: float = 0.0) -> list[tuple[float, float]]:
    """Sorted intervals, those less than ``gap`` apart merged."""
    out: list[list[float]] = []
    for lo, hi in sorted(intervals):
        if out and lo <= out[-1][1] + gap:
            out[-1][1] = max(out[-1][1], hi)
        else:
            out.append([lo, hi])
    return [(lo, hi) for lo, hi in out]


def _cuts_in(intervals: list[tuple[float, float]], length: float, piece: float) -> np.ndarray:
    """Interior cut fractions of a segment of ``length`` [m] that divide each interval (fractions
    of the segment) into equal pieces no longer than ``piece`` [m] (interval ends included as
    cuts, 0 and 1 excluded). No piece is made shorter than half of ``piece`` only because an
    interval was short or near an end or another interval: intervals are first grown to at least
    ``piece``, snapped to a segment end less than ``piece`` away and merged across gaps shorter
    than ``piece`` (a light node would shorten the collision's time step, ``collide.timestep``)."""
    h = piece / length
    grown = []
    for lo, hi in intervals:
        pad = max(0.0, 0.5 * (h - (hi - lo)))
        lo, hi = lo - pad, hi + pad
        grown.append((0.0 if lo < h else lo, 1.0 if hi > 1.0 - h else hi))
    cuts = [np.linspace(lo, hi, max(1, math.ceil((hi - lo) / h)) + 1) for lo, hi in _merge(grown, h)]
    c = np.unique(np.concatenate(cuts))
    return c[(c > 1e-12) & (c < 1.0 - 1e-12)]


def fin_strip_cuts(net: HeldNet, missile, cfg) -> tuple[np.ndarray, list[np.ndarray]]:
    """(idx (s,) int64, cuts): the segments (hub links excluded, and those no cut divides) whose capsule passes within
    ``cfg.fin_split_margin`` [m] of a fin's strip (:func:`fin_strips`, in the plane across the
    path through ``cfg.aim_point``), and for each the cut fractions that divide the part of it
    within that distance into equal pieces of at most ``cfg.fin_piece_length`` [m] (length: the
    larger of the held chord and the rest length). The test is on the held positions: rope that
    moves into a strip only during the impact is caught by the edge-resolution guard
    (``simulate.edge_resolution``)."""
    rot = missile_attitude(cfg.incidence_angle, cfg.roll_angle)
    aim = np.array([cfg.aim_point[0], cfg.aim_point[1], 0.0])
    m = net.model
    yz = (net.x - aim) @ rot[:, 1:]  # (n, 2): (y_b, z_b) of every node
    p, q = m.springs[:, 0], m.springs[:, 1]
    a, u = yz[p], yz[q] - yz[p]
    ok = ~np.asarray(m.hub_link, dtype=bool)
    found: dict[int, list[tuple[float, float]]] = {}
    for f0, f1, half in fin_strips(missile):
        lo, hi = stadium_interval(a, u, f0, f1, cfg.fin_split_margin + half + 0.5 * net.rope.diameter)
        lo, hi = np.maximum(lo, 0.0), np.minimum(hi, 1.0)
        for i in np.flatnonzero(ok & (lo < hi)):
            found.setdefault(int(i), []).append((float(lo[i]), float(hi[i])))
    idx = np.array(sorted(found), dtype=np.int64)
    length = np.maximum(np.linalg.norm(net.x[q[idx]] - net.x[p[idx]], axis=1), net.rest_length[idx])
    cuts = [_cuts_in(found[int(i)], float(L), cfg.fin_piece_length) for i, L in zip(idx, length)]
    cut = np.array([c.size > 0 for c in cuts], dtype=bool)  # a segment shorter than a piece stays whole
    return idx[cut], [c for c, keep in zip(cuts, cut) if keep]


def refine_near_fins(net: HeldNet, missile, cfg) -> HeldNet:
    """The held net with the rope near the fins' strips cut into pieces of at most
    ``cfg.fin_piece_length`` (:func:`fin_strip_cuts`, :func:`split_at`); ``net`` itself when
    ``cfg.fin_piece_length`` is None."""
    if cfg.fin_piece_length is None:
        return net
    idx, cuts = fin_strip_cuts(net, missile, cfg)
    return split_at(net, idx, cuts)
