"""Data of the compiled collision: the model (what does not change) and the state (what does).

Both are NamedTuples of numpy arrays and scalars, so numba compiles ``kernel.advance(model,
state, n_steps, dt)`` against them like a record; Python code reads the same fields by name.
Frames: W world, B missile body (``flexnet_fe.frames``); SI units.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

# -- accumulators ``state.acc`` (float64) -------------------------------------------------------
A_DISS_ROPE = 0  # energy dissipated by rope damping, whole run [J]
A_DISS_CONTACT = 1  # energy dissipated by contact damping, whole run [J]
A_DISS_FRICTION = 2  # energy dissipated by friction, whole run [J]
A_WORK_GRAVITY = 3  # work of gravity on net + missile, whole run [J]
A_BROKEN = 4  # energy released by broken segments (their elastic + contact energy at failure) [J]
A_PHELD = 5  # impulse received by held nodes, whole run, W [N s] (5, 6, 7)
A_IMP_B = 8  # Σ Rᵀ F dt over the call, F the contact force on the missile (no gravity) [N s] (8, 9, 10)
A_PEN = 11  # largest penetration δ of the run [m]
A_PEN_RATIO = 12  # largest δ / (rope radius + core half-thickness) of the run [-] (1 = centre line on the core)
A_NCONTACT = 13  # largest number of simultaneous (segment, part) contacts within the call
A_FCONTACT = 14  # Σ |F_contact| dt over the call [N s]
A_NBROKEN = 15  # segments broken, whole run
A_CROSS = 16  # segment-steps whose centre line crossed a part's core (tunnelling), whole run
A_SKIPPED = 17  # impulse skipped by tunnelling (allowed runs), whole run [N s]: m_eff |v_rel| at each crossing's first step
A_TUN_PART = 18  # part id of the first tunnelling
A_TUN_SPEED = 19  # approach speed of the first tunnelling [m/s]
A_TUN_STEP = 20  # step index (within the call) of the first tunnelling
A_PEN_INT = 21  # largest penetration within the call [m]
A_DISS_AIR = 22  # work done against the air (collide.air), whole run [J]
A_IMP_AIR = 23  # impulse of the air on the net, whole run, W [N s] (23, 24, 25)
A_FAST_SEG_STEPS = 26  # Σ over the steps of the number of fast segments (kernel, far net), whole run
A_U_CONTACT = 27  # contact stored energy Σ U(δ) at the end of the last call [J] (kernel._stored_contact_energy)
A_AIR_PAID = 28  # far net: time the last air impulses covered beyond the current window's start [s] (kernel._far_window)
A_REFINE = 29  # energy taken out by cutting rope pieces during the run, −ΔE, whole run [J] (collide.adapt)
A_DAMP_POINTS = 30  # contact point-steps with a force (each point of the line law counts), whole run
A_DAMP_CAPPED = 31  # of those, the point-steps whose dashpot was capped at the explicit step (contact.law.normal_force)
A_TIME = 32  # time of the state [s]: set by the caller before each call, advanced by dt per step (prescribed fin motion)
A_FIN_WORK = 33  # work of the prescribed fin motion on the rope, Σ F·v_surface dt, whole run [J] (0 with rigid fins)
N_ACC = 34

# -- status codes of ``kernel.advance`` ---------------------------------------------------------
OK, TUNNEL, NONFINITE, FAR = 0, 1, 2, 3


class CollideModel(NamedTuple):
    """What the collision kernel needs and never changes (read-only in the kernel).

    Net (only the active sub-net: free nodes and the held nodes their segments reach):
        seg (ns, 2) int64; rest [m], k = EA/l0 [N/m], c [N s/m], off [m] (ns,) the rope law
        Eq. (1)–(4) (``net.forces.spring_force``); break_stretch [m] (ns,) stretch at which a
        segment's elastic tension reaches the breaking load (inf: unbreakable); mass [kg] (n,);
        free (n,) bool (held nodes do not move); rope_radius r [m].
    Missile: m_mass [kg]; inv_inertia [1/(kg m²)] (3, 3) about the CG in B; cg_b [m] (3,);
        bbox (4,) (x_min, x_max, r_max, R_body) bounding cylinder of all parts in B;
        prof_kind, prof_data, prof_part: body of revolution; fin_origin (nf, 3), fin_axes
        (nf, 3, 3), fin_poly (nf, 4, 2) planform trapezoids (the broad phase's bounds), fin_core
        (nf, kc, 2) and fin_ncore (nf,) the contact cores (tip corners rounded), fin_half (nf,)
        half-thicknesses (``missile.shapes.ShapeArrays``); fin_planes (nf, 7) broad phase
        (``scene.fin_planes``).
    Contact (``contact.law``): k_body, k_fin [N/m^m] stiffness K of Eq. (28) per part kind;
        exponent m; damp_c [-] the damping model's χ·v_k (Eq. (29): χ = damp_c / v_k);
        v_floor [m/s] smallest v_k; mu, v_reg [m/s] friction Eq. (32);
        allow_tunnel: finish a tunnelling run (else stop); gravity (3,) [m/s²] W.
    Broad phase: nose_cones (nc, 2) (r0 [m], k [-]) cones ρ ≤ r0 + k s that contain the body
        (``missile.shapes.nose_cones``; station s = −x_b; empty: the bounding cylinder alone).
    Air (``collide.air``): air_density ρ [kg/m³] (0: no air, the default); diameter [m] (ns,)
        each segment's aerodynamic diameter (Eq. (5)–(8), ``collide.air``; empty when ρ = 0);
        air_every (≥ 1): with the far net in windows (``advance`` ratio > 1) the air acts on every
        live segment as one impulse per air_every windows (``kernel._far_window``).
    Far net: always_fast (ns,) bool, segments stepped every step whatever their clearance — the
        pieces cut during the run (``collide.adapt``), stiffer than the rest, so the far window
        stays set by the uncut rope (empty: none).
    Line contact (``collide.contact_law = "line"``, ``contact.stiffness.line_stiffness``):
        line_law: the linear line-load law q = k_l δ [N per metre of rest length] integrated along
        each segment by the midpoint rule on points h apart (``kernel._line_contact``);
        kl_body, kl_fin (nf,) [N/m²] k_l per part; line_h_body, line_h_fin (nf,) [m] the spacing h
        per part. False: Eq. (28) once per segment at its closest point (``contact_law = "segment"``).
    Prescribed fin motion (the one-way check, ``FinMotion``; line law only; empty: rigid fins):
        fin_motion_t0 (nf,) [s], fin_motion_dt [s], fin_motion_nt (nf,), fin_motion_offset (nf + 1,),
        fin_motion_grid (nf, 4) [m], fin_motion_w (rows, nu, nv) [m] as ``FinMotion``'s fields;
        fin_wmax (nf,) [m] each fin's largest |w| (the broad phase's bounds widen by it).
    """

    seg: np.ndarray
    rest: np.ndarray
    k: np.ndarray
    c: np.ndarray
    off: np.ndarray
    break_stretch: np.ndarray
    mass: np.ndarray
    free: np.ndarray
    rope_radius: float
    m_mass: float
    inv_inertia: np.ndarray
    cg_b: np.ndarray
    bbox: np.ndarray
    prof_kind: np.ndarray
    prof_data: np.ndarray
    prof_part: np.ndarray
    fin_origin: np.ndarray
    fin_axes: np.ndarray
    fin_poly: np.ndarray
    fin_core: np.ndarray
    fin_ncore: np.ndarray
    fin_half: np.ndarray
    fin_planes: np.ndarray
    k_body: float
    k_fin: float
    exponent: float
    damp_c: float
    v_floor: float
    mu: float
    v_reg: float
    allow_tunnel: bool
    gravity: np.ndarray
    air_density: float = 0.0
    diameter: np.ndarray = np.zeros(0)
    nose_cones: np.ndarray = np.zeros((0, 2))
    air_every: int = 1
    always_fast: np.ndarray = np.zeros(0, np.bool_)
    line_law: bool = False
    kl_body: float = 0.0
    kl_fin: np.ndarray = np.zeros(0)
    line_h_body: float = np.inf
    line_h_fin: np.ndarray = np.zeros(0)
    fin_motion_t0: np.ndarray = np.zeros(0)
    fin_motion_dt: float = 1.0
    fin_motion_nt: np.ndarray = np.zeros(0, np.int64)
    fin_motion_offset: np.ndarray = np.zeros(0, np.int64)
    fin_motion_grid: np.ndarray = np.zeros((0, 4))
    fin_motion_w: np.ndarray = np.zeros((0, 2, 2))
    fin_wmax: np.ndarray = np.zeros(0)


class FinMotion(NamedTuple):
    """A prescribed normal displacement w(u, v, t) of each fin's mid-surface (the one-way check,
    ``study.one_way``: sampled from the shell stage's run under a rigid collision's loads, then
    imposed on a second collision). Fins in the order of ``missile.fins``; fin f's frame is
    ``missile.shapes`` fin_origin / fin_axes (e1 = u, e2 = v, n).

    t0 (nf,) [s] time of fin f's first sample; dt [s] sample interval (all fins); nt (nf,) int64
    samples of fin f (0: rigid); offset (nf + 1,) int64: fin f's samples are rows
    offset[f]:offset[f + 1] of w; grid (nf, 4) [m] (u0, du, v0, dv): grid point (i, j) at
    origin + (u0 + i du) e1 + (v0 + j dv) e2; w (rows, nu, nv) [m] along n, row offset[f] + k at
    t0[f] + k dt. Between samples w is linear in t (so ẇ is constant over each interval),
    bilinear in (u, v), clamped to the grid; 0 before t0 (the fin at rest), the last sample held
    after the last (ẇ = 0)."""

    t0: np.ndarray
    dt: float
    nt: np.ndarray
    offset: np.ndarray
    grid: np.ndarray
    w: np.ndarray


def with_fin_motion(km: CollideModel, m: FinMotion) -> CollideModel:
    """``km`` with the fins moving as ``m`` (kernel arrays; the line contact law only: ``_point_depth``)."""
    nf = km.fin_half.shape[0]
    if not km.line_law:
        raise ValueError("a prescribed fin motion needs collide.contact_law = 'line'")
    if len(m.nt) != nf or m.grid.shape != (nf, 4) or len(m.offset) != nf + 1 or m.w.shape[0] != m.offset[-1]:
        raise ValueError(f"fin motion: arrays for {len(m.nt)} fins do not match the missile's {nf}")
    if m.w.shape[1] < 2 or m.w.shape[2] < 2 or not m.dt > 0.0:
        raise ValueError("fin motion: the grid needs at least 2 x 2 points and dt > 0")
    wmax = np.array([float(np.abs(m.w[m.offset[f]:m.offset[f + 1]]).max(initial=0.0)) for f in range(nf)])
    if (wmax >= km.rope_radius + km.fin_half).any():  # the crossing test reads the undeformed core
        raise ValueError(f"fin motion: |w| up to {1e3 * wmax.max():.3g} mm reaches rope radius + half-thickness")
    return km._replace(fin_motion_t0=np.asarray(m.t0, np.float64), fin_motion_dt=float(m.dt),
                       fin_motion_nt=np.asarray(m.nt, np.int64), fin_motion_offset=np.asarray(m.offset, np.int64),
                       fin_motion_grid=np.ascontiguousarray(m.grid, np.float64),
                       fin_motion_w=np.ascontiguousarray(m.w, np.float64), fin_wmax=wmax)


class CollideState(NamedTuple):
    """Everything the kernel changes (in place).

    Net: x, v [m, m/s] (n, 3) W; alive (ns,) bool (False once broken).
    Missile: mx, mv [m, m/s] (3,) CG in W; mq (4,) attitude (w, x, y, z) B → W; mh [kg m²/s] (3,)
        angular momentum about the CG in W.
    Contact slots, one per (segment, part kind) pair, slot = e·(1 + nf) + (0 body | 1 + fin):
        vk [m/s] (ns·(1+nf),) largest approach speed of the current contact (0: not in contact;
        −1: its centre line crossed the core, tunnelling episode).
    Fin loads of the current call, one slot per (segment, fin), slot = e·nf + fin:
        fin_imp [N s] (ns·nf, 3) impulse on the fin in B; fin_pt [N s m] (ns·nf, 3) impulse-
        weighted contact point in B; fin_w [N s] (ns·nf,) Σ |impulse|; fin_len [N s m] (ns·nf,)
        impulse-weighted chord length |x_j − x_i| of the segment while it pressed (its current,
        stretched length: the edge-resolution guard, ``simulate.edge_resolution``); touched (ns·nf,) int64 the
        slots written in this call, ntouched (1,) int64 their count (``simulate`` reads and clears them).
    part_imp [N s] (1 + nf, 2): per part (row 0 the body, 1 + fin), the whole run's Σ |F_n| dt
        (normal-force magnitude, damping included) and Σ |F_t| dt (friction magnitude): scalar
        sums, unlike the vector fin impulses — their ratio to the vector impulse shows how much
        of the normal force cancels around an edge (docs/collide_convergence.md, fourth pass).
    acc (N_ACC,) accumulators (``A_*``).
    """

    x: np.ndarray
    v: np.ndarray
    alive: np.ndarray
    mx: np.ndarray
    mv: np.ndarray
    mq: np.ndarray
    mh: np.ndarray
    vk: np.ndarray
    fin_imp: np.ndarray
    fin_pt: np.ndarray
    fin_w: np.ndarray
    fin_len: np.ndarray
    touched: np.ndarray
    ntouched: np.ndarray
    part_imp: np.ndarray
    acc: np.ndarray


def new_state(x: np.ndarray, n_seg: int, n_fin: int, mx, mv, mq) -> CollideState:
    """A state with the net at rest at x [m] (n, 3), all segments intact, no contact, and the
    missile at mx [m], mv [m/s] (3,), attitude mq (4,), not rotating."""
    n_fin_slots = n_seg * n_fin
    return CollideState(
        x=np.ascontiguousarray(x, dtype=np.float64), v=np.zeros((len(x), 3)), alive=np.ones(n_seg, np.bool_),
        mx=np.array(mx, dtype=np.float64), mv=np.array(mv, dtype=np.float64), mq=np.array(mq, dtype=np.float64),
        mh=np.zeros(3), vk=np.zeros(n_seg * (1 + n_fin)), fin_imp=np.zeros((n_fin_slots, 3)),
        fin_pt=np.zeros((n_fin_slots, 3)), fin_w=np.zeros(n_fin_slots), fin_len=np.zeros(n_fin_slots), touched=np.zeros(n_fin_slots, np.int64),
        ntouched=np.zeros(1, np.int64), part_imp=np.zeros((1 + n_fin, 2)), acc=np.zeros(N_ACC))
