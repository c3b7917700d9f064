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


@njit(cache=True)
def los_rate(r, v):
    """Inertial LOS angular-rate vector Ω = r × v / |r|² [rad/s], shape (3,); r [m], v [m/s]."""
    return np.cross(r, v) / np.dot(r, r)


@njit(cache=True)
def closing_speed(r, v):
    """V_c = −(r · v)/|r| [m/s] (positive while closing)."""
    return -np.dot(r, v) / np.sqrt(np.dot(r, r))


@njit(cache=True)
def pn_command(nav_constant, vc, omega_los, r):
    """True PN acceleration command a_c = N V_c (Ω × u_r) [m/s²], shape (3,)."""
    return nav_constant * vc * np.cross(omega_los, r / np.sqrt(np.dot(r, r)))


@njit(cache=True)
def first_order_lag_rate(x_filtered, x_true, time_constant):
    """dx_f/dt = (x − x_f)/τ (any shape, τ [s])."""
    return (x_true - x_filtered) / time_constant
