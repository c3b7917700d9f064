"""Pure force laws of the rope net (numba ``@njit``), reusable from any kernel.

Paper §III-A: rope tension Eq. (1)–(4) (tension-only spring-damper with an LS-DYNA LINK167
style offset) and the rope-segment aerodynamic force Eq. (5)–(10).
"""

from __future__ import annotations

import math

from numba import njit

CD_FRICTION = 0.022
"""Skin-friction part of the rope drag coefficient, Eq. (7) [-]."""
C_CROSS = 1.1
"""Cross-flow coefficient of the rope, Eq. (7)–(8) [-]."""


@njit(cache=True)
def rope_tension(length, rest_length, stiffness, damping, offset, length_rate):
    """Tension T [N] of one rope segment, Eq. (1)–(2) with a LINK167 offset.

    length, rest_length [m]; stiffness K = EA/l0 [N/m] (Eq. 3); damping c [N s/m] (Eq. 4);
    offset [m] (taut length l0 - offset; > 0 pretension, < 0 slack); length_rate dl/dt [m/s].

    T = K (l - (l0 - offset)) + c dl/dt while l > l0 - offset, else 0 (slack: no force and no
    damping). A rope cannot push: when a fast shortening makes the damped value negative, T = 0
    (the rope goes slack for that instant). This is the law, not a stabiliser.
    """
    stretch = length - (rest_length - offset)
    if stretch <= 0.0:
        return 0.0
    t = stiffness * stretch + damping * length_rate
    return t if t > 0.0 else 0.0


@njit(cache=True)
def aero_coefficients(sin_alpha):
    """Drag and lift coefficients of a rope at angle of attack α, Eq. (7)–(8).

    C_D = 0.022 + 1.1 sin^3 α, C_L = 1.1 sin^2 α cos α, for α in [0, π/2] (sin α >= 0).
    Returns (C_D, C_L).
    """
    s = sin_alpha
    c = math.sqrt(max(0.0, 1.0 - s * s))
    return CD_FRICTION + C_CROSS * s * s * s, C_CROSS * s * s * c


@njit(cache=True)
def segment_aero_force(u0, u1, u2, length, vx, vy, vz, rho, diameter):
    """Aerodynamic force on one rope segment [N], Eq. (5)–(8). Returns (Fx, Fy, Fz).

    (u0, u1, u2) : unit vector along the segment; length l [m]; (vx, vy, vz) : segment velocity
    relative to the air [m/s] (mean of its end velocities minus the wind); rho [kg/m^3];
    diameter d [m].

    Drag F_D = ½ ρ C_D d l |v|^2 along -v̂; lift F_L = ½ ρ C_L d l |v|^2 along ê_L, the unit
    vector perpendicular to v̂ in the plane of v̂ and the segment, on the side opposite to the
    cross-flow velocity v_n = v - (v·ê)ê; C_D, C_L from Eq. (7)–(8) at sin α = |v_n| / |v|.
    Departure from the paper: Eq. (5)–(6) as printed read ½ ρ C d ||v|| l, which is not a
    force; the dimensionally correct ½ ρ C d l |v|^2 is used. With Eq. (7)–(8) the sum is
    F = -½ ρ d l (0.022 |v| v + 1.1 |v_n| v_n) (cross-flow principle), which is how it is
    evaluated (exact, and free of the α = 0 / 90° singularities of ê_L).
    """
    v2 = vx * vx + vy * vy + vz * vz
    ve = vx * u0 + vy * u1 + vz * u2
    vm = math.sqrt(v2)
    vnm = math.sqrt(max(0.0, v2 - ve * ve))
    q = -0.5 * rho * diameter * length
    a = q * CD_FRICTION * vm
    b = q * C_CROSS * vnm
    return (a * vx + b * (vx - ve * u0), a * vy + b * (vy - ve * u1), a * vz + b * (vz - ve * u2))


@njit(cache=True)
def accumulate_spring_forces(x, v, springs, rest_length, stiffness, damping, offset, skip, f, tension):
    """Add all rope tensions into f, Eq. (1)–(4), (11).

    x, v : node positions [m] / velocities [m/s], shape (n, 3); springs (m, 2) int64;
    rest_length [m], stiffness [N/m], damping [N s/m], offset [m], shape (m,);
    skip (m,) bool — segments handled elsewhere (hub links); f (n, 3) [N] accumulated in place;
    tension (m,) [N] written (0 for skipped segments).
    """
    for s in range(springs.shape[0]):
        if skip[s]:
            tension[s] = 0.0
            continue
        i = springs[s, 0]
        j = springs[s, 1]
        d0 = x[j, 0] - x[i, 0]; d1 = x[j, 1] - x[i, 1]; d2 = x[j, 2] - x[i, 2]
        l = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        if l == 0.0:
            tension[s] = 0.0
            continue
        u0 = d0 / l; u1 = d1 / l; u2 = d2 / l
        ldot = (v[j, 0] - v[i, 0]) * u0 + (v[j, 1] - v[i, 1]) * u1 + (v[j, 2] - v[i, 2]) * u2
        t = rope_tension(l, rest_length[s], stiffness[s], damping[s], offset[s], ldot)
        tension[s] = t
        f[i, 0] += t * u0; f[i, 1] += t * u1; f[i, 2] += t * u2
        f[j, 0] -= t * u0; f[j, 1] -= t * u1; f[j, 2] -= t * u2


@njit(cache=True)
def accumulate_aero_forces(x, v, springs, diameter, rho, wind, skip, f):
    """Add the rope aerodynamic loads into f [N], shape (n, 3): each segment's force
    (:func:`segment_aero_force`, with the mean velocity of its ends minus ``wind`` (3,) [m/s])
    goes half to each end node, Eq. (9)–(10). ``skip`` (m,) bool excludes segments."""
    for s in range(springs.shape[0]):
        if skip[s]:
            continue
        i = springs[s, 0]
        j = springs[s, 1]
        d0 = x[j, 0] - x[i, 0]; d1 = x[j, 1] - x[i, 1]; d2 = x[j, 2] - x[i, 2]
        l = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        if l == 0.0:
            continue
        fx, fy, fz = segment_aero_force(d0 / l, d1 / l, d2 / l, l, 0.5 * (v[i, 0] + v[j, 0]) - wind[0],
                                        0.5 * (v[i, 1] + v[j, 1]) - wind[1],
                                        0.5 * (v[i, 2] + v[j, 2]) - wind[2], rho, diameter[s])
        f[i, 0] += 0.5 * fx; f[i, 1] += 0.5 * fy; f[i, 2] += 0.5 * fz
        f[j, 0] += 0.5 * fx; f[j, 1] += 0.5 * fy; f[j, 2] += 0.5 * fz
