"""Rigid-body equations of motion (flat, non-rotating Earth; body axes; diagonal inertia).

    ṙ = v,    v̇ = R(q) f_B + g,    q̇ = ½ q ⊗ (0, ω),    I ω̇ = M − ω × (I ω)

(e.g. Stevens, Lewis & Johnson, *Aircraft Control and Simulation*, 3rd ed., §1.8; Euler's
equations of a rigid body). q = (w, x, y, z) rotates body vectors into the flight frame.
The translational part is two lines in ``flexnet_fe.flight.simulate.derivative``; the rotational
laws below are shared with the tests against NASA's check case.
"""

from __future__ import annotations

import numpy as np
from numba import njit



@njit(cache=True)
def euler_rates(omega, inertia, moment):
    """ω̇ [rad/s²], shape (3,), from Euler's equations for principal inertia ``inertia``
    (I_xx, I_yy, I_zz) [kg m²] and body moment [N m]."""
    p, q, r = omega[0], omega[1], omega[2]
    ix, iy, iz = inertia[0], inertia[1], inertia[2]
    out = np.empty(3)
    out[0] = (moment[0] - (iz - iy) * q * r) / ix
    out[1] = (moment[1] - (ix - iz) * r * p) / iy
    out[2] = (moment[2] - (iy - ix) * p * q) / iz
    return out


@njit(cache=True)
def quat_rate(q, omega):
    """q̇ = ½ q ⊗ (0, ω), shape (4,) (ω: body rate [rad/s]); the Hamilton product of
    ``frames.quat_mul`` with a zero scalar part, written out (one allocation)."""
    p, r, y = 0.5 * omega[0], 0.5 * omega[1], 0.5 * omega[2]
    out = np.empty(4)
    out[0] = -q[1] * p - q[2] * r - q[3] * y
    out[1] = q[0] * p + q[2] * y - q[3] * r
    out[2] = q[0] * r - q[1] * y + q[3] * p
    out[3] = q[0] * y + q[1] * r - q[2] * p
    return out
