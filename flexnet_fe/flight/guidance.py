"""Seeker (line-of-sight rate) and proportional navigation.

True proportional navigation in 3-D (Zarchan ch. 2 in vector form): the command is normal to
the line of sight,

    a_c = N V_c (Ω × u_r),    Ω = (r × v) / |r|²,    V_c = −(r · v)/|r|,

with r the target-minus-missile position, v the relative velocity and u_r = r/|r|.
In the plane this is Zarchan's n_c = N' V_c λ̇. The seeker is modelled as the true inertial LOS
rate seen through a first-order lag (time constant τ_s): Ω̇_f = (Ω − Ω_f)/τ_s.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def _dot3(a, b):
    """a · b for two 3-vectors (no BLAS call)."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True, inline="always")
def _cross_scaled(a, b, k):
    """k (a × b), shape (3,): one allocation (in the flight RHS, called every evaluation)."""
    out = np.empty(3)
    out[0] = k * (a[1] * b[2] - a[2] * b[1])
    out[1] = k * (a[2] * b[0] - a[0] * b[2])
    out[2] = k * (a[0] * b[1] - a[1] * b[0])
    return out


@njit(cache=True)
def los_rate(r, v):
    """Inertial LOS angular-rate vector Ω = r × v / |r|² [rad/s], shape (3,); r [m], v [m/s]."""
    return _cross_scaled(r, v, 1.0 / _dot3(r, r))


@njit(cache=True)
def closing_speed(r, v):
    """V_c = −(r · v)/|r| [m/s] (positive while closing)."""
    return -_dot3(r, v) / np.sqrt(_dot3(r, r))


@njit(cache=True)
def pn_command(nav_constant, vc, omega_los, r):
    """True PN acceleration command a_c = N V_c (Ω × u_r) [m/s²], shape (3,), u_r = r/|r|."""
    return _cross_scaled(omega_los, r, nav_constant * vc / np.sqrt(_dot3(r, r)))


@njit(cache=True)
def first_order_lag_rate(x_filtered, x_true, time_constant):
    """dx_f/dt = (x − x_f)/τ (any shape, τ [s])."""
    return (x_true - x_filtered) / time_constant
