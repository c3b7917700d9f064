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
N_ACC = 32

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
