"""The frames every module uses (one place; plots say which frame they show).

World frame W (deploy and collide stages)
    Origin at the net centre at t = 0. ``+z`` is the flight direction of the interceptor
    (the net deploys in the x–y plane and the free stream blows along ``-z`` relative to it);
    in the collision the missile moves along ``+z`` into the net (paper §V-C: "the Z-axis points
    to the direction of the missile's motion"). ``+y`` is up (gravity is ``-g ŷ``; the paper's
    "Y-axis along the direction of the lead weight pointing upwards"); ``x = y × z``.

Missile body frame B (missile geometry, contact loads, shell loads, collision attitude)
    Origin at the nose apex. ``+x_b`` points forward along the missile axis, so the missile
    occupies ``x_b ∈ [-L, 0]``. ``y_b``, ``z_b`` span the cross-section; a fin's roll angle φ
    is measured from ``+y_b`` towards ``+z_b`` about ``+x_b``. Stations (distance aft of the
    nose) are ``s = -x_b``. The centre of gravity is a point of B. Attitude is the unit
    quaternion q = (w, x, y, z) rotating B vectors into W: ``v_W = R(q) v_B``.

Flight frame F (the 6-DOF engagement, flight stage)
    Documented in ``flexnet_fe.flight`` (it follows the paper's engagement coordinates).

Quaternion algebra (numba-compiled so hot kernels can call it): quaternions are float64 arrays
(w, x, y, z), scalar first, Hamilton convention; ``R(q)`` rotates body vectors into the world
frame: ``v_W = R(q) v_B``.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def quat_mul(p, q):
    """Hamilton product p ⊗ q, shape (4,)."""
    out = np.empty(4)
    out[0] = p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3]
    out[1] = p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2]
    out[2] = p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1]
    out[3] = p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0]
    return out


@njit(cache=True)
def quat_to_matrix(q):
    """Rotation matrix R(q), shape (3, 3), for a unit quaternion q (w, x, y, z)."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    r = np.empty((3, 3))
    r[0, 0] = 1 - 2 * (y * y + z * z)
    r[0, 1] = 2 * (x * y - w * z)
    r[0, 2] = 2 * (x * z + w * y)
    r[1, 0] = 2 * (x * y + w * z)
    r[1, 1] = 1 - 2 * (x * x + z * z)
    r[1, 2] = 2 * (y * z - w * x)
    r[2, 0] = 2 * (x * z - w * y)
    r[2, 1] = 2 * (y * z + w * x)
    r[2, 2] = 1 - 2 * (x * x + y * y)
    return r


@njit(cache=True)
def quat_exp_step(q, omega_body, dt):
    """Advance q by a constant body rate ``omega_body`` [rad/s] (3,) over ``dt`` [s] exactly:
    q ⊗ exp(½ ω dt). Keeps |q| = 1 to round-off."""
    wn = np.sqrt(omega_body[0] ** 2 + omega_body[1] ** 2 + omega_body[2] ** 2)
    half = 0.5 * wn * dt
    dq = np.empty(4)
    dq[0] = np.cos(half)
    s = 0.5 * dt * np.sinc(half / np.pi)  # sin(half)/wn, finite as wn -> 0
    dq[1] = omega_body[0] * s
    dq[2] = omega_body[1] * s
    dq[3] = omega_body[2] * s
    out = quat_mul(q, dq)
    return out / np.sqrt(np.sum(out * out))


def quat_from_matrix(r: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation matrix (Shepperd's method)."""
    tr = np.trace(r)
    if tr > 0:
        s = 2.0 * np.sqrt(1.0 + tr)
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    else:
        i = int(np.argmax(np.diag(r)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(1.0 + r[i, i] - r[j, j] - r[k, k])
        q = np.empty(4)
        q[0] = (r[k, j] - r[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (r[j, i] + r[i, j]) / s
        q[1 + k] = (r[k, i] + r[i, k]) / s
    q = np.asarray(q, dtype=float)
    return q / np.linalg.norm(q) * (1 if q[0] >= 0 else -1)
