"""Rope pieces cut while they press on a fin: ``[collide] fin_piece_chord``.

Why: the paper's rope (E = 1 MPa) is stretched ~10× at the fins (docs/collide_convergence.md,
thirteenth pass): a piece cut to 0.7 mm at collision start presses on a rudder's rounded edge at
up to 10 mm, seven times the chord (r + h/2)/3 that the rudder-tip friction lock needs resolved,
and the headlines then converge only at 0.1 mm pieces everywhere near the fins (8 min of CPU).
Cutting only the pieces that actually press, when they press, gives the rope its resolution where
the contact is, at a fraction of that cost.

Rule (between two output intervals, ``simulate._drive``): every segment that pressed on a fin
during the interval with an impulse-weighted chord c (``CollideState.fin_len``) longer than the
target chord L, and every segment whose chord c is now longer than L among the rope neighbours of
a pressing segment (sharing a node with it: the rope that slides onto the fin next) and the
segments within two intervals' travel of a fin (``kernel.fin_gaps``: the rope about to be struck),
is cut into n = min(⌈c / L⌉, 8) equal pieces (:func:`cut_live`, ``simulate.CUT_MAX``: a long
segment near a fin is cut progressively, its pieces near the fin again at the next interval). A
piece that stretches further is cut again at a later interval.

How a live segment i–j is cut into n pieces (the same rope as ``collide.refine.split_at`` makes
at collision start, applied to the moving state):

* new nodes on the chord at fractions m/n, velocities interpolated linearly between v_i and v_j;
* rest length, slack offset and breaking stretch × 1/n, stiffness EA/l0 × n (E·A kept), dashpot
  by the rope's damping law (``refine._piece_damping``), air diameter kept;
* the segment's rope mass λ l0 (λ = ρA) re-lumped piece by piece (each end keeps 1/(2n), each new
  node 1/n). With linear velocities the trapezoid rule is exact: **momentum is unchanged** to
  round-off. Kinetic energy falls by (λ l0 / 12)(1 − 1/n²)|v_j − v_i|² (the lumped mass of a
  linear velocity field converging to the continuous one), the rope's elastic energy is
  unchanged (uniform stretch), and the contact stored energy changes because the new pieces touch
  where the chord's single closest point did not: the total change ΔE is booked in
  ``acc[A_REFINE]`` (−ΔE; history column ``rope_refinement_j``), so the energy balance closes and
  the cut's effect is on the record;
* the parent's contact-slot memory (largest approach speed, ``vk``) is copied to every piece: a
  contact in progress keeps its damping law (Eq. (29)).

The cut changes the model: the step is chosen again (``timestep.choose_step``: the lighter nodes
shorten the contact limit). The pieces are stiffer than the rest of the rope; they are stepped
every step (``CollideModel.always_fast``), so the far-net window (``simulate.far_ratio``) stays
set by the uncut rope's stiffest segment and grows as the step shrinks. Nodes and segments are appended: the ids of the existing ones do not change,
and segment e keeps being the parent's first piece.

Rope that has left the fins is merged back (:func:`merge_roots`, rule in ``simulate._merge_idle``):
once every piece of a start segment is out of contact, ``simulate.MERGE_REACH`` intervals' travel
from every fin and the pieces lie on their chord, the segment is restored as it was at the start
(its rope law; mass and momentum kept, the energy change booked as for a cut). Without it the
pieces of every strand the fins ever touched stay in the run, stepped every step at the contact
step: in radar × traction 3 900 of them from 5 ms on, against ~20 segments near the fins
(docs/performance.md). ``Lineage`` records which start segment each piece belongs to and where. The snapshots and the result's ``net`` are the
net as cut at the start: a segment cut during the run is drawn as its chord (its pieces lie on it
when cut; later they bend), and its ``alive`` flag is its first piece's.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from flexnet_fe.collide import kernel as K
from flexnet_fe.collide import model as M
from flexnet_fe.net.topology import segment_damping


def cut_counts(chord: np.ndarray, target: float) -> np.ndarray:
    """Pieces n = ⌈chord / target⌉ (s,) int64 for segments whose chord [m] (s,) exceeds ``target`` [m]
    (1 where it does not)."""
    return np.maximum(1, np.ceil(chord / target - 1e-12)).astype(np.int64)


def _pinned(always_fast: np.ndarray, n_seg: int, idx: np.ndarray, n_total: int) -> np.ndarray:
    """``always_fast`` (n_seg or 0,) grown to n_total segments, True for the cut segments ``idx``
    (their first pieces) and every appended piece."""
    out = np.zeros(n_total, dtype=np.bool_)
    out[:always_fast.shape[0]] = always_fast
    out[idx] = True
    out[n_seg:] = True
    return out


def _total_energy(km: M.CollideModel, st: M.CollideState) -> float:
    """Net kinetic + rope elastic + contact stored energy [J] of the state (``kernel.energies``)."""
    ke, pe, pc = K.energies(km, st)
    return float(ke + pe + pc)


def cut_live(km: M.CollideModel, st: M.CollideState, idx: np.ndarray, n_piece: np.ndarray, line_density: float,
             damping_law: str, damping_ratio: float) -> tuple[M.CollideModel, M.CollideState, float]:
    """(model, state, ΔE): segments ``idx`` (s,) int64 of the running collision each cut into
    ``n_piece`` (s,) ≥ 2 equal pieces (module docstring); line_density λ = ρA [kg/m] of the rope;
    damping_law "segment" | "material" and ζ [-] as the net's rope (Eq. (4)). ΔE [J] = the change of
    net kinetic + rope elastic + contact stored energy, already booked as −ΔE in acc[A_REFINE]."""
    if idx.size == 0:
        return km, st, 0.0
    e_before = _total_energy(km, st)
    nf = km.fin_half.shape[0]
    a, b = km.seg[idx, 0], km.seg[idx, 1]
    n_new = n_piece - 1
    n_nodes, n_seg = km.mass.shape[0], km.seg.shape[0]
    new_id = n_nodes + np.arange(int(n_new.sum()))
    seg_mass = line_density * km.rest[idx]
    frac = np.concatenate([np.arange(1, n) / n for n in n_piece])  # chord fractions of the new nodes
    rep = np.repeat(np.arange(idx.size), n_new)
    x_new = st.x[a[rep]] + frac[:, None] * (st.x[b[rep]] - st.x[a[rep]])
    v_new = st.v[a[rep]] + frac[:, None] * (st.v[b[rep]] - st.v[a[rep]])
    mass = km.mass.copy()
    shed = 0.5 * seg_mass * (1.0 - 1.0 / n_piece)  # each end keeps 1/(2n) of the segment's mass
    np.add.at(mass, a, -shed)
    np.add.at(mass, b, -shed)
    mass = np.concatenate([mass, (seg_mass / n_piece)[rep]])
    start = np.concatenate([[0], np.cumsum(n_new)])
    chains = [np.concatenate([[a[s]], new_id[start[s]:start[s + 1]], [b[s]]]) for s in range(idx.size)]
    first = np.array([c[:2] for c in chains], dtype=np.int64)  # the parent's slot becomes piece 1
    extra = np.concatenate([np.column_stack([c[1:-1], c[2:]]) for c in chains]).astype(np.int64)
    parent = np.repeat(idx, n_new)  # segment each appended piece comes from
    seg = km.seg.copy()
    seg[idx] = first
    seg = np.concatenate([seg, extra])

    def per_piece(arr: np.ndarray, scale: np.ndarray) -> np.ndarray:
        out = np.concatenate([arr, arr[parent]])
        out[idx] = arr[idx] * scale
        out[n_seg:] *= np.repeat(scale, n_new)
        return out

    inv_n = 1.0 / n_piece.astype(np.float64)
    rest = per_piece(km.rest, inv_n)
    k = per_piece(km.k, n_piece.astype(np.float64))
    pieces = np.concatenate([idx, np.arange(n_seg, seg.shape[0])])
    if damping_law == "material":
        c = per_piece(km.c, n_piece.astype(np.float64))
    else:
        c = np.concatenate([km.c, km.c[parent]])
        c[pieces] = segment_damping(k[pieces], mass[seg[pieces, 0]], mass[seg[pieces, 1]], damping_ratio)
    model = km._replace(
        seg=np.ascontiguousarray(seg), rest=rest, k=k, c=c, off=per_piece(km.off, inv_n),
        break_stretch=per_piece(km.break_stretch, inv_n), mass=mass,
        free=np.concatenate([km.free, np.ones(new_id.size, dtype=np.bool_)]),
        diameter=np.concatenate([km.diameter, km.diameter[parent]]) if km.diameter.size else km.diameter,
        always_fast=_pinned(km.always_fast, n_seg, idx, seg.shape[0]))
    vk = st.vk.reshape(n_seg, 1 + nf)
    grow = np.zeros((extra.shape[0], nf))
    state = st._replace(
        x=np.ascontiguousarray(np.concatenate([st.x, x_new])), v=np.ascontiguousarray(np.concatenate([st.v, v_new])),
        alive=np.concatenate([st.alive, st.alive[parent]]),
        vk=np.ascontiguousarray(np.concatenate([vk, vk[parent]]).ravel()),
        fin_imp=np.concatenate([st.fin_imp, np.zeros((extra.shape[0] * nf, 3))]),
        fin_pt=np.concatenate([st.fin_pt, np.zeros((extra.shape[0] * nf, 3))]),
        fin_w=np.concatenate([st.fin_w, grow.ravel()]), fin_len=np.concatenate([st.fin_len, grow.ravel()]),
        touched=np.concatenate([st.touched, np.zeros(extra.shape[0] * nf, np.int64)]))
    d_e = _total_energy(model, state) - e_before
    state.acc[M.A_REFINE] -= d_e
    return model, state, d_e



class Lineage(NamedTuple):
    """Where each segment of the running model comes from (``cut_live``, ``merge_roots``): root (ns,)
    int64 the segment of the model at collision start it is a piece of (itself if never cut); s0, s1
    (ns,) the piece's span in the root's rest coordinate (0 at the root's first node, 1 at its
    second). A root's first piece keeps the root's index."""

    root: np.ndarray
    s0: np.ndarray
    s1: np.ndarray


def lineage_start(n_seg: int) -> Lineage:
    """Every segment its own root, spanning [0, 1]."""
    return Lineage(np.arange(n_seg, dtype=np.int64), np.zeros(n_seg), np.ones(n_seg))


def lineage_cut(lin: Lineage, idx: np.ndarray, n_piece: np.ndarray) -> Lineage:
    """The lineage after ``cut_live(…, idx, n_piece)``: segment idx[s] keeps its first piece, the other
    n_piece[s] − 1 pieces are appended in order (as ``cut_live`` appends them)."""
    if idx.size == 0:
        return lin
    s0, span = lin.s0[idx], lin.s1[idx] - lin.s0[idx]
    m = np.concatenate([np.arange(1, n) for n in n_piece]).astype(np.float64)
    rep = np.repeat(np.arange(idx.size), n_piece - 1)
    s1 = lin.s1.copy()
    s1[idx] = s0 + span / n_piece
    step = span[rep] / n_piece[rep]
    return Lineage(np.concatenate([lin.root, lin.root[idx][rep]]),
                   np.concatenate([lin.s0, s0[rep] + m * step]),
                   np.concatenate([s1, s0[rep] + (m + 1.0) * step]))


def merge_roots(km: M.CollideModel, st: M.CollideState, km0: M.CollideModel, lin: Lineage, roots: np.ndarray,
                damping_law: str, damping_ratio: float) -> tuple[M.CollideModel, M.CollideState, Lineage, np.ndarray,
                                                                  float]:
    """(model, state, lineage, new segment index (ns_old,) int64 (−1: removed), ΔE): the pieces of each
    root segment ``roots`` (indices into km0, the model at collision start) merged back into that
    segment, the reverse of ``cut_live`` — for rope that has left the fins (``simulate``: the pieces
    are then idle, stepped every step for nothing).

    The pieces' interior nodes are removed; each one's mass m_k and momentum m_k v_k go to the root's
    end nodes a and b in the shares (1 − s_k, s_k), s_k its rest coordinate on the root: **mass and
    momentum are unchanged** to round-off, and a and b get back exactly the root's lumped mass λ l0/2
    each (the trapezoid rule is exact on the linear weights). The root's rope law is the start
    model's (rest length, E·A/l0, slack, breaking stretch, air diameter; the dashpot by the rope's
    damping law with the current end masses, as ``cut_live``). The energy change ΔE (kinetic: the
    pieces' motion relative to the linear field; elastic: the path of the pieces against the chord)
    is booked in ``acc[A_REFINE]`` (−ΔE). The pieces must be intact and out of contact (the
    caller's rule); the start model's nodes keep their indices."""
    roots = np.unique(roots)
    if roots.size == 0:
        return km, st, lin, np.arange(km.seg.shape[0]), 0.0
    if st.ntouched[0]:
        raise ValueError("merge_roots: the fin-load slots of the last call have not been taken")
    e_before = _total_energy(km, st)
    n_seg, n_nodes, nf = km.seg.shape[0], km.mass.shape[0], km.fin_half.shape[0]
    chosen = np.zeros(km0.seg.shape[0], dtype=np.bool_)
    chosen[roots] = True
    pieces = np.flatnonzero(chosen[lin.root])
    inner = pieces[lin.s0[pieces] > 0.0]  # pieces that start at an interior node
    node, s, r = km.seg[inner, 0], lin.s0[inner], lin.root[inner]
    a, b = km0.seg[r, 0], km0.seg[r, 1]
    mass = km.mass.copy()
    mom = km.mass[:, None] * st.v
    m_k = km.mass[node]
    np.add.at(mass, a, (1.0 - s) * m_k)
    np.add.at(mass, b, s * m_k)
    np.add.at(mom, a, ((1.0 - s) * m_k)[:, None] * st.v[node])
    np.add.at(mom, b, (s * m_k)[:, None] * st.v[node])
    ends = np.unique(np.concatenate([a, b]))
    v = st.v.copy()
    v[ends] = mom[ends] / mass[ends, None]
    keep_n = np.ones(n_nodes, dtype=np.bool_)
    keep_n[node] = False
    keep_s = np.ones(n_seg, dtype=np.bool_)
    keep_s[pieces[pieces != lin.root[pieces]]] = False
    new_node = np.cumsum(keep_n) - 1
    new_seg = np.where(keep_s, np.cumsum(keep_s) - 1, -1)
    seg = km.seg.copy()
    rest, k, c, off = km.rest.copy(), km.k.copy(), km.c.copy(), km.off.copy()
    brk, diam = km.break_stretch.copy(), km.diameter.copy()
    seg[roots], rest[roots], k[roots], off[roots] = km0.seg[roots], km0.rest[roots], km0.k[roots], km0.off[roots]
    brk[roots] = km0.break_stretch[roots]
    if diam.size:
        diam[roots] = km0.diameter[roots]
    c[roots] = km0.c[roots] if damping_law == "material" else segment_damping(
        k[roots], mass[seg[roots, 0]], mass[seg[roots, 1]], damping_ratio)
    fast = km.always_fast.copy()
    fast[roots] = False
    model = km._replace(
        seg=np.ascontiguousarray(new_node[seg[keep_s]]), rest=rest[keep_s], k=k[keep_s], c=c[keep_s],
        off=off[keep_s], break_stretch=brk[keep_s], mass=mass[keep_n], free=km.free[keep_n],
        diameter=diam[keep_s] if diam.size else diam, always_fast=fast[keep_s])
    slots = np.repeat(keep_s, nf)
    vk = st.vk.reshape(n_seg, 1 + nf)[keep_s]
    vk[new_seg[roots]] = 0.0
    state = st._replace(
        x=np.ascontiguousarray(st.x[keep_n]), v=np.ascontiguousarray(v[keep_n]), alive=st.alive[keep_s],
        vk=np.ascontiguousarray(vk.ravel()), fin_imp=st.fin_imp[slots], fin_pt=st.fin_pt[slots],
        fin_w=st.fin_w[slots], fin_len=st.fin_len[slots], touched=np.zeros(int(slots.sum()), np.int64))
    s0, s1 = lin.s0.copy(), lin.s1.copy()
    s0[roots], s1[roots] = 0.0, 1.0
    lineage = Lineage(lin.root[keep_s], s0[keep_s], s1[keep_s])
    d_e = _total_energy(model, state) - e_before
    state.acc[M.A_REFINE] -= d_e
    return model, state, lineage, new_seg, d_e
