"""Rigid 6-DOF missile step (numba), driven by the summed contact force and torque about the CG.

State (world frame W unless noted, see ``flexnet_fe.frames``):
    x  [m] (3,)        CG position          v  [m/s] (3,)     CG velocity
    q  [-] (4,)        attitude (w, x, y, z), v_W = R(q) v_B
    h  [kg m²/s] (3,)  angular momentum about the CG, in W

Scheme: symplectic Euler on momenta — v += dt F/M, x += dt v; h += dt τ_W,
ω_B = I_B⁻¹ R(q)ᵀ h, q ← q ⊗ exp(½ ω_B dt) (``rigid.quat_exp_step``). Updating the momenta
with exactly the impulses F dt, τ dt applied (equal and opposite) to the net makes the linear
and angular momentum balance of net + missile hold to round-off; Euler's equations
I ω̇ + ω × Iω = τ are satisfied to first order in dt (the gyroscopic term comes from the
rotating R(q) in ω_B = I⁻¹ Rᵀ h).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from flexnet_fe.frames import quat_exp_step, quat_to_matrix


@njit(cache=True)
def body_rate(q, h, inv_inertia_b):
    """Body angular velocity ω_B [rad/s] (3,) from world angular momentum h [kg m²/s] (3,)."""
    r = quat_to_matrix(q)
    hb = np.empty(3)
    w = np.empty(3)
    for k in range(3):
        hb[k] = r[0, k] * h[0] + r[1, k] * h[1] + r[2, k] * h[2]
    for k in range(3):
        w[k] = inv_inertia_b[k, 0] * hb[0] + inv_inertia_b[k, 1] * hb[1] + inv_inertia_b[k, 2] * hb[2]
    return w


class RigidBody(NamedTuple):
    """A rigid body for :func:`rigid_step` (numba record): x [m] (3,), v [m/s] (3,), q (4,), h
    [kg m²/s] (3,) as in the module doc (arrays, updated in place); mass [kg]; inv_inertia
    [1/(kg m²)] (3, 3) about the CG in B."""

    x: np.ndarray
    v: np.ndarray
    q: np.ndarray
    h: np.ndarray
    mass: float
    inv_inertia: np.ndarray


@njit(cache=True)
def rigid_step(body, force_w, torque_w, dt):
    """Advance ``body`` (:class:`RigidBody`) one step in place (see module doc). force_w [N] (3,)
    and torque_w [N m] (3,) about the CG in W; dt [s]."""
    for k in range(3):
        body.v[k] += dt * force_w[k] / body.mass
        body.x[k] += dt * body.v[k]
        body.h[k] += dt * torque_w[k]
    w_b = body_rate(body.q, body.h, body.inv_inertia)
    body.q[:] = quat_exp_step(body.q, w_b, dt)


@njit(cache=True)
def integrate_rigid(body, force_b, torque_b, dt, n_steps):
    """Integrate ``n_steps`` of ``dt`` [s] with a force [N] (3,) and torque [N m] (3,) about the CG
    constant in the BODY frame (test driver); ``body`` (:class:`RigidBody`) is updated in place."""
    for _ in range(n_steps):
        r = quat_to_matrix(body.q)
        rigid_step(body, r @ force_b, r @ torque_b, dt)
