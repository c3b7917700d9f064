"""The compiled collision loop: ``advance(model, state, n_steps, dt)`` (data in ``collide.model``);
``advance_kept`` with the loop's scratch kept from call to call (``new_work``).

Per step (symplectic Euler for the net nodes and the rigid missile, ``rigid_body.rigid_step``):

1. rope forces, Eq. (1)–(4), with the package's one segment mapper ``net.forces.spring_force``;
   a segment whose elastic stretch exceeds its breaking stretch is removed (rope failure), its
   elastic and contact energy booked as released;
2. capsule contact (``missile.shapes``): every rope segment is a capsule of the rope radius r,
   every fin a rounded plate (core polygon swept by its half-thickness h/2), the body of
   revolution as it is. For each (segment, part) pair the closest pair (p on the segment at
   parameter s, q on the part's core) gives the gap g = |p − q| − r − h/2 (body: its signed
   distance − r), the penetration δ = −g and the normal n = (p − q)/|p − q| (body: outward
   surface normal). The elastic force derives from the potential U(δ) = K δ^(m+1)/(m+1)
   (Eq. (28), K from Eq. (30) per part kind); because p minimises the distance over the segment,
   ∂U/∂x_i = −(1 − s) F n and ∂U/∂x_j = −s F n (envelope theorem), so applying (1 − s, s) × F n
   to the nodes and −F n at q to the missile (with its torque) is exactly the gradient of the
   stored energy: the contact neither creates nor loses energy beyond the step error. That is
   the segment law (``collide.contact_law = "segment"``). The line law (``"line"``,
   ``_line_contact``) integrates a linear line-load law along the segment instead (n points of the
   midpoint rule, each its own contact point with the same damping and friction), so the force of
   a rope pressed on a part does not grow with the number of segments that reach it: once per
   segment, Eq. (28) gives a rope crossing an edge 2 / 3 / 5 × Eq. (30)'s energy at 1.4 / 0.7 /
   0.35 mm chords (tests/collide/test_line_contact.py);
3. Hunt–Crossley damping, Eq. (29): F_n = K δ^m (1 + χ δ̇), χ = damp_c / v_k, with v_k the
   LARGEST approach speed seen in the current contact (≥ v_floor). So χ δ̇ ≤ damp_c while
   approaching: the damping force never exceeds damp_c × the elastic force, whatever part the
   contact slides to; its dashpot K δ^m χ is capped at the explicit step's bound STICK_FRACTION ×
   m_eff / dt (``contact.law.normal_force``, ``damp_cap``: without it a contact that began at the
   v_floor and is pressed hard alternates from step to step). Friction Eq. (32), regularised, its
   impulse per step capped at the discrete stick (``contact.law.friction_force``, the same
   bound). Both are booked as dissipated
   at the step's mean velocity (``_book_mean_velocity``): the exact work of the applied forces
   under symplectic Euler, so the energy balance measures the integration error of the
   conservative forces alone;
4. a centre line that reaches a part's core (fin: crosses the core polygon; body: enters the
   solid) is tunnelling: the call stops with status TUNNEL unless the model allows it, in which
   case that pair gets no force and the skipped impulse (effective mass × relative speed at the
   crossing's first step) is accumulated;
5. missile and free nodes advanced; held nodes (crop) keep still, the impulse they receive is
   accumulated so the momentum balance closes.

Candidate list (broad phase; exact: the results are bit-identical to testing every segment every
step). Of the thousands of segments inside the missile's bounding cylinder only tens touch a
part, so step 2 visits only the candidates of ``_build_candidates``: the live segments whose
clearance c (``_clearance``) is ≤ CANDIDATE_SKIN. c is a lower bound of how far the capsule is
from touching any part (c ≤ 0 for every capsule in contact or crossing a core: it is the max of
bounding-cylinder gaps and the min of the body gap (``_body_gap``: bounding cylinder and nose
cones) and the fins' ``_fin_gap``, each ≤ 0 when the capsule touches what it bounds). Each of its terms is 1-Lipschitz in D = max(|Δa|, |Δb|), the
larger displacement (in B) of the segment's ends since the list was built: a distance from the
segment to a fixed set changes by at most D, because every point (1 − s) a + s b of it moves by
(1 − s) Δa + s Δb, of length ≤ D; the x range moves by ≤ D; (end radius − length)/3 by ≤
(D + 2D)/3. So a segment left out with clearance c > 0 cannot touch while each of its ends has
moved by less than c; every node gets the smallest c of its left-out segments as its margin,
``_to_body`` compares each node's displacement with it every step, and the list is rebuilt as
soon as one node reaches its margin (and at the start of every far-net window, and of a new work). The same holds per part:
each candidate keeps the parts whose own bound is ≤ CANDIDATE_SKIN (``_part_mask``; the bounds of
the parts left out join its nodes' margins), and the step skips the others as failed gates. The
segments a step evaluates are then a superset of those in contact, in the same (increasing) order,
and the per-pair gates (body: distance to the axis; fin: ``_fin_gap``) are supersets too; a pair
that fails a gate has no force, so every force, accumulator and contact slot is computed with the
same arithmetic in the same order as with no broad phase (tests/collide/test_kernel_speedups.py).

Far net (``advance(..., ratio)``; multiple time stepping, the impulse method of Grubmüller et al.
1991 / r-RESPA, Tuckerman et al. 1992, with lazy positions as in asynchronous variational
integrators, Lew et al. 2003). The step is set by the contact of the lightest rope pieces at the
fins, ~1/300 of the rope springs' own limit, yet only the rope near the missile can touch it. The
steps are cut into windows of ``ratio`` steps; a window ends by the call's ``horizon`` (a call of
``advance``: its own end; ``advance_kept``: the next output time, so windows run on across the
fin-load intervals' calls). At a window's start (``_far_window``) every node's
largest speed relative to the missile's frame v_max gives the bound d = FAR_BOUND_FACTOR × v_max ×
window; a live segment whose clearance exceeds d cannot touch any part within the window (the
clearance is 1-Lipschitz in its ends' displacements, as for the candidate list) and is slow; the
others are fast, and so are their nodes. The slow segments' forces (rope; and gravity on the
slow nodes) act as one impulse of the whole window, window × F, at its start (their dissipation
booked over the window); the air on every live segment, slow or fast, acts likewise as one impulse
per ``model.air_every`` windows (its rate is ~3e-4 per window, ``simulate.air_windows``); the slow
nodes feel nothing else, so they move over the whole window at once, and the fast nodes take that impulse and then advance step by step with the fast segments'
forces and the contacts. Momentum is exact (every impulse has its reaction); a slow spring's
error is O(window) and is measured against single rate (tests/collide/test_far_net.py,
docs/performance.md "Far net"). The bound is checked, not assumed: a node of a slow segment that
moves farther than d from its position at the window's start (every step for the fast ones, at the
window's end for the slow ones, whose motion in the window is a straight line) stops the call with
FAR. ratio = 1 is the single-rate loop (every segment and node every step, no check).

Call cost, and no reference counting in the hot loop. A compiled call that passes the model, state
and work records (≈ 50 arrays) costs ≈ 0.5 µs when LLVM does not inline it — more than the narrow
phase of a capsule — and even inlined by numba (``inline="always"``) binding the records to the
callee's names costs ≈ 0.23 µs per call (measured: the fin narrow phase of 58 candidates, 19.4 µs
with the records, 6.4 µs with plain arrays). The cost is numba's reference counting (NRT): every
binding of an array, a view or a record of arrays increments and later decrements each array's
count, an atomic read-modify-write. Sampled with ``perf`` on radar × traction's impact
(2026-11-28, the run's JIT symbols mapped by hand), ``NRT_incref`` and ``NRT_decref`` took about a
fifth of the kernel's time, beside 10 % for ``segment_contacts`` itself. The functions of the step's
hot paths — the broad phase (``_to_body``, ``_build_candidates`` and its tests), the narrow phase
(``segment_contacts``, ``_line_contact``, the part shapes' closest points in ``missile.shapes``),
the rope and air forces and the far net's windows — are therefore compiled with ``_nrt=False``:
no reference counts at all. That is safe because none of them allocates: numba refuses to compile
an allocation (or a call that returns a new array) in such a function, and every array they see is
owned by the caller for the whole call. Same arithmetic, same results to the last bit; the
measured gain is in docs/performance.md, "No reference counting in the collide kernel". The
functions that still allocate (the missile's rigid step, the attitude matrix, the calls' scratch)
run once per step or per call. The per-contact helpers (``_apply_to_node``,
``_book_dissipative``, ``_book_penetration``) take plain arrays; ``_apply`` and ``_tunnel`` take the
records (inlined).

A fin's core is its contact polygon (root extended into the body, tip corners rounded to the fin
set's ``tip_corner_radius``: ``missile.shapes`` fin_core, ``missile.planform``; the broad phase's
bounds use the sharp trapezoid, which contains it), used as it is wherever its closest core point
lies: a rope in the corner between a fin and the body is pressed by both (the stored energy is the
sum of the two potentials, each continuous in the positions, so the pair stays conservative).
Dropping the fin pair whenever its closest core point fell inside the body's radius — the former
rule — switched the fin potential on and off discontinuously (a rope at the root of a swept leading
edge has its closest core point inside the body until it is ≈ 2 mm deep in the rounded edge):
energy created independently of dt (+2 200 % on the root-corner test of
``tests/collide/test_contact_kernel.py``). A centre line crossing the root extension is inside the
body, which the body pair has already booked as tunnelling.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from flexnet_fe.collide.air import segment_air
from flexnet_fe.collide.fpu import FTZ_DAZ, get_mxcsr, set_mxcsr
from flexnet_fe.collide.model import (A_AIR_PAID, A_BROKEN, A_CROSS, A_DAMP_CAPPED, A_DAMP_POINTS,
                                      A_DISS_CONTACT, A_DISS_FRICTION, A_DISS_ROPE, A_FIN_WORK, A_TIME,
                                      A_FAST_SEG_STEPS, A_FCONTACT, A_IMP_B, A_NBROKEN, A_NCONTACT, A_PEN,
                                      A_PEN_INT, A_PEN_RATIO, A_PHELD, A_SKIPPED, A_TUN_PART, A_TUN_SPEED,
                                      A_TUN_STEP, A_U_CONTACT, A_WORK_GRAVITY, FAR, NONFINITE, OK,
                                      TUNNEL)
from flexnet_fe.collide.rigid_body import RigidBody, rigid_step
from flexnet_fe.contact.law import approach_speed, contact_potential, friction_force, normal_force
from flexnet_fe.missile.shapes import (FIN_PART_OFFSET, body_closest_scalar, point_core_closest,
                                      segment_body_closest, segment_core_closest)
from flexnet_fe.net.forces import rope_elastic_energy, spring_force
from flexnet_fe.frames import quat_to_matrix


@njit(cache=True)
def _rv(r, a0, a1, a2):
    """R a for R (3, 3) and a = (a0, a1, a2): three floats."""
    return (r[0, 0] * a0 + r[0, 1] * a1 + r[0, 2] * a2, r[1, 0] * a0 + r[1, 1] * a1 + r[1, 2] * a2,
            r[2, 0] * a0 + r[2, 1] * a1 + r[2, 2] * a2)


@njit(cache=True)
def _rtv(r, a0, a1, a2):
    """Rᵀ a: three floats."""
    return (r[0, 0] * a0 + r[1, 0] * a1 + r[2, 0] * a2, r[0, 1] * a0 + r[1, 1] * a1 + r[2, 1] * a2,
            r[0, 2] * a0 + r[1, 2] * a1 + r[2, 2] * a2)


@njit(cache=True)
def _world_rate(r, h, inv_inertia):
    """The missile's angular velocity ω_W = R I_B⁻¹ Rᵀ h [rad/s] (three floats) from its attitude
    R (3, 3) B → W, angular momentum h [kg m²/s] (3,) in W and I_B⁻¹ (3, 3)."""
    hb0, hb1, hb2 = _rtv(r, h[0], h[1], h[2])
    wb0, wb1, wb2 = _rv(inv_inertia, hb0, hb1, hb2)
    return _rv(r, wb0, wb1, wb2)


class StepWork(NamedTuple):
    """Scratch of the loop, kept across calls (``new_work``) while the model does not change: r (3, 3) attitude B → W; w_w [rad/s] (3,)
    missile rate in W; f [N] (n, 3) forces on the nodes; fmt (6,) force [N] and torque about the
    CG [N m] on the missile, W; pbn [m] (n, 3) node positions in B; nb (3,) contact normal and
    qb [m] (3,) contact point of the current pair, B.

    Candidate list (``_build_candidates``): cand (ns,) int64 the segments that may touch a part
    before the list is rebuilt, in increasing order; ncand (2,) int64 (their count, builds in
    this call); cmask (ns,) int64 per candidate the parts it may touch before the rebuild (bit 0
    the body, bit 1 + fi fin fi: ``_part_mask``); pref [m] (n, 3) node positions in B when the
    list was built; marg2 [m²] (n,) squared distance each node may move in B before the list must
    be rebuilt.
    fin_pl (nf, 5, 4): per fin, the core's mid-plane (unit normal n (3), n·origin [m]) and its
    4 edge half-spaces (outward unit normal in the plane (3), offset [m]), B (``_fin_gap``);
    fin_rh [m] (nf,) rope radius + the fin's half-thickness.
    Dissipation at the step's mean velocity (``_book_mean_velocity``): fd [N] (n, 6) the contact
    damping (0:3) and friction (3:6) forces applied to each free node this step; md (12,) their
    reactions on the missile, W: damping force [N], torque about the CG [N m], friction force,
    torque.
    Far-net windows (``_far_window``; module docstring, "Far net"): fseg (ns,) int64 the fast
    segments (stepped every step), sseg (ns,) int64 the slow ones, fnode (n,) int64 the fast nodes
    (nodes of fast segments), nlist (3,) int64 their counts (fast segments, slow segments, fast
    nodes); isfast (n,) bool; pwin [m] (n, 3) node positions in B at the window's start; dfar [m]
    (n,) how far each node whose motion the window's split relies on may move in B during the
    window (inf: not checked); cseg [m] (ns,) each segment's clearance at the last full split,
    pfull [m] (n, 3) the node positions in B then, dfull [m] (n,) each node's displacement since;
    wasfast (ns,) bool scratch of ``_far_split``; refresh (2,) int64: [0] ≠ 0 when the next split
    must evaluate every segment (a new work, or the last split re-evaluated more than
    REFRESH_SHARE of them), [1] the full splits made; win (1,) int64 the steps left in the open
    window (0: none; a window may span calls, ``advance_kept``'s horizon). Single rate (ratio 1):
    every segment and node fast, dfar inf.
    sv (1,) [m/s]: the prescribed normal speed ẇ of the fin surface under the current contact point
    (``_point_depth``; 0 for rigid fins and the body)."""

    r: np.ndarray
    w_w: np.ndarray
    f: np.ndarray
    fmt: np.ndarray
    pbn: np.ndarray
    nb: np.ndarray
    qb: np.ndarray
    cand: np.ndarray
    ncand: np.ndarray
    pref: np.ndarray
    marg2: np.ndarray
    fin_pl: np.ndarray
    fin_rh: np.ndarray
    fd: np.ndarray
    md: np.ndarray
    fseg: np.ndarray
    sseg: np.ndarray
    fnode: np.ndarray
    nlist: np.ndarray
    isfast: np.ndarray
    pwin: np.ndarray
    dfar: np.ndarray
    cseg: np.ndarray
    pfull: np.ndarray
    dfull: np.ndarray
    wasfast: np.ndarray
    cmask: np.ndarray
    refresh: np.ndarray
    win: np.ndarray
    sv: np.ndarray


@njit(cache=True)
def _fin_half_spaces(model):
    """(nf, 5, 4) the ``StepWork.fin_pl`` of the model's fins: row 0 the core's mid-plane
    (n, n·o), rows 1..4 edge k of ``fin_poly`` (corner k → k + 1, counter-clockwise in (u, v)):
    outward normal m = (t_v e1 − t_u e2)/|t| and offset m·(o + u_k e1 + v_k e2) [m]."""
    nf = model.fin_half.shape[0]
    out = np.zeros((nf, 5, 4))
    for fi in range(nf):
        o, ax, poly = model.fin_origin[fi], model.fin_axes[fi], model.fin_poly[fi]
        for c in range(3):
            out[fi, 0, c] = ax[2, c]
            out[fi, 0, 3] += ax[2, c] * o[c]
        nv = poly.shape[0]
        for k in range(nv):
            tu, tv = poly[(k + 1) % nv, 0] - poly[k, 0], poly[(k + 1) % nv, 1] - poly[k, 1]
            ln = np.sqrt(tu * tu + tv * tv)
            for c in range(3):
                m_c = (tv * ax[0, c] - tu * ax[1, c]) / ln
                out[fi, 1 + k, c] = m_c
                out[fi, 1 + k, 3] += m_c * (o[c] + poly[k, 0] * ax[0, c] + poly[k, 1] * ax[1, c])
    return out


@njit(cache=True)
def _fin_reach(model):
    """(nf,) [m] rope radius + each fin's half-thickness (+ its largest prescribed |w|, a moving fin):
    the distance from a fin's undeformed core within which a rope centre line may touch it."""
    rh = model.fin_half + model.rope_radius
    if model.fin_wmax.shape[0] > 0:
        rh = rh + model.fin_wmax
    return rh


@njit(cache=True)
def _work(model, n):
    """A new scratch for ``n`` nodes; the candidate list is empty and every node's margin 0, so the
    first step builds it; every segment and node is fast (single rate); the first split is full."""
    ns = model.seg.shape[0]
    return StepWork(np.eye(3), np.zeros(3), np.zeros((n, 3)), np.zeros(6), np.zeros((n, 3)), np.zeros(3),
                    np.zeros(3), np.zeros(ns, np.int64), np.zeros(2, np.int64), np.zeros((n, 3)), np.zeros(n),
                    _fin_half_spaces(model), _fin_reach(model), np.zeros((n, 6)), np.zeros(12),
                    np.arange(ns), np.zeros(ns, np.int64), np.arange(n), np.array([ns, 0, n]),
                    np.ones(n, np.bool_), np.zeros((n, 3)), np.full(n, np.inf), np.zeros(ns), np.zeros((n, 3)),
                    np.zeros(n), np.zeros(ns, np.bool_), np.zeros(ns, np.int64), np.array([1, 0]),
                    np.zeros(1, np.int64), np.zeros(1))


@njit(cache=True)
def _body_positions(model, state):
    """Every node's position in B [m] (n, 3), as ``_to_body`` computes it."""
    r = quat_to_matrix(state.mq)
    n = state.x.shape[0]
    pbn = np.empty((n, 3))
    for i in range(n):
        b0, b1, b2 = _rtv(r, state.x[i, 0] - state.mx[0], state.x[i, 1] - state.mx[1], state.x[i, 2] - state.mx[2])
        pbn[i, 0] = b0 + model.cg_b[0]
        pbn[i, 1] = b1 + model.cg_b[1]
        pbn[i, 2] = b2 + model.cg_b[2]
    return pbn


@njit(cache=True)
def _measure_work(model, pbn):
    """A ``StepWork`` for measuring contacts (``segment_contacts`` with apply False) at the node
    positions pbn [m] (n, 3) in B: only pbn, nb, qb, fin_pl and fin_rh are held; the loop's other
    scratch is empty (a whole ``_work`` zeroes ~7 MB on radar × traction, most of the cost of a
    measurement once per output interval)."""
    e1, e2, i1 = np.zeros((0, 3)), np.zeros(0), np.zeros(0, np.int64)
    return StepWork(np.eye(3), np.zeros(3), e1, np.zeros(6), pbn, np.zeros(3), np.zeros(3), i1, np.zeros(2, np.int64),
                    e1, e2, _fin_half_spaces(model), _fin_reach(model), np.zeros((0, 6)),
                    np.zeros(12), i1, i1, i1, np.zeros(3, np.int64), np.zeros(0, np.bool_), e1, e2, e2, e1, e2,
                    np.zeros(0, np.bool_), i1, np.zeros(2, np.int64), np.zeros(1, np.int64), np.zeros(1))


@njit(cache=True, _nrt=False)
def _to_body(model, state, wk, nodes, count):
    """Positions in B [m] of the nodes ``nodes[:count]`` into wk.pbn (n, 3); wk.r must hold the
    attitude. Returns (rebuild, far): rebuild True when one of them has moved (in B) by its margin
    since the candidate list was built (wk.pref, wk.marg2): the list must then be rebuilt; far True
    when one has moved farther from its position at the window's start (wk.pwin) than its bound
    wk.dfar (``_far_window``)."""
    r, pbn, pref, marg2, pwin, dfar = wk.r, wk.pbn, wk.pref, wk.marg2, wk.pwin, wk.dfar
    moved = False
    far = False
    for c in range(count):
        i = nodes[c]
        b0, b1, b2 = _rtv(r, state.x[i, 0] - state.mx[0], state.x[i, 1] - state.mx[1], state.x[i, 2] - state.mx[2])
        pbn[i, 0] = b0 + model.cg_b[0]
        pbn[i, 1] = b1 + model.cg_b[1]
        pbn[i, 2] = b2 + model.cg_b[2]
        d0, d1, d2 = pbn[i, 0] - pref[i, 0], pbn[i, 1] - pref[i, 1], pbn[i, 2] - pref[i, 2]
        moved |= d0 * d0 + d1 * d1 + d2 * d2 >= marg2[i]
        w0, w1, w2 = pbn[i, 0] - pwin[i, 0], pbn[i, 1] - pwin[i, 1], pbn[i, 2] - pwin[i, 2]
        far |= w0 * w0 + w1 * w1 + w2 * w2 > dfar[i] * dfar[i]
    return moved, far


@njit(cache=True, _nrt=False)
def _near_missile(model, pa, pb):
    """Broad phase: can the capsule a–b [m] (B) reach the missile's bounding cylinder?"""
    rad = model.rope_radius
    bb = model.bbox
    if max(pa[0], pb[0]) < bb[0] - rad or min(pa[0], pb[0]) > bb[1] + rad:
        return False
    lab = np.sqrt((pb[0] - pa[0]) ** 2 + (pb[1] - pa[1]) ** 2 + (pb[2] - pa[2]) ** 2)
    rmin = min(np.sqrt(pa[1] ** 2 + pa[2] ** 2), np.sqrt(pb[1] ** 2 + pb[2] ** 2))
    return rmin - lab <= bb[2] + rad


CANDIDATE_SKIN = 1.0e-3
"""[m] A segment whose clearance (``_clearance``) is at most this is a candidate (its contacts are
evaluated every step); the others are skipped until some node has moved by its margin (≥ this).
A larger skin means more candidates and fewer rebuilds; the results do not depend on it (bit for
bit: measured). radar × traction's impact, alternated side by side (docs/performance.md, "Where the
collide stage's time goes"): `simulate` 41.9 s at 2 mm (the former value), 39.6 s at 1 mm, 39.9 s at
0.5 mm, 42.9 s at 3 mm; the resolution check's impact 95.2 → 86.4 s from 2 to 1 mm."""
ROUND_OFF_GUARD = 1.0e-9
"""[m] taken off every margin: the clearances are computed in floating point (errors ~1e-15 m at
the missile's size), the proof below is in exact arithmetic."""


@njit(cache=True, _nrt=False)
def _clearance(bb, rad, fin_pl, fin_rh, cones, pa, pb, skin):
    """A lower bound [m] of how far the capsule a–b (B) of radius rad [m] is from touching any
    part (bb: ``CollideModel.bbox``; fin_pl, fin_rh: ``StepWork``): > 0 proves it touches
    nothing. It is the largest of the bounding-cylinder gaps (x range; distance to the axis −
    r_max − r), else the smallest of the body gap (``_body_gap``) and the fins'
    ``_fin_gap`` (a fin whose mid-plane alone is farther than the smallest gap so far cannot
    lower it and is not evaluated further); 1-Lipschitz in the ends' displacement (module
    docstring, candidate list). A bound already above ``skin`` [m] is returned at once (the
    callers only compare it with their skin). Plain arrays, not the records: this runs for every
    segment at each rebuild, and passing the model record to a function costs more than the whole
    test."""
    c = max((bb[0] - rad) - max(pa[0], pb[0]), min(pa[0], pb[0]) - (bb[1] + rad))
    if c > skin:
        return c
    axis = _axis_distance(pa, pb)
    c = max(c, axis - (bb[2] + rad))
    if c > skin:
        return c
    parts = _body_gap(axis, cones, rad, pa, pb, bb[3])
    for fi in range(fin_rh.shape[0]):
        fp = fin_pl[fi]
        da = pa[0] * fp[0, 0] + pa[1] * fp[0, 1] + pa[2] * fp[0, 2] - fp[0, 3]
        db = pb[0] * fp[0, 0] + pb[1] * fp[0, 1] + pb[2] * fp[0, 2] - fp[0, 3]
        if da * db > 0.0 and min(abs(da), abs(db)) - fin_rh[fi] >= parts:
            continue  # _fin_gap ≥ its plane term ≥ parts
        parts = min(parts, _fin_gap(fin_pl, fi, fin_rh[fi], pa, pb))
    return max(c, parts)


ALL_PARTS = -1
"""``segment_contacts`` mask: every part (bits of ``_part_mask``)."""


@njit(cache=True, _nrt=False)
def _part_mask(bb, rad, fin_pl, fin_rh, cones, pa, pb, skin):
    """(mask, lb) of a candidate capsule a–b (B): bit 0 set when the body's lower bound
    (bounding-cylinder gaps, ``_body_gap``) is ≤ ``skin`` [m], bit 1 + fi when fin fi's
    (bounding-cylinder gaps, ``_fin_gap``) is; lb [m] the smallest lower bound of the parts left
    out (inf: none). Each bound is 1-Lipschitz in the ends' displacement (module docstring,
    candidate list), so a part left out cannot be touched while both ends move by less than lb:
    the step skips its pair with the result of its failed gate."""
    c = max((bb[0] - rad) - max(pa[0], pb[0]), min(pa[0], pb[0]) - (bb[1] + rad))
    axis = _axis_distance(pa, pb)
    c = max(c, axis - (bb[2] + rad))
    mask = 0
    lb = np.inf
    g = max(c, _body_gap(axis, cones, rad, pa, pb, bb[3]))
    if g <= skin:
        mask |= 1
    else:
        lb = g
    for fi in range(fin_rh.shape[0]):
        g = max(c, _fin_gap(fin_pl, fi, fin_rh[fi], pa, pb))
        if g <= skin:
            mask |= 1 << (fi + 1)
        else:
            lb = min(lb, g)
    return mask, lb


@njit(cache=True, _nrt=False)
def _build_candidates(model, state, wk):
    """Rebuild the candidate list from the node positions in B (wk.pbn): the live fast segments
    (wk.fseg; all of them at single rate) whose ``_clearance`` is ≤ CANDIDATE_SKIN, each with
    the parts it may touch (``_part_mask``; the parts left out give its nodes a margin of their
    lower bound); every other live fast segment gives each of its nodes a margin of its clearance
    (margins less ROUND_OFF_GUARD), and its contact slots are reset (not in contact). The slow
    segments cannot touch before the window ends (``_far_window``)."""
    nf = model.fin_half.shape[0]
    pbn, pref, marg2 = wk.pbn, wk.pref, wk.marg2
    for c in range(wk.nlist[2]):
        i = wk.fnode[c]
        pref[i, 0], pref[i, 1], pref[i, 2] = pbn[i, 0], pbn[i, 1], pbn[i, 2]
        marg2[i] = np.inf
    nc = 0
    seg, alive, bb, rad, fin_pl, fin_rh = model.seg, state.alive, model.bbox, model.rope_radius, wk.fin_pl, wk.fin_rh
    for fc in range(wk.nlist[0]):
        e = wk.fseg[fc]
        if not alive[e]:
            continue
        i, j = seg[e, 0], seg[e, 1]
        c = _clearance(bb, rad, fin_pl, fin_rh, model.nose_cones, pbn[i], pbn[j], CANDIDATE_SKIN)
        if c <= CANDIDATE_SKIN:
            mask, lb = _part_mask(bb, rad, fin_pl, fin_rh, model.nose_cones, pbn[i], pbn[j],
                                  CANDIDATE_SKIN)
            wk.cand[nc] = e
            wk.cmask[nc] = mask
            nc += 1
            if lb < np.inf:
                m2 = (lb - ROUND_OFF_GUARD) ** 2
                marg2[i] = min(marg2[i], m2)
                marg2[j] = min(marg2[j], m2)
            continue
        m2 = (c - ROUND_OFF_GUARD) ** 2
        marg2[i] = min(marg2[i], m2)
        marg2[j] = min(marg2[j], m2)
        for p in range(e * (1 + nf), (e + 1) * (1 + nf)):
            state.vk[p] = 0.0
    wk.ncand[0] = nc
    wk.ncand[1] += 1


@njit(cache=True, inline="always")  # (module docstring: call cost)
def _body_gap(axis, cones, rad, pa, pb, r_body):
    """A lower bound [m] of (distance from the segment a–b (B) to the body of revolution) − rad:
    the largest of the bounding cylinder's axis − R and each nose cone's (axis − r0 − k s_max) /
    (1 + k) (``missile.shapes.nose_cones``: the body lies in each; s_max = −min(a_x, b_x) the
    segment's largest station). Each is at most the distance to its solid (in the meridian plane
    a cone is the half-plane ρ − k s ≤ r0, at distance (ρ − k s − r0)/√(1 + k²) ≥ the value here
    where positive; the segment's points have ρ ≥ axis and s ≤ s_max), and 1-Lipschitz in the
    ends' displacement (axis and s_max are; the weights 1/(1 + k) and k/(1 + k) sum to 1). axis:
    the segment's distance to the axis [m] (``_axis_distance``); cones (nc, 2); r_body R [m]."""
    g = axis - r_body
    s_max = -min(pa[0], pb[0])
    for c in range(cones.shape[0]):
        g = max(g, (axis - cones[c, 0] - cones[c, 1] * s_max) / (1.0 + cones[c, 1]))
    return g - rad


@njit(cache=True, _nrt=False)
def _axis_distance(pa, pb):
    """Smallest distance [m] of the segment a–b (B) from the missile axis x_b (closed form)."""
    dy, dz = pb[1] - pa[1], pb[2] - pa[2]
    ll = dy * dy + dz * dz
    s = 0.0 if ll == 0.0 else min(max(-(pa[1] * dy + pa[2] * dz) / ll, 0.0), 1.0)
    return np.sqrt((pa[1] + s * dy) ** 2 + (pa[2] + s * dz) ** 2)


@njit(cache=True, _nrt=False)
def _fin_gap(fin_pl, fi, rh, pa, pb):
    """A lower bound [m] of (distance from the segment a–b (B) to fin fi's core) − rh (rh = r +
    h/2 [m]): the largest of the segment's distances to the core's mid-plane and to each edge's
    outer half-space (fin_pl: ``StepWork.fin_pl``; the core lies in the plane and inside every
    edge's inner half-space, so each is a lower bound of the distance to it). ≤ 0 for every pair
    in contact or crossing; 1-Lipschitz in the ends' displacement (a distance to a fixed set)."""
    fp = fin_pl[fi]
    da = pa[0] * fp[0, 0] + pa[1] * fp[0, 1] + pa[2] * fp[0, 2] - fp[0, 3]
    db = pb[0] * fp[0, 0] + pb[1] * fp[0, 1] + pb[2] * fp[0, 2] - fp[0, 3]
    gap = 0.0 if da * db <= 0.0 else min(abs(da), abs(db))
    for k in range(1, 5):
        sa = pa[0] * fp[k, 0] + pa[1] * fp[k, 1] + pa[2] * fp[k, 2] - fp[k, 3]
        sb = pb[0] * fp[k, 0] + pb[1] * fp[k, 1] + pb[2] * fp[k, 2] - fp[k, 3]
        gap = max(gap, min(sa, sb))
    return gap - rh


@njit(cache=True, inline="always")  # (module docstring: call cost)
def _apply_to_node(free, acc, f, node, weight, force, dt):
    """Add ``weight`` × the contact force ``force`` = (f0, f1, f2) [N] to a free node's force row of ``f``;
    a held node (crop boundary) does not move, so its impulse [N s] goes to the held-node
    accumulator that closes the momentum balance."""
    f0, f1, f2 = force
    if free[node]:
        f[node, 0] += weight * f0
        f[node, 1] += weight * f1
        f[node, 2] += weight * f2
    else:
        acc[A_PHELD] += weight * f0 * dt
        acc[A_PHELD + 1] += weight * f1 * dt
        acc[A_PHELD + 2] += weight * f2 * dt


@njit(cache=True, inline="always")  # (module docstring: call cost)
def _take_wrench(out, k, lever, force):
    """The missile's reaction to a force on the rope: out[k:k+3] −= force [N] and out[k+3:k+6] −=
    lever × force [N m] (lever [m] from the CG to the contact point, W)."""
    l0, l1, l2 = lever
    f0, f1, f2 = force
    out[k] -= f0
    out[k + 1] -= f1
    out[k + 2] -= f2
    out[k + 3] -= l1 * f2 - l2 * f1
    out[k + 4] -= l2 * f0 - l0 * f2
    out[k + 5] -= l0 * f1 - l1 * f0


@njit(cache=True, inline="always")  # (module docstring: call cost)
def _book_dissipative(free, fd, node, weight, forces):
    """Add ``weight`` × the contact damping and friction forces ``forces`` (6 floats) [N] to a free
    node's row of fd (wk.fd, ``_book_mean_velocity``); a held node does not move: no work."""
    if free[node]:
        for k in range(6):
            fd[node, k] += weight * forces[k]


@njit(cache=True, inline="always")  # (module docstring: call cost)
def _apply(model, state, wk, slot, fin, pt, dt, law):
    """Force of one (segment, part) contact point on the net and the missile, Eq. (28), (29), (32).

    slot: contact slot (segment e = slot // (1 + nf)); fin: fin index or −1 (body); pt = (delta,
    s): penetration [m] > 0 and segment parameter of the point; wk.nb (3,) unit normal (towards the
    rope) and wk.qb [m] (3,) missile contact point, in B; law = (kk, expo, wstick): the point's
    stiffness [N/m^expo] and exponent (segment law: K of the part, m; line law: k_l × the point's
    rest length, 1) and its share (0, 1] of the segment's discrete-stick friction cap. Adds the force to
    wk.f (weights 1 − s, s on the segment's nodes) and its reaction to wk.fmt (missile force,
    torque about the CG, W); books the dissipation; fin ≥ 0: adds the impulse to the fin-load
    slot. Returns |F| [N]."""
    delta, s = pt
    kk, expo, wstick = law
    v, mv = state.v, state.mv
    r, w_w, f, fmt, nb, qb = wk.r, wk.w_w, wk.f, wk.fmt, wk.nb, wk.qb
    e = slot // (model.fin_half.shape[0] + 1)
    i, j = model.seg[e, 0], model.seg[e, 1]
    nw0, nw1, nw2 = _rv(r, nb[0], nb[1], nb[2])
    l0, l1, l2 = _rv(r, qb[0] - model.cg_b[0], qb[1] - model.cg_b[1], qb[2] - model.cg_b[2])
    w = 1.0 - s
    vr0 = w * v[i, 0] + s * v[j, 0] - mv[0] - (w_w[1] * l2 - w_w[2] * l1)
    vr1 = w * v[i, 1] + s * v[j, 1] - mv[1] - (w_w[2] * l0 - w_w[0] * l2)
    vr2 = w * v[i, 2] + s * v[j, 2] - mv[2] - (w_w[0] * l1 - w_w[1] * l0)
    sn = wk.sv[0] if fin >= 0 else 0.0  # a moving fin's surface speed along its normal
    s0, s1, s2 = 0.0, 0.0, 0.0
    if sn != 0.0:
        ax2 = model.fin_axes[fin, 2]
        s0, s1, s2 = _rv(r, sn * ax2[0], sn * ax2[1], sn * ax2[2])
        vr0, vr1, vr2 = vr0 - s0, vr1 - s1, vr2 - s2
    vn = vr0 * nw0 + vr1 * nw1 + vr2 * nw2
    ddot = -vn
    vk = approach_speed(state.vk[slot], ddot, model.v_floor)
    state.vk[slot] = vk
    inv_m = 1.0 / model.m_mass  # the contact point's effective mass (translation; the missile's
    if model.free[i]:           # rotation adds < 1e-6 of a rope piece's 1/m)
        inv_m += w * w / model.mass[i]
    if model.free[j]:
        inv_m += s * s / model.mass[j]
    cap = wstick * STICK_FRACTION / (inv_m * dt)  # [kg/s] the explicit step's discrete bound
    fel = kk * delta ** expo
    chi = model.damp_c / vk
    fn = normal_force(delta, ddot, kk, expo, chi, cap)
    state.acc[A_DAMP_POINTS] += 1.0
    if fel * chi > cap:
        state.acc[A_DAMP_CAPPED] += 1.0
    vt0, vt1, vt2 = vr0 - vn * nw0, vr1 - vn * nw1, vr2 - vn * nw2
    ft0, ft1, ft2 = friction_force(fn, model.mu, vt0, vt1, vt2, model.v_reg, cap)
    f0, f1, f2 = fn * nw0 + ft0, fn * nw1 + ft1, fn * nw2 + ft2
    _apply_to_node(model.free, state.acc, f, i, w, (f0, f1, f2), dt)
    _apply_to_node(model.free, state.acc, f, j, s, (f0, f1, f2), dt)
    fd0, fd1, fd2 = (fn - fel) * nw0, (fn - fel) * nw1, (fn - fel) * nw2
    _book_dissipative(model.free, wk.fd, i, w, (fd0, fd1, fd2, ft0, ft1, ft2))
    _book_dissipative(model.free, wk.fd, j, s, (fd0, fd1, fd2, ft0, ft1, ft2))
    _take_wrench(wk.md, 0, (l0, l1, l2), (fd0, fd1, fd2))
    _take_wrench(wk.md, 6, (l0, l1, l2), (ft0, ft1, ft2))
    _take_wrench(fmt, 0, (l0, l1, l2), (f0, f1, f2))
    if sn != 0.0:  # the moving surface's work on the rope (external: the energy balance books it)
        state.acc[A_FIN_WORK] += (f0 * s0 + f1 * s1 + f2 * s2) * dt
    state.acc[A_DISS_CONTACT] += (fn - fel) * ddot * dt
    state.acc[A_DISS_FRICTION] -= (ft0 * vt0 + ft1 * vt1 + ft2 * vt2) * dt
    state.part_imp[fin + 1, 0] += fn * dt
    state.part_imp[fin + 1, 1] += np.sqrt(ft0 * ft0 + ft1 * ft1 + ft2 * ft2) * dt
    fmag = np.sqrt(f0 * f0 + f1 * f1 + f2 * f2)
    state.acc[A_FCONTACT] += fmag * dt
    if fin >= 0 and fmag > 0.0:  # (a contact in restitution may carry no force: F_n ≥ 0 clamp)
        fs = slot // (model.fin_half.shape[0] + 1) * model.fin_half.shape[0] + fin
        if state.fin_w[fs] == 0.0:
            state.touched[state.ntouched[0]] = fs
            state.ntouched[0] += 1
        b0, b1, b2 = _rtv(r, f0, f1, f2)
        state.fin_imp[fs, 0] -= b0 * dt
        state.fin_imp[fs, 1] -= b1 * dt
        state.fin_imp[fs, 2] -= b2 * dt
        for k in range(3):
            state.fin_pt[fs, k] += fmag * dt * qb[k]
        state.fin_w[fs] += fmag * dt
        c0, c1, c2 = state.x[j, 0] - state.x[i, 0], state.x[j, 1] - state.x[i, 1], state.x[j, 2] - state.x[i, 2]
        state.fin_len[fs] += fmag * dt * np.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
    return fmag


@njit(cache=True, inline="always")
def _bilinear(w, r, i, j, a, b):
    """Row r of the sampled field w (rows, nu, nv) at cell (i, j), local coordinates (a, b) ∈ [0, 1]²."""
    return ((1.0 - a) * ((1.0 - b) * w[r, i, j] + b * w[r, i, j + 1])
            + a * ((1.0 - b) * w[r, i + 1, j] + b * w[r, i + 1, j + 1]))


@njit(cache=True, _nrt=False)
def _fin_motion(model, fin, pu, pv, t):
    """(w [m], ẇ [m/s]) of fin ``fin``'s prescribed normal displacement (``model.FinMotion``) at its
    planform point (pu, pv) [m] and time t [s]: bilinear on the fin's grid (clamped to it), linear in
    t between samples (ẇ the interval's slope); 0 before the first sample, the last one held after."""
    nt = model.fin_motion_nt[fin]
    tau = (t - model.fin_motion_t0[fin]) / model.fin_motion_dt
    if nt == 0 or tau < 0.0:
        return 0.0, 0.0
    g, w = model.fin_motion_grid[fin], model.fin_motion_w
    nu, nv = w.shape[1], w.shape[2]
    x = min(max((pu - g[0]) / g[1], 0.0), nu - 1.0)
    y = min(max((pv - g[2]) / g[3], 0.0), nv - 1.0)
    i, j = min(int(x), nu - 2), min(int(y), nv - 2)
    a, b = x - i, y - j
    r = model.fin_motion_offset[fin] + min(int(tau), nt - 1)
    w0 = _bilinear(w, r, i, j, a, b)
    if tau >= nt - 1:  # at or past the last sample: held
        return w0, 0.0
    w1 = _bilinear(w, r + 1, i, j, a, b)
    c = tau - int(tau)
    return (1.0 - c) * w0 + c * w1, (w1 - w0) / model.fin_motion_dt


@njit(cache=True, inline="always")  # (module docstring: call cost)
def _point_depth(model, wk, fin, p, t):
    """Penetration δ [m] of the rope's cross-section centred at p = (p0, p1, p2) [m] (B) into part
    ``fin`` (−1: the body) at time t [s], with wk.nb its unit normal (towards the rope), wk.qb the
    part's surface point under it and wk.sv the surface's prescribed normal speed there (a moving
    fin, ``_fin_motion``: its core shifted by w along its normal n, the shift read at p's projection
    on the planform — first order in the fin's slope); δ ≤ 0: apart (nb, qb then undefined), and 0
    when the centre is on the core (a crossing: booked per segment as tunnelling)."""
    p0, p1, p2 = p
    nb, qb = wk.nb, wk.qb
    if fin < 0:
        d, nb[0], nb[1], nb[2], qb[0], qb[1], qb[2], _ = body_closest_scalar(
            (p0, p1, p2), model.prof_kind, model.prof_data, model.prof_part)
        return model.rope_radius - d if d > 0.0 else 0.0
    o, ax, half = model.fin_origin[fin], model.fin_axes[fin], model.fin_half[fin]
    wf = 0.0
    if model.fin_motion_nt.shape[0] > 0:
        du0, du1, du2 = p0 - o[0], p1 - o[1], p2 - o[2]
        wf, wk.sv[0] = _fin_motion(model, fin, du0 * ax[0, 0] + du1 * ax[0, 1] + du2 * ax[0, 2],
                                   du0 * ax[1, 0] + du1 * ax[1, 1] + du2 * ax[1, 2], t)
        p0, p1, p2 = p0 - wf * ax[2, 0], p1 - wf * ax[2, 1], p2 - wf * ax[2, 2]
    dist, qu, qv = point_core_closest((p0, p1, p2), o, ax, model.fin_core[fin, :model.fin_ncore[fin]])
    if dist <= 0.0:
        return 0.0
    c0 = o[0] + qu * ax[0, 0] + qv * ax[1, 0]
    c1 = o[1] + qu * ax[0, 1] + qv * ax[1, 1]
    c2 = o[2] + qu * ax[0, 2] + qv * ax[1, 2]
    nb[0], nb[1], nb[2] = (p0 - c0) / dist, (p1 - c1) / dist, (p2 - c2) / dist
    qb[0], qb[1], qb[2] = c0 + half * nb[0], c1 + half * nb[1], c2 + half * nb[2]
    if wf != 0.0:  # the surface point where the fin is
        qb[0], qb[1], qb[2] = qb[0] + wf * ax[2, 0], qb[1] + wf * ax[2, 1], qb[2] + wf * ax[2, 2]
    return model.rope_radius + half - dist


@njit(cache=True, inline="always")  # (module docstring: call cost)
def _line_grid(model, state, wk, slot, fin, geo, dt, apply):
    """One midpoint rule of ``_line_contact``: geo = (pa, pb, s*, n, weight) — the segment's ends [m]
    (3,) in B, the parameter of its deepest point, the number of cells n (points s_q = (q + ½)/n, each
    of length ℓ/n) and the rule's weight in the blend. Points are taken from the two nearest s*
    outwards until δ ≤ 0 (δ is concave along the segment: convex parts). With ``apply`` each point
    with δ_q > 0 gets ``_apply`` with the stiffness weight × k_l ℓ0/n (ℓ0 the segment's rest length),
    exponent 1 and weight/n of the segment's stick cap. Returns (U_n = Σ_q ½ k_l (ℓ0/n) δ_q² [J],
    whether a point touched)."""
    pa, pb, s_star, n, weight = geo
    t0, t1, t2 = pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]
    kq = (model.kl_fin[fin] if fin >= 0 else model.kl_body) * model.rest[slot // (model.fin_half.shape[0] + 1)] / n
    energy = 0.0
    touched = False
    # δ is concave along the segment with its maximum at s*, so it falls monotonically from s* in
    # each direction: walk each side from the point nearest s* on that side (qr: the first point at
    # or past s*) and stop at the first point out of contact. (Walking from the cell holding s* missed
    # the points beyond a first point on the wrong side of s* that was out of contact: U jumped.)
    qr = min(max(int(np.ceil(s_star * n - 0.5)), 0), n)
    for step in (1, -1):
        q = qr if step == 1 else qr - 1
        while 0 <= q < n:
            s = (q + 0.5) / n
            delta = _point_depth(model, wk, fin, (pa[0] + s * t0, pa[1] + s * t1, pa[2] + s * t2),
                                 state.acc[A_TIME])
            if delta <= 0.0:
                break
            touched = True
            energy += 0.5 * kq * delta * delta
            if apply:
                _apply(model, state, wk, slot, fin, (delta, s), dt, (weight * kq, 1.0, weight / n))
            q += step
    return energy, touched


@njit(cache=True, _nrt=False)  # not inlined: one compiled copy (the segment law's path stays inline)
def _line_contact(model, state, wk, slot, fin, seg_pt, dt, apply):
    """Line contact of a segment with one part, ``collide.contact_law = "line"``
    (``contact.stiffness.line_stiffness``); seg_pt = (pa, pb, s*): its ends [m] (3,) in B and the
    parameter of its point deepest in the part.

    The stored energy is the integral over the rope's material, U = ∫ ½ k_l δ² dl0: k_l per unit of
    rest length ℓ0, δ the penetration of the rope's cross-section, taken along the segment's
    current chord by the composite midpoint rule U_n on n cells (``_line_grid``), each carrying ℓ0/n
    of rope. Points at most 2h apart in space resolve any contact wider than that (h =
    model.line_h_*), so n follows the current length ℓ: with m = ℓ/h, n = max(1, ⌊m⌋) and
    U = (1 − α) U_n + α U_{n+1}, α = m − n ∈ [0, 1) (0 below m = 1): continuous as ℓ crosses a
    whole number of h, so the potential never jumps. The forces are its exact gradient: each rule's
    points (weights 1 − α, α) by the envelope theorem, plus along the segment the blend's length
    derivative (U_{n+1} − U_n)/h (the two rules' difference: small). Unlike Eq. (28) applied once per
    segment, the total force of a rope on a part does not grow as the rope is cut finer: it
    converges to the integral (an unstretched rope crossing an edge: K δ0^1.5 of Eq. (30),
    ``line_stiffness``; stretched s×, K δ0^1.5 / s, as its mass per length).
    Per unit of rest length, not of current length (until 2026-11-28): U per current length grew
    by ½ k_l δ² per metre the pressed rope stretched, an axial force that at δ = 1 mm (2.7 kN)
    dwarfs the paper rope's E A = 16 N and crushed pressed pieces to micrometres, where its
    direction flips; a rope bundle striking a rudder then created 12 % of the energy exchanged at
    the case's step (benchmarks/strike_convergence.py; ≤ 0.11 % now). Per rest length, each
    material element of rope meets the part as an unstretched one would (its ω² = k_l / ρA), so
    the contact limit of the step does not move as the rope stretches.
    Returns the stored energy U [J]; with ``apply``, the slot's approach speed is reset when no
    point touches."""
    pa, pb, s_star = seg_pt
    t0, t1, t2 = pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]
    ell = np.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
    if ell <= 0.0:
        return 0.0
    m = ell / (model.line_h_fin[fin] if fin >= 0 else model.line_h_body)
    n = max(1, int(m))
    alpha = m - n if m > n else 0.0
    u_n, u_m = 0.0, 0.0
    touched = False
    for k in range(2 if alpha > 0.0 else 1):  # (one call site: one inlined copy of the rule)
        u, hit = _line_grid(model, state, wk, slot, fin, (pa, pb, s_star, n + k, alpha if k else 1.0 - alpha),
                            dt, apply)
        touched = touched or hit
        if k:
            u_m = u
        else:
            u_n = u
    if apply:
        g = (u_m - u_n) * m / ell if alpha > 0.0 else 0.0
        tw0, tw1, tw2 = _rv(wk.r, t0 / ell, t1 / ell, t2 / ell)
        e = slot // (model.fin_half.shape[0] + 1)
        _apply_to_node(model.free, state.acc, wk.f, model.seg[e, 0], g, (tw0, tw1, tw2), dt)
        _apply_to_node(model.free, state.acc, wk.f, model.seg[e, 1], -g, (tw0, tw1, tw2), dt)
        if not touched:
            state.vk[slot] = 0.0
    return (1.0 - alpha) * u_n + alpha * u_m


@njit(cache=True, inline="always")  # (module docstring: call cost)
def _pair_contact(model, state, wk, slot, fin, geo, dt, apply):
    """The contact of a segment with one part once its closest point penetrates: geo = (pa, pb,
    s, delta, dist) — ends [m] (3,) in B, parameter, penetration [m] > 0 of the closest point and
    (fins) its distance to the core; wk.nb, wk.qb as ``segment_contacts`` left them (body: normal
    and surface point; fin: the core point in wk.qb). The line law (``_line_contact``) or Eq. (28)
    at the closest point. Returns the stored energy [J]."""
    pa, pb, s, delta, dist = geo
    if model.line_law:
        return _line_contact(model, state, wk, slot, fin, (pa, pb, s), dt, apply)
    kk = model.k_fin if fin >= 0 else model.k_body
    if apply:
        if fin >= 0:
            nb, qb, half = wk.nb, wk.qb, model.fin_half[fin]
            for k in range(3):
                nb[k] = (pa[k] + s * (pb[k] - pa[k]) - qb[k]) / dist
                qb[k] += half * nb[k]  # the fin's surface point under the rope
        _apply(model, state, wk, slot, fin, (delta, s), dt, (kk, model.exponent, 1.0))
    return contact_potential(delta, kk, model.exponent)


@njit(cache=True, inline="always")  # (module docstring: call cost)
def _tunnel(model, state, slot, part, s, step):
    """Book a centre line that reached part ``part``'s core (tunnelling) at segment parameter s.
    The impulse a contact would have had to deliver to stop it, m_eff |v_rel| (m_eff =
    (1 − s) m_i + s m_j, v_rel its velocity relative to the missile's CG), is booked as skipped
    at the crossing's first step. Returns TUNNEL unless allowed."""
    state.acc[A_CROSS] += 1.0
    if state.vk[slot] >= 0.0:
        e = slot // (model.fin_half.shape[0] + 1)
        i, j = model.seg[e, 0], model.seg[e, 1]
        w = 1.0 - s
        v2 = 0.0
        for k in range(3):
            v2 += (w * state.v[i, k] + s * state.v[j, k] - state.mv[k]) ** 2
        state.acc[A_SKIPPED] += (w * model.mass[i] + s * model.mass[j]) * np.sqrt(v2)
        if state.acc[A_CROSS] == 1.0:
            state.acc[A_TUN_PART] = part
            state.acc[A_TUN_SPEED] = np.sqrt(v2)
            state.acc[A_TUN_STEP] = step
    state.vk[slot] = -1.0
    return OK if model.allow_tunnel else TUNNEL


@njit(cache=True, _nrt=False)
def segment_contacts(model, state, wk, segs, masks, dt, apply, step):
    """All contacts of the capsules ``segs`` (ends wk.pbn in B) with the missile's parts, in
    that order; dead segments have none (their slots reset when applying).

    masks[c]: the parts to test for segs[c] (``_part_mask`` bits; an empty ``masks``: every
    part); a part left out is treated as its failed gate (no contact, slot reset), which
    ``_part_mask`` proves it is. apply: add forces (``_apply``) and update the contact slots;
    otherwise only measure. One call per list, not per segment: a call that binds the model,
    state and work records costs ~0.25 µs even inlined (module docstring, call cost).
    Returns (stored contact energy Σ U(δ) [J], status, number of contacts)."""
    nf = model.fin_half.shape[0]
    rad = model.rope_radius
    energy = 0.0
    ncon = 0
    nb, qb = wk.nb, wk.qb
    for c in range(segs.shape[0]):
        e = segs[c]
        base = e * (1 + nf)
        if not state.alive[e]:
            if apply:
                for p in range(base, base + 1 + nf):
                    state.vk[p] = 0.0
            continue
        mask = masks[c] if masks.shape[0] > 0 else ALL_PARTS
        pa, pb = wk.pbn[model.seg[e, 0]], wk.pbn[model.seg[e, 1]]
        u_e = 0.0  # this segment's energy, then added: the sums of one call per segment
        # body of revolution (one convex solid: body + nose)
        if mask & 1 and _body_gap(_axis_distance(pa, pb), model.nose_cones, rad, pa, pb,
                                  model.bbox[3]) <= 0.0:
            d, s, nb[0], nb[1], nb[2], qb[0], qb[1], qb[2], part = segment_body_closest(
                pa, pb, model.prof_kind, model.prof_data, model.prof_part, rad)  # d ≥ rad: no contact (exact)
            delta = rad - d
            if d <= 0.0:
                if apply and _tunnel(model, state, base, part, s, step) == TUNNEL:
                    return energy + u_e, TUNNEL, ncon
            elif delta > 0.0:
                ncon += 1
                u_e += _pair_contact(model, state, wk, base, -1, (pa, pb, s, delta, d), dt, apply)
                if apply:
                    _book_penetration(state.acc, delta, delta / rad)
            elif apply:
                state.vk[base] = 0.0
        elif apply:
            state.vk[base] = 0.0
        for fi in range(nf):
            slot = base + 1 + fi
            if not mask & (1 << (fi + 1)) or _fin_gap(wk.fin_pl, fi, wk.fin_rh[fi], pa, pb) > 0.0:
                if apply:
                    state.vk[slot] = 0.0
                continue
            dist, s, qu, qv, crossed = segment_core_closest(pa, pb, model.fin_origin[fi], model.fin_axes[fi],
                                                            model.fin_core[fi, :model.fin_ncore[fi]])
            ax = model.fin_axes[fi]
            for k in range(3):
                qb[k] = model.fin_origin[fi, k] + qu * ax[0, k] + qv * ax[1, k]
            half = model.fin_half[fi]
            if crossed:  # (the undeformed core: a moving fin's |w| < r + h/2, model.with_fin_motion)
                if qb[1] * qb[1] + qb[2] * qb[2] < model.bbox[3] * model.bbox[3]:
                    continue  # through the root extension, i.e. inside the body: booked by the body above
                if apply and _tunnel(model, state, slot, FIN_PART_OFFSET + fi, s, step) == TUNNEL:
                    return energy + u_e, TUNNEL, ncon
                continue
            delta = rad + half - dist
            if wk.fin_rh[fi] - dist <= 0.0:  # (fin_rh = r + h/2 (+ a moving fin's largest |w|): ≡ delta ≤ 0 if rigid)
                if apply:
                    state.vk[slot] = 0.0
                continue
            ncon += 1
            u_e += _pair_contact(model, state, wk, slot, fi, (pa, pb, s, delta, dist), dt, apply)
            if apply:
                _book_penetration(state.acc, delta, delta / (rad + half))
        energy += u_e
    return energy, OK, ncon


@njit(cache=True, inline="always")  # (module docstring: call cost)
def _book_penetration(acc, delta, ratio):
    if delta > acc[A_PEN]:
        acc[A_PEN] = delta
    if delta > acc[A_PEN_INT]:
        acc[A_PEN_INT] = delta
    if ratio > acc[A_PEN_RATIO]:
        acc[A_PEN_RATIO] = ratio


@njit(cache=True, _nrt=False)
def _rope_forces(model, state, wk, dt, segs, count, air):
    """Rope tensions of the segments ``segs[:count]`` into wk.f (Eq. (1)–(4)) and, with ``air``
    and ``collide.air``, the rope's air force (Eq. (5)–(8), ``collide.air``), their dissipation
    booked over dt [s]; breaks segments past their breaking stretch. (With the far net in windows
    the air comes from ``_air_impulse`` instead: ``air`` False.)"""
    x, v, seg, f = state.x, state.v, model.seg, wk.f
    diss = state.acc[A_DISS_ROPE]  # a local sum (as ``_integrate``); nothing else writes it here
    for c in range(count):
        e = segs[c]
        if not state.alive[e]:
            continue
        i, j = seg[e, 0], seg[e, 1]
        t, u0, u1, u2, lf, ldot, stretch = spring_force(
            (x[j, 0] - x[i, 0], x[j, 1] - x[i, 1], x[j, 2] - x[i, 2]), (v[j, 0] - v[i, 0], v[j, 1] - v[i, 1],
            v[j, 2] - v[i, 2]), 0.0, (model.rest[e], model.k[e], model.c[e], model.off[e]))
        if stretch > model.break_stretch[e]:
            u_c, _, _ = segment_contacts(model, state, wk, segs[c:c + 1], segs[:0], dt, False, 0)  # (no masks:
            # every part; an empty view, as this function may not allocate)
            state.alive[e] = False
            state.acc[A_NBROKEN] += 1.0
            state.acc[A_BROKEN] += rope_elastic_energy(stretch, model.k[e]) + u_c
            continue
        if t > 0.0:
            f[i, 0] += t * u0
            f[i, 1] += t * u1
            f[i, 2] += t * u2
            f[j, 0] -= t * u0
            f[j, 1] -= t * u1
            f[j, 2] -= t * u2
        # the dashpot's share T − K s: also when T is cut to 0 (a stretched rope contracting so
        # fast that K s + c l̇ < 0 cannot push), the dashpot then takes the spring's −K s l̇ > 0
        diss += (t - model.k[e] * max(stretch, 0.0)) * ldot * dt
        if air:
            segment_air(model, state, f, e, (u0, u1, u2), lf, dt, 1.0)  # collide.air (no-op when off)
    state.acc[A_DISS_ROPE] = diss


@njit(cache=True, _nrt=False)
def _air_impulse(model, state, f, scale, dt):
    """``scale`` × the air force (Eq. (5)–(8), ``collide.air``) on every live segment into f [N]
    (n, 3), booked as acting over dt [s] (``_far_window``: the impulse of the next air_every
    windows)."""
    x, seg = state.x, model.seg
    for e in range(seg.shape[0]):
        if not state.alive[e]:
            continue
        i, j = seg[e, 0], seg[e, 1]
        d0, d1, d2 = x[j, 0] - x[i, 0], x[j, 1] - x[i, 1], x[j, 2] - x[i, 2]
        lf = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        if lf > 0.0:
            segment_air(model, state, f, e, (d0 / lf, d1 / lf, d2 / lf), lf, dt, scale)


@njit(cache=True, _nrt=False)
def _step_contacts(model, state, wk, dt, step):
    """Contacts of the candidate segments (the others cannot touch: ``_build_candidates``), in
    increasing segment order as over all segments. Returns (status, contacts)."""
    n = wk.ncand[0]
    _, status, ncon = segment_contacts(model, state, wk, wk.cand[:n], wk.cmask[:n], dt, True, step)
    return status, ncon


@njit(cache=True)
def _integrate(model, state, wk, dt):
    """Missile and the fast free nodes (every node at single rate) one step (symplectic Euler);
    fast held nodes book their impulse. The
    sums are kept in locals (same additions in the same order as into ``state.acc``, which the
    compiler must otherwise reload and store at every node: it cannot rule out aliasing)."""
    x, v, g, f, fmt, acc = state.x, state.v, model.gravity, wk.f, wk.fmt, state.acc
    wg = acc[A_WORK_GRAVITY]
    for k in range(3):
        wg += model.m_mass * g[k] * state.mv[k] * dt
    body = RigidBody(state.mx, state.mv, state.mq, state.mh, model.m_mass, model.inv_inertia)
    rigid_step(body, fmt[:3], fmt[3:], dt)
    h0, h1, h2 = acc[A_PHELD], acc[A_PHELD + 1], acc[A_PHELD + 2]
    for c in range(wk.nlist[2]):
        i = wk.fnode[c]
        if model.free[i]:
            a = dt / model.mass[i]
            for k in range(3):
                wg += model.mass[i] * g[k] * v[i, k] * dt
                v[i, k] += a * f[i, k]
                x[i, k] += dt * v[i, k]
        else:
            h0 += f[i, 0] * dt
            h1 += f[i, 1] * dt
            h2 += f[i, 2] * dt
    acc[A_WORK_GRAVITY] = wg
    acc[A_PHELD], acc[A_PHELD + 1], acc[A_PHELD + 2] = h0, h1, h2


STICK_FRACTION = 0.5
"""[-] The friction impulse of one step removes at most this fraction of a contact point's slip
(``contact.law.friction_force``, ``stick``), the damping impulse at most this fraction of its
normal approach speed (``contact.law.normal_force``, ``damp_cap``): below 1 so that the two
contacts of a node shared by two pieces on one fin edge do not together reverse it."""


@njit(cache=True)
def _book_mean_velocity(model, state, wk, mv0, dt):
    """Book the contact damping and friction at the step's mean velocity (module doc, step 3).

    A force F applied over the step does the work F·v̄ dt, v̄ = v + ½ Δv the mean of the velocities
    before and after the step (the exact change of ½ m v² under symplectic Euler); ``_apply``
    booked −F·v dt at the start velocity. This adds −½ dt F·Δv to each dissipation: Δv = dt f/m
    for a free node (wk.fd rows, cleared here; only nodes of candidate segments carry contact
    forces), the missile's change of velocity and rotation rate against wk.md (mv0 [m/s] (3,) its
    velocity and wk.w_w [rad/s] its rate before the step). Called after ``_integrate``. Without it
    the booking misses ½ dt² F·a per step, a first-order energy error that is largest where it
    matters (light rope pieces struck at 500 m/s: 0.4 % of the energy exchanged, +7 J in 10 µs)."""
    fd, f, seg, cand = wk.fd, wk.f, model.seg, wk.cand
    cd = 0.0
    cf = 0.0
    for c in range(wk.ncand[0]):
        for end in range(2):
            n = seg[cand[c], end]
            if not model.free[n]:
                continue
            a = dt / model.mass[n]
            for k in range(3):
                cd += fd[n, k] * f[n, k] * a
                cf += fd[n, 3 + k] * f[n, k] * a
            for k in range(6):
                fd[n, k] = 0.0
    w1 = _world_rate(quat_to_matrix(state.mq), state.mh, model.inv_inertia)
    md = wk.md
    for k in range(3):
        dv = state.mv[k] - mv0[k]
        dw = w1[k] - wk.w_w[k]
        cd += md[k] * dv + md[3 + k] * dw
        cf += md[6 + k] * dv + md[9 + k] * dw
    for k in range(12):
        md[k] = 0.0
    state.acc[A_DISS_CONTACT] -= 0.5 * dt * cd
    state.acc[A_DISS_FRICTION] -= 0.5 * dt * cf


FAR_BOUND_FACTOR = 2.0
"""The far net's window bound (``_far_window``) is this × the window × the largest speed of a node
relative to the missile's frame at the window's start: a margin for the speeds' change within the
window (slow nodes move at constant velocity; the missile's rate and speed change by < 1e-4 of
themselves in a window of the paper cases). A node that still moves farther stops the run (FAR)."""


@njit(cache=True, _nrt=False)
def _far_check(model, state, wk, alln):
    """Every node's position in B into wk.pbn (wk.r must hold the attitude); True when one has
    moved farther since the window's start than its bound wk.dfar."""
    _, far = _to_body(model, state, wk, alln, alln.shape[0])
    return far


REFRESH_SHARE = 0.25
"""A far-net split that had to evaluate ``_clearance`` again for more than this share of the live
segments (their kept clearance, less their ends' displacements since, no longer proves them slow)
asks the next split to evaluate every segment afresh (``StepWork.refresh``): about the same cost
once, and the kept bounds are tight again."""


@njit(cache=True, _nrt=False)
def _far_split(model, state, wk, d):
    """Split the live segments (positions in B: wk.pbn) into fast (clearance ≤ d [m]: may touch a
    part within the window; or ``model.always_fast``) and slow, in increasing order, with the fast nodes; the segments that
    turn slow have their contact slots reset (they cannot touch) and every node of a slow segment
    gets the bound d. A full split (wk.refresh[0] ≠ 0: a new work, or REFRESH_SHARE) evaluates
    ``_clearance`` for every segment and keeps it in wk.cseg with the positions in wk.pfull;
    otherwise a segment whose kept clearance, less the larger of its ends' displacements since
    (1-Lipschitz, module docstring), still exceeds d is slow without a new evaluation. Either way
    the split is the same (each segment's test is exact about c ≤ d); the work is kept across
    calls, so a call's first window no longer pays for a full split (0.6 ms on radar × traction's
    9 561 segments, once per fin-load interval)."""
    full = wk.refresh[0] != 0
    if full:
        wk.refresh[0] = 0
        wk.refresh[1] += 1
    n_eval, n_live = 0, 0
    nf = model.fin_half.shape[0]
    seg, alive, pbn, isfast, cseg, pfull = model.seg, state.alive, wk.pbn, wk.isfast, wk.cseg, wk.pfull
    pinned = model.always_fast
    n_pinned = pinned.shape[0]
    n = pbn.shape[0]
    dmov = wk.dfull
    for i in range(n):
        if full:
            pfull[i, 0], pfull[i, 1], pfull[i, 2] = pbn[i, 0], pbn[i, 1], pbn[i, 2]
            dmov[i] = 0.0
        else:
            dmov[i] = np.sqrt((pbn[i, 0] - pfull[i, 0]) ** 2 + (pbn[i, 1] - pfull[i, 1]) ** 2
                              + (pbn[i, 2] - pfull[i, 2]) ** 2)
    for c in range(wk.nlist[0]):  # the last window's fast segments: reset below if they turn slow
        wk.wasfast[wk.fseg[c]] = True
    isfast[:] = False
    nfs, nss = 0, 0
    for e in range(seg.shape[0]):
        if not alive[e]:
            continue
        i, j = seg[e, 0], seg[e, 1]
        n_live += 1
        if full:
            cseg[e] = _clearance(model.bbox, model.rope_radius, wk.fin_pl, wk.fin_rh, model.nose_cones, pbn[i],
                                 pbn[j], d)
            c = cseg[e]
        else:
            c = cseg[e] - max(dmov[i], dmov[j])
            if c <= d:
                n_eval += 1
                c = _clearance(model.bbox, model.rope_radius, wk.fin_pl, wk.fin_rh, model.nose_cones, pbn[i],
                               pbn[j], d)
        if c <= d or (e < n_pinned and pinned[e]):
            wk.fseg[nfs] = e
            nfs += 1
            isfast[i] = True
            isfast[j] = True
        else:
            wk.sseg[nss] = e
            nss += 1
            if wk.wasfast[e]:
                for p in range(e * (1 + nf), (e + 1) * (1 + nf)):
                    state.vk[p] = 0.0
        wk.wasfast[e] = False
    nfn = 0
    for i in range(n):
        wk.pwin[i, 0], wk.pwin[i, 1], wk.pwin[i, 2] = pbn[i, 0], pbn[i, 1], pbn[i, 2]
        wk.dfar[i] = np.inf
        if isfast[i]:
            wk.fnode[nfn] = i
            nfn += 1
            wk.marg2[i] = 0.0  # the window's first step rebuilds the candidate list
    for c in range(nss):
        e = wk.sseg[c]
        wk.dfar[seg[e, 0]] = d
        wk.dfar[seg[e, 1]] = d
    wk.nlist[0], wk.nlist[1], wk.nlist[2] = nfs, nss, nfn
    if n_eval > REFRESH_SHARE * n_live:
        wk.refresh[0] = 1


@njit(cache=True, _nrt=False)
def _far_window(model, state, wk, alln, w, dt):
    """Start a window of w steps of dt [s] (module docstring, "Far net"): check the last window's
    bounds, split the segments (``_far_split``) with the bound d = FAR_BOUND_FACTOR × w dt × the
    largest node speed relative to the missile's frame, and give the slow segments' forces (and
    gravity on the slow nodes) as one impulse over the window, w dt × F: slow nodes are then moved
    over the whole window at once (they feel no other force), fast nodes take the impulse and go
    on step by step. wk.r, wk.w_w must hold the missile's attitude and rate. Returns OK or FAR."""
    if _far_check(model, state, wk, alln):
        return FAR
    x, v, mv, mx, w_w, acc, g = state.x, state.v, state.mv, state.mx, wk.w_w, state.acc, model.gravity
    tw = w * dt
    wmag = np.sqrt(w_w[0] ** 2 + w_w[1] ** 2 + w_w[2] ** 2)
    vmax = 0.0
    for i in range(x.shape[0]):
        rel = np.sqrt((v[i, 0] - mv[0]) ** 2 + (v[i, 1] - mv[1]) ** 2 + (v[i, 2] - mv[2]) ** 2)
        arm = np.sqrt((x[i, 0] - mx[0]) ** 2 + (x[i, 1] - mx[1]) ** 2 + (x[i, 2] - mx[2]) ** 2)
        vmax = max(vmax, rel + wmag * arm)
    _far_split(model, state, wk, FAR_BOUND_FACTOR * vmax * tw)
    f, isfast = wk.f, wk.isfast
    for i in range(x.shape[0]):
        for k in range(3):
            f[i, k] = 0.0 if isfast[i] else model.mass[i] * g[k]
    _rope_forces(model, state, wk, tw, wk.sseg, wk.nlist[1], False)
    if model.air_density > 0.0 and acc[A_AIR_PAID] < 0.5 * tw:
        # the air on every live segment (slow and fast), one impulse for air_every windows: its
        # rate is ~3e-4 per window (simulate.air_windows), so its force hardly changes meanwhile
        _air_impulse(model, state, f, model.air_every, model.air_every * tw)
        acc[A_AIR_PAID] += model.air_every * tw
    acc[A_AIR_PAID] -= tw
    wg = acc[A_WORK_GRAVITY]
    for i in range(x.shape[0]):
        if not model.free[i]:
            for k in range(3):
                acc[A_PHELD + k] += f[i, k] * tw
            continue
        a = tw / model.mass[i]
        for k in range(3):
            if not isfast[i]:
                wg += model.mass[i] * g[k] * v[i, k] * tw
            v[i, k] += a * f[i, k]
            if not isfast[i]:
                x[i, k] += tw * v[i, k]
    acc[A_WORK_GRAVITY] = wg
    acc[A_FAST_SEG_STEPS] += wk.nlist[0] * w
    return OK


@njit(cache=True)
def _fine_step(model, state, wk, dt, step, mv0, air):
    """One step of the fast segments and nodes (all of them at single rate) and the missile: rope
    forces (with their air when ``air``: single rate), contacts, symplectic Euler, dissipation at
    the mean velocity. Returns the status."""
    f, fmt, w_w, acc = wk.f, wk.fmt, wk.w_w, state.acc
    wk.r[:, :] = quat_to_matrix(state.mq)
    r = wk.r
    w_w[0], w_w[1], w_w[2] = _world_rate(r, state.mh, model.inv_inertia)
    for k in range(3):
        fmt[k] = model.m_mass * model.gravity[k]
        fmt[3 + k] = 0.0
    for c in range(wk.nlist[2]):
        i = wk.fnode[c]
        for k in range(3):
            f[i, k] = model.mass[i] * model.gravity[k]
    rebuild, far = _to_body(model, state, wk, wk.fnode, wk.nlist[2])
    if far:
        return FAR
    if rebuild:
        _build_candidates(model, state, wk)
    _rope_forces(model, state, wk, dt, wk.fseg, wk.nlist[0], air)
    status, ncon = _step_contacts(model, state, wk, dt, step)
    if status != OK:
        return status
    if ncon > acc[A_NCONTACT]:
        acc[A_NCONTACT] = ncon
    g = model.gravity
    b0, b1, b2 = _rtv(r, fmt[0] - model.m_mass * g[0], fmt[1] - model.m_mass * g[1], fmt[2] - model.m_mass * g[2])
    acc[A_IMP_B] += b0 * dt
    acc[A_IMP_B + 1] += b1 * dt
    acc[A_IMP_B + 2] += b2 * dt
    for k in range(3):
        mv0[k] = state.mv[k]
    _integrate(model, state, wk, dt)
    _book_mean_velocity(model, state, wk, mv0, dt)
    acc[A_TIME] += dt
    if not (np.isfinite(state.mx[0]) and np.isfinite(state.mv[2])):
        return NONFINITE
    return OK


@njit(cache=True)
def _advance(model, state, wk, n_steps, dt, ratio, horizon):
    n = state.x.shape[0]
    alln = np.arange(n)
    acc = state.acc
    for k in range(3):
        acc[A_IMP_B + k] = 0.0
    acc[A_PEN_INT] = 0.0
    acc[A_NCONTACT] = 0.0
    acc[A_FCONTACT] = 0.0
    mv0 = np.empty(3)
    step = 0
    while step < n_steps:
        run = n_steps - step
        if ratio > 1:
            if wk.win[0] == 0:  # open a window: at most ratio steps, ending by the horizon
                w = min(ratio, horizon - step)
                wk.r[:, :] = quat_to_matrix(state.mq)
                wk.w_w[0], wk.w_w[1], wk.w_w[2] = _world_rate(wk.r, state.mh, model.inv_inertia)
                if _far_window(model, state, wk, alln, w, dt) != OK:
                    return FAR
                wk.win[0] = w
            run = min(run, wk.win[0])
        for s in range(step, step + run):
            status = _fine_step(model, state, wk, dt, s, mv0, ratio <= 1)
            if status != OK:
                return status
        step += run
        if ratio > 1:
            wk.win[0] -= run
    wk.r[:, :] = quat_to_matrix(state.mq)
    if ratio > 1 and wk.win[0] == 0 and _far_check(model, state, wk, alln):  # (an open window's
        return FAR                                                              # at its end)
    for i in range(n):
        if not (np.isfinite(state.x[i, 0]) and np.isfinite(state.x[i, 1]) and np.isfinite(state.x[i, 2])):
            return NONFINITE
    acc[A_U_CONTACT] = _stored_contact_energy(model, state, wk)
    return OK


@njit(cache=True)
def _stored_contact_energy(model, state, wk):
    """Σ U(δ) [J] of the contacts at the end of a call, from the candidate list: the list is made
    valid at the final positions as a step would (rebuilt if a fast node reached its margin), and
    the slow segments cannot touch (the window's bound, just checked). The same pairs in the same
    order as ``energies``' scan of every segment near the missile, which adds only zeros besides:
    the same sum to the last bit (tests/collide/test_far_net.py). wk.r must hold the attitude."""
    rebuild, _ = _to_body(model, state, wk, wk.fnode, wk.nlist[2])
    if rebuild:
        _build_candidates(model, state, wk)
    n = wk.ncand[0]
    u_c, _, _ = segment_contacts(model, state, wk, wk.cand[:n], wk.cmask[:n], 0.0, False, 0)
    return u_c


@njit(cache=True)
def advance(model, state, n_steps, dt, ratio=1):
    """Advance ``state`` (``model.CollideState``) in place by ``n_steps`` steps of ``dt`` [s]
    under ``model`` (``model.CollideModel``), the far net in windows of ``ratio`` steps (module
    docstring, "Far net"; 1: every segment every step), with a new work (``advance_kept``: a kept
    one). Returns the status OK, TUNNEL (a rope
    centre line reached a part's core and the model does not allow it; ``state.acc[A_TUN_*]``
    say where), FAR (a node moved farther in a window than its bound) or NONFINITE. Subnormal floats are flushed to zero during the call (``collide.fpu``); the
    caller's floating-point control register is restored on return."""
    return advance_kept(model, state, _work(model, state.x.shape[0]), n_steps, dt, ratio, n_steps)


@njit(cache=True)
def new_work(model, state):
    """The loop's scratch (``StepWork``) for ``model`` and ``state``'s nodes, to pass to every
    ``advance_kept`` call while the model, its node count and the window ``ratio`` stay the same."""
    return _work(model, state.x.shape[0])


@njit(cache=True)
def advance_kept(model, state, wk, n_steps, dt, ratio, horizon):
    """``advance`` with the work ``wk`` (``new_work``) kept from call to call: its far-net
    clearances and candidate list carry over, so a call costs what its steps cost (a new work
    costs a full far-net split and a candidate rebuild over every segment, ≈ 0.8 ms on radar ×
    traction — once per fin-load interval); every kept bound is re-checked, not trusted.

    horizon ≥ n_steps: the steps from this call's start to the next time at which every far-net
    window must have ended (the caller reads the whole net's state there: the output interval's
    end). A window opened in this call may then run on into the next calls: the fin-load
    intervals (``collide.load_interval``) no longer cut the windows short. Between two such calls
    the slow nodes stand at their window's end (they move once per window); only the fast nodes
    and the contacts may be read there. Calls of n steps with horizon H give the run of calls of H
    steps to the last bit (tests/collide/test_far_net.py)."""
    old = get_mxcsr()
    set_mxcsr(old | np.uint32(FTZ_DAZ))
    status = _advance(model, state, wk, n_steps, dt, ratio, horizon)
    set_mxcsr(old)
    return status


@njit(cache=True)
def net_energies(model, state):
    """(net kinetic, rope elastic) [J] of the state; held nodes are at rest."""
    x, v = state.x, state.v
    ke = 0.0
    for i in range(x.shape[0]):
        if model.free[i]:
            ke += 0.5 * model.mass[i] * (v[i, 0] ** 2 + v[i, 1] ** 2 + v[i, 2] ** 2)
    pe = 0.0
    for e in range(model.seg.shape[0]):
        if not state.alive[e]:
            continue
        i, j = model.seg[e, 0], model.seg[e, 1]
        ln = np.sqrt((x[j, 0] - x[i, 0]) ** 2 + (x[j, 1] - x[i, 1]) ** 2 + (x[j, 2] - x[i, 2]) ** 2)
        pe += rope_elastic_energy(ln - (model.rest[e] - model.off[e]), model.k[e])
    return ke, pe


@njit(cache=True)
def fin_gaps(model, state):
    """A lower bound [m] (ns,) of each live segment's gap to the nearest fin (``_fin_gap``: its
    capsule's distance to the fin's core − r − h/2, ≤ 0 when it touches), in the missile's frame;
    inf for a broken segment or a missile without fins (``collide.adapt``: the pieces about to
    press). A fin whose mid-plane term alone (a lower bound of its ``_fin_gap``) is not below the
    smallest gap found so far cannot lower it and is not evaluated further: the same minimum as
    every fin evaluated (``_clearance``'s rule)."""
    ns, nf = model.seg.shape[0], model.fin_half.shape[0]
    out = np.full(ns, np.inf)
    if nf == 0:
        return out
    pbn = _body_positions(model, state)
    fin_pl = _fin_half_spaces(model)
    fin_rh = _fin_reach(model)
    for e in range(ns):
        if not state.alive[e]:
            continue
        pa, pb = pbn[model.seg[e, 0]], pbn[model.seg[e, 1]]
        best = np.inf
        for fi in range(nf):
            fp = fin_pl[fi]
            da = pa[0] * fp[0, 0] + pa[1] * fp[0, 1] + pa[2] * fp[0, 2] - fp[0, 3]
            db = pb[0] * fp[0, 0] + pb[1] * fp[0, 1] + pb[2] * fp[0, 2] - fp[0, 3]
            if da * db > 0.0 and min(abs(da), abs(db)) - fin_rh[fi] >= best:
                continue  # _fin_gap ≥ its plane term − rh ≥ best
            best = min(best, _fin_gap(fin_pl, fi, fin_rh[fi], pa, pb))
        out[e] = best
    return out


@njit(cache=True)
def energies(model, state):
    """(net kinetic, rope elastic, contact stored) [J] of any state, every segment near the missile
    tested. After ``advance`` the contact stored energy is also in state.acc[A_U_CONTACT], from the
    call's candidate list (the same value, at a fraction of the cost: ``_stored_contact_energy``)."""
    ke, pe = net_energies(model, state)
    wk = _measure_work(model, _body_positions(model, state))
    near = np.empty(model.seg.shape[0], np.int64)
    nn = 0
    for e in range(model.seg.shape[0]):
        if state.alive[e] and _near_missile(model, wk.pbn[model.seg[e, 0]], wk.pbn[model.seg[e, 1]]):
            near[nn] = e
            nn += 1
    uc, _, _ = segment_contacts(model, state, wk, near[:nn], np.zeros(0, np.int64), 0.0, False, 0)
    return ke, pe, uc
