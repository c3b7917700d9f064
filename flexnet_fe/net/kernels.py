"""The compiled time-stepping kernel of the net (many steps per call, no Python per step).

Scheme: symplectic (semi-implicit) Euler, i.e. central differences with velocities at half
steps: v_{n+1/2} = v_{n-1/2} + dt f(x_n, v_{n-1/2}) / m ; x_{n+1} = x_n + dt v_{n+1/2}.
Second-order in positions for conservative forces; it conserves linear momentum and (for
central forces) angular momentum exactly. For a spring-dashpot with damping evaluated at the
lagged velocity the stability limit is ω dt <= 2 (√(1+ζ²) - ζ) (see ``timestep.py``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from flexnet_fe.net.forces import C_CROSS, CD_FRICTION, segment_aero_force, spring_force
from flexnet_fe.net.hub import hub_link_state

C_MAX = CD_FRICTION + C_CROSS


class DeployModel(NamedTuple):
    """What the deploy kernel needs and never changes (read-only in the kernel).

    springs (m, 2) uint32 node pairs (unsigned: no negative-index test in the hot loop); rest
    l0 [m], stiffness K = EA/l0 [N/m], damping c [N s/m],
    offset [m] (LINK167), diameter d [m], all (m,) — the rope law Eq. (1)–(4) and its aerodynamic
    size Eq. (5)–(6); hub_link (m,) bool; links (k,) int64 indices of the hub links; anchor (m,)
    [rad] rim angle of each hub link; mass (n,)
    [kg]; hub node index (-1: none); r0 hub radius [m]; half_length H/2 [m]; hub_inertia J
    [kg m²] (1 without a hub); gravity (3,) [m/s²]; rho air density [kg/m³]; wind (3,) [m/s];
    air: aerodynamic loads on/off. Built by ``net.state.kernel_model``.
    """

    springs: np.ndarray
    rest: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    offset: np.ndarray
    diameter: np.ndarray
    hub_link: np.ndarray
    links: np.ndarray
    anchor: np.ndarray
    mass: np.ndarray
    hub: int
    r0: float
    half_length: float
    hub_inertia: float
    gravity: np.ndarray
    rho: float
    wind: np.ndarray
    air: bool


class DeployState(NamedTuple):
    """What the deploy kernel changes in place: x, v (n, 3) [m], [m/s]; hub (2,) = (θ [rad],
    ω [rad/s]); wrap (m,) wound angle of each hub link [rad]; tension (m,) [N] of the last force
    evaluation; losses (2,) [J], accumulated by :func:`advance`: (dissipated by the rope
    dashpots, work of the air on the motion about the centre of mass)."""

    x: np.ndarray
    v: np.ndarray
    hub: np.ndarray
    wrap: np.ndarray
    tension: np.ndarray
    losses: np.ndarray


@njit(cache=True, inline="always")
def _segment_air(model, v, s, ends, u, lf, vi, lam):
    """Rope aerodynamics of segment s, Eq. (5)–(10). Returns half its force [N] (3 floats), the
    share of each end (i, j) = ``ends`` (the hub's half acts on its translation only); adds the
    drag's velocity-derivative bound ½ ρ C_max d l |v_s| [kg/s] to lam[i], lam[j] (lam (n,)).
    u unit vector i → j, lf straight length [m] (> 0), vi velocity of end i [m/s] (3 floats)."""
    i, j = ends
    wind = model.wind
    vrel = (0.5 * (vi[0] + v[j, 0]) - wind[0], 0.5 * (vi[1] + v[j, 1]) - wind[1], 0.5 * (vi[2] + v[j, 2]) - wind[2])
    fx, fy, fz, vm = segment_aero_force(u, lf, vrel, model.rho, model.diameter[s])
    q = 0.5 * model.rho * C_MAX * model.diameter[s] * lf * vm
    lam[i] += q
    lam[j] += q
    return 0.5 * fx, 0.5 * fy, 0.5 * fz


@njit(cache=True, error_model="numpy")
def _rope_forces(model, state, f, lam, fa):
    """Adds the tensions (Eq. 1–4) and, with air, the aerodynamics (Eq. 5–10) of every segment
    that is not a hub link to f (n, 3) [N], the aerodynamics also to fa (n, 3) [N]; writes their
    tension (m,) [N]. Returns (the largest tension [N], the dashpots' dissipation rate
    Σ (T − K s) l̇ [W] at the step's lagged velocities).

    The hot loop of the deploy stage: one pass over the segments, node indices unsigned (no
    negative-index wrap test), no allocation, no branch but the slack test inside the law."""
    x = state.x
    v = state.v
    tension = state.tension
    springs = model.springs
    hub_link = model.hub_link
    rest = model.rest
    stiffness = model.stiffness
    damping = model.damping
    offset = model.offset
    air = model.air
    tmax = 0.0
    p_diss = 0.0
    for s in range(springs.shape[0]):
        if hub_link[s]:
            continue
        i = springs[s, 0]
        j = springs[s, 1]
        t, u0, u1, u2, lf, ldot, stretch = spring_force(
            (x[j, 0] - x[i, 0], x[j, 1] - x[i, 1], x[j, 2] - x[i, 2]),
            (v[j, 0] - v[i, 0], v[j, 1] - v[i, 1], v[j, 2] - v[i, 2]), 0.0,
            (rest[s], stiffness[s], damping[s], offset[s]))
        tension[s] = t
        tmax = max(tmax, t)
        p_diss += (t - stiffness[s] * max(stretch, 0.0)) * ldot
        a0 = a1 = a2 = 0.0
        if air and lf != 0.0:
            a0, a1, a2 = _segment_air(model, v, s, (i, j), (u0, u1, u2), lf, (v[i, 0], v[i, 1], v[i, 2]), lam)
            fa[i, 0] += a0; fa[i, 1] += a1; fa[i, 2] += a2
            fa[j, 0] += a0; fa[j, 1] += a1; fa[j, 2] += a2
        f[i, 0] += t * u0 + a0; f[i, 1] += t * u1 + a1; f[i, 2] += t * u2 + a2
        f[j, 0] += a0 - t * u0; f[j, 1] += a1 - t * u1; f[j, 2] += a2 - t * u2
    return tmax, p_diss


@njit(cache=True, error_model="numpy")
def _hub_link_forces(model, state, f, lam, fa):
    """Adds the forces of the hub links (Eq. 12–19: rim point, wrap, tension, air) to f (n, 3)
    [N], their air loads also to fa (n, 3) [N]; updates their wrap (m,) [rad] and tension (m,)
    [N]. Returns (torque about +z on the hub [N m], largest hub-link tension [N], dashpot
    dissipation rate [W]); as :func:`_rope_forces`, with l̇ the rate of the straight part (the
    wound part's rate is not in the dashpot, Eq. 12–19)."""
    x = state.x
    v = state.v
    hub = model.hub
    torque = 0.0
    tmax = 0.0
    p_diss = 0.0
    pt = np.empty(3)
    vt = np.empty(3)
    for s in model.links:
        j = model.springs[s, 1]
        gamma, w = hub_link_state(model, state, s, pt, vt)
        state.wrap[s] = w
        t, u0, u1, u2, lf, ldot, stretch = spring_force(
            (x[j, 0] - pt[0], x[j, 1] - pt[1], x[j, 2] - pt[2]), (v[j, 0] - vt[0], v[j, 1] - vt[1], v[j, 2] - vt[2]),
            model.r0 * abs(w), (model.rest[s], model.stiffness[s], model.damping[s], model.offset[s]))
        state.tension[s] = t
        tmax = max(tmax, t)
        p_diss += (t - model.stiffness[s] * max(stretch, 0.0)) * ldot
        f[hub, 0] += t * u0; f[hub, 1] += t * u1; f[hub, 2] += t * u2
        f[j, 0] -= t * u0; f[j, 1] -= t * u1; f[j, 2] -= t * u2
        # lever arm of the rim point: (T - c) x (t u), z component (Eq. 12-13)
        torque += t * ((pt[0] - x[hub, 0]) * u1 - (pt[1] - x[hub, 1]) * u0)
        if model.air and lf != 0.0:
            a0, a1, a2 = _segment_air(model, v, s, (hub, j), (u0, u1, u2), lf, (vt[0], vt[1], vt[2]), lam)
            f[hub, 0] += a0; f[hub, 1] += a1; f[hub, 2] += a2
            f[j, 0] += a0; f[j, 1] += a1; f[j, 2] += a2
            fa[hub, 0] += a0; fa[hub, 1] += a1; fa[hub, 2] += a2
            fa[j, 0] += a0; fa[j, 1] += a1; fa[j, 2] += a2
    return torque, tmax, p_diss


@njit(cache=True)
def _weights(model, f):
    """f[i] = m_i g (n, 3) [N]."""
    for i in range(f.shape[0]):
        f[i, 0] = model.mass[i] * model.gravity[0]
        f[i, 1] = model.mass[i] * model.gravity[1]
        f[i, 2] = model.mass[i] * model.gravity[2]


@njit(cache=True)
def net_forces(model, state, f, lam):
    """All forces on the net at one instant, Eq. (11): gravity + rope tensions (Eq. 1–4, hub
    links Eq. 12–19) + rope aerodynamics (Eq. 5–10). ``model`` a DeployModel, ``state`` a
    DeployState (its tension (m,) [N] is written and its wrap (m,) [rad] updated in place).
    Writes f (n, 3) [N]. Returns (torque about +z on the hub [N m], max tension [N]).

    lam (n,) [kg/s]: accumulates, per node, a Gershgorin bound of the drag's velocity
    derivative Σ_s ½ ρ C_max d l |v_s| (the caller divides by m).
    """
    _weights(model, f)
    fa = np.zeros(f.shape)
    tmax, _ = _rope_forces(model, state, f, lam, fa)
    torque, tlink, _ = _hub_link_forces(model, state, f, lam, fa)
    return torque, max(tmax, tlink)


@njit(cache=True, error_model="numpy")
def advance(model, state, n_steps, dt):
    """Advance ``state`` (DeployState) of ``model`` (DeployModel) ``n_steps`` steps of ``dt``
    [s] in place (symplectic Euler); ``state.tension`` holds the tensions of the last force
    evaluation (one step old).

    Returns (largest segment tension seen during the call [N], largest drag stability number
    λ dt, λ = drag velocity-derivative bound / m; the lagged-velocity update needs λ dt <= 2).
    Adds to ``state.losses`` (2,) [J] the dashpots' dissipation, booked as its power at the
    step's lagged velocities × dt (a left sum, first order in dt, as the collide kernel's rope
    dashpots), and the air's work on the motion about the centre of mass, booked exactly: the
    step changes that kinetic energy by Σ F_i·(v̄_i − v̄_c) dt, v̄ the mean of the velocities
    before and after it, and the weights' share of that sum is zero.
    """
    x = state.x
    v = state.v
    mass = model.mass
    g0 = model.gravity[0]
    g1 = model.gravity[1]
    g2 = model.gravity[2]
    n = x.shape[0]
    f = np.empty((n, 3))
    fa = np.zeros((n, 3))
    lam = np.zeros(n)
    _weights(model, f)
    peak = 0.0
    drag_number = 0.0
    inv_m = 1.0 / mass.sum()
    losses = state.losses
    fa_sum = np.zeros(3)               # Σ fa_i
    vc_sum = np.zeros(3)               # Σ m_i (v_old + v_new)_i
    for step in range(n_steps):
        tmax, p_diss = _rope_forces(model, state, f, lam, fa)
        torque, tlink, q_diss = _hub_link_forces(model, state, f, lam, fa)
        peak = max(peak, tmax, tlink)
        losses[0] += dt * (p_diss + q_diss)
        w_air = 0.0                    # Σ fa_i · (v_old + v_new)_i
        fa_sum[:] = 0.0
        vc_sum[:] = 0.0
        for i in range(n):  # update, and reset f to the weights for the next step
            a = dt / mass[i]
            if lam[i] != 0.0:
                drag_number = max(drag_number, lam[i] * a)
                lam[i] = 0.0
            if model.air:
                for k in range(3):
                    w_air += fa[i, k] * (2.0 * v[i, k] + a * f[i, k])
                    fa_sum[k] += fa[i, k]
                    vc_sum[k] += mass[i] * (2.0 * v[i, k] + a * f[i, k])
                    fa[i, k] = 0.0
            v[i, 0] += a * f[i, 0]
            v[i, 1] += a * f[i, 1]
            v[i, 2] += a * f[i, 2]
            x[i, 0] += dt * v[i, 0]
            x[i, 1] += dt * v[i, 1]
            x[i, 2] += dt * v[i, 2]
            f[i, 0] = mass[i] * g0
            f[i, 1] = mass[i] * g1
            f[i, 2] = mass[i] * g2
        if model.air:
            losses[1] += 0.5 * dt * (w_air - inv_m * (fa_sum[0] * vc_sum[0] + fa_sum[1] * vc_sum[1]
                                                      + fa_sum[2] * vc_sum[2]))
        if model.hub >= 0:
            state.hub[1] += dt * torque / model.hub_inertia
            state.hub[0] += dt * state.hub[1]
    return peak, drag_number
