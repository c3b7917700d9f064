"""The compiled time-stepping kernel of the net (many steps per call, no Python per step).

Scheme: symplectic (semi-implicit) Euler, i.e. central differences with velocities at half
steps: v_{n+1/2} = v_{n-1/2} + dt f(x_n, v_{n-1/2}) / m ; x_{n+1} = x_n + dt v_{n+1/2}.
Second-order in positions for conservative forces; it conserves linear momentum and (for
central forces) angular momentum exactly. For a spring-dashpot with damping evaluated at the
lagged velocity the stability limit is ω dt <= 2 (√(1+ζ²) - ζ) (see ``timestep.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from flexnet_fe.net.forces import C_CROSS, CD_FRICTION, segment_aero_force, spring_force

C_MAX = CD_FRICTION + C_CROSS
from flexnet_fe.net.hub import hub_link_state


@njit(cache=True)
def net_forces(x, v, hub_state, wrap, springs, rest, stiffness, damping, offset, diameter,
               hub_link, anchor, mass, hub, r0, half_length, gvec, rho, wind, air, f, tension, lam):
    """All forces on the net at one instant, Eq. (11): gravity + rope tensions (Eq. 1–4, hub
    links Eq. 12–19) + rope aerodynamics (Eq. 5–10). Writes f (n, 3) [N], tension (m,) [N],
    updates wrap (m,) [rad] in place. Returns (torque about +z on the hub [N m], max tension [N]).

    hub_state = (θ [rad], ω [rad/s]); gvec (3,) [m/s^2]; rho [kg/m^3]; wind (3,) [m/s];
    air : include aerodynamic loads; lam (n,) [kg/s]: accumulates, per node, a Gershgorin
    bound of the drag's velocity derivative Σ_s ½ ρ C_max d l |v_s| (the caller divides by m).
    """
    n = x.shape[0]
    for i in range(n):
        f[i, 0] = mass[i] * gvec[0]
        f[i, 1] = mass[i] * gvec[1]
        f[i, 2] = mass[i] * gvec[2]
    theta = hub_state[0]
    omega = hub_state[1]
    torque = 0.0
    tmax = 0.0
    pt = np.empty(3)
    vt = np.empty(3)
    for s in range(springs.shape[0]):
        j = springs[s, 1]
        if hub_link[s]:
            i = hub
            gamma, w = hub_link_state(x, v, hub, j, theta, omega, anchor[s], r0, half_length, wrap[s], pt, vt)
            wrap[s] = w
            d0 = x[j, 0] - pt[0]; d1 = x[j, 1] - pt[1]; d2 = x[j, 2] - pt[2]
            extra = r0 * abs(w)
            vi0 = vt[0]; vi1 = vt[1]; vi2 = vt[2]
        else:
            i = springs[s, 0]
            d0 = x[j, 0] - x[i, 0]; d1 = x[j, 1] - x[i, 1]; d2 = x[j, 2] - x[i, 2]
            extra = 0.0
            vi0 = v[i, 0]; vi1 = v[i, 1]; vi2 = v[i, 2]
        t, u0, u1, u2, lf, ldot, stretch = spring_force(d0, d1, d2, v[j, 0] - vi0, v[j, 1] - vi1, v[j, 2] - vi2,
                                                        extra, rest[s], stiffness[s], damping[s], offset[s])
        if lf == 0.0:
            tension[s] = 0.0
            continue
        tension[s] = t
        if t > tmax:
            tmax = t
        f[i, 0] += t * u0; f[i, 1] += t * u1; f[i, 2] += t * u2
        f[j, 0] -= t * u0; f[j, 1] -= t * u1; f[j, 2] -= t * u2
        if hub_link[s]:
            # lever arm of the rim point: (T - c) x (t u), z component (Eq. 12-13)
            torque += t * ((pt[0] - x[hub, 0]) * u1 - (pt[1] - x[hub, 1]) * u0)
        if air:
            vrx = 0.5 * (vi0 + v[j, 0]) - wind[0]
            vry = 0.5 * (vi1 + v[j, 1]) - wind[1]
            vrz = 0.5 * (vi2 + v[j, 2]) - wind[2]
            fx, fy, fz = segment_aero_force(u0, u1, u2, lf, vrx, vry, vrz, rho, diameter[s])
            # Eq. (9)-(10): half to each end (the hub's half acts on its translation only)
            f[i, 0] += 0.5 * fx; f[i, 1] += 0.5 * fy; f[i, 2] += 0.5 * fz
            f[j, 0] += 0.5 * fx; f[j, 1] += 0.5 * fy; f[j, 2] += 0.5 * fz
            q = 0.5 * rho * C_MAX * diameter[s] * lf * math.sqrt(vrx * vrx + vry * vry + vrz * vrz)
            lam[i] += q
            lam[j] += q
    return torque, tmax


@njit(cache=True)
def advance(x, v, hub_state, wrap, n_steps, dt, springs, rest, stiffness, damping, offset,
            diameter, hub_link, anchor, mass, hub, r0, half_length, hub_inertia, gvec, rho, wind, air,
            f, tension, lam):
    """Advance the net ``n_steps`` steps of ``dt`` [s] in place (symplectic Euler).

    x, v (n, 3) [m], [m/s]; hub_state (2,) = (θ, ω); wrap (m,) [rad]; f (n, 3) work array;
    tension (m,) [N] holds the tensions of the last force evaluation; lam (n,) work array.
    Returns (largest segment tension seen during the call [N], largest drag stability number
    λ dt, λ = drag velocity-derivative bound / m; the lagged-velocity update needs λ dt <= 2).
    """
    n = x.shape[0]
    peak = 0.0
    drag_number = 0.0
    for i in range(n):
        lam[i] = 0.0
    for step in range(n_steps):
        torque, tmax = net_forces(x, v, hub_state, wrap, springs, rest, stiffness, damping, offset,
                            diameter, hub_link, anchor, mass, hub, r0, half_length, gvec, rho, wind, air,
                            f, tension, lam)
        if tmax > peak:
            peak = tmax
        for i in range(n):
            a = dt / mass[i]
            if lam[i] != 0.0:
                if lam[i] * a > drag_number:
                    drag_number = lam[i] * a
                lam[i] = 0.0
            v[i, 0] += a * f[i, 0]
            v[i, 1] += a * f[i, 1]
            v[i, 2] += a * f[i, 2]
            x[i, 0] += dt * v[i, 0]
            x[i, 1] += dt * v[i, 1]
            x[i, 2] += dt * v[i, 2]
        if hub >= 0:
            hub_state[1] += dt * torque / hub_inertia
            hub_state[0] += dt * hub_state[1]
    return peak, drag_number
