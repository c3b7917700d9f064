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
and segment e keeps being the parent's first piece. The snapshots and the result's ``net`` are the
net as cut at the start: a segment cut during the run is drawn as its chord (its pieces lie on it
when cut; later they bend), and its ``alive`` flag is its first piece's.
"""
from __future__ import annotations

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

