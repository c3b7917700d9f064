"""Aerodynamic force and moment of the component airframe (``flexnet_fe.flight.airframe``).

Each component sees the local air velocity at its centre of pressure and gives a normal force
along its own normal (pure functions, body axes, SI units):

* nose:      F = −q̄ S 2 v_⊥/V                       at s_nose          (slender body)
* cross-flow F = −q̄ S C_cf |v_⊥| v_⊥/V²            at s_crossflow     (Zarchan ch. 21)
* panel i:   F = −q̄ S (a_i/β_M) (α_i + ρ_i + δ_i) n_i at its centroid c_i, and the carry-over
             −q̄ S (c_i^B/β_M)(α_i + ρ_i + δ_i) n_i on the body axis at the same station,
  with α_i = v_b·n_i/V (incidence), ρ_i = ((0, q, r) × c_i)·n_i/V (pitch/yaw-rate incidence:
  the damping), δ_i the fin deflection of a rudder (a deflection δ about the fin's outward
  axis e1 turns its normal to n + δ x̂_b, so it adds δ to the incidence); roll damping of panel i
  M_x = −q̄ S d (p d/V) D_i/β_M (strip theory).

v_⊥ = (0, v_y, v_z) is the body's cross-flow velocity. With the paper's coefficient readings the
α-, δ- and rate-parts are scaled separately: F = k_lift F_α + k_ctrl F_δ + F_rate,
M = k_moment M_α + k_ctrl M_δ + M_rate (``flexnet_fe.flight.config.DamageModel``).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit


class CoefficientScale(NamedTuple):
    """Multipliers of the whole-airframe α-, δ-terms (paper §VI readings; 1, 1, 1 = geometry)."""

    lift: float
    moment: float
    control: float


@njit(cache=True)
def supersonic_beta(mach):
    """β_M = √(M² − 1) of linear supersonic theory [-]; valid for M > 1."""
    return math.sqrt(mach * mach - 1.0)


@njit(cache=True)
def loads(af, scale, v_b, omega, fin_delta, qbar, beta_m):
    """(force [N], moment about the CG [N m]) in body axes, each shape (3,) (module doc).

    af: ``flexnet_fe.flight.airframe.Airframe``; scale: :class:`CoefficientScale`;
    v_b: velocity in body axes [m/s] (3,); omega: body rates (p, q, r) [rad/s] (3,);
    fin_delta: deflections of rudder_1..4 [rad] (4,); qbar: dynamic pressure [Pa]; beta_m: √(M²−1).
    Written out in scalars (one allocation per call): acc[k] holds (F, M) of part k = 0 incidence,
    1 rate, 2 control.
    """
    speed = math.sqrt(v_b[0] * v_b[0] + v_b[1] * v_b[1] + v_b[2] * v_b[2])
    qs = qbar * af.sref
    acc = np.zeros((3, 6))
    # body: nose (slender body) and cross-flow, along −v_⊥ = −(0, v_y, v_z), at stations on the axis
    vp = math.sqrt(v_b[1] * v_b[1] + v_b[2] * v_b[2])
    for slope, station in ((af.nose_slope * speed, af.s_nose), (af.crossflow * vp, af.s_crossflow)):
        k = -qs * slope / (speed * speed)
        arm = af.s_cg - station                       # x of the station relative to the CG
        acc[0, 1] += k * v_b[1]
        acc[0, 2] += k * v_b[2]
        acc[0, 4] -= arm * k * v_b[2]                 # (arm, 0, 0) × (0, F_y, F_z) = (0, −arm F_z, arm F_y)
        acc[0, 5] += arm * k * v_b[1]
    q, r = omega[1], omega[2]
    for i in range(af.panel_slope.shape[0]):
        n0, n1, n2 = af.panel_normal[i, 0], af.panel_normal[i, 1], af.panel_normal[i, 2]
        c0, c1, c2 = af.panel_cp[i, 0], af.panel_cp[i, 1], af.panel_cp[i, 2]
        x_alpha = (v_b[0] * n0 + v_b[1] * n1 + v_b[2] * n2) / speed
        x_rate = ((q * c2 - r * c1) * n0 + r * c0 * n1 - q * c0 * n2) / speed     # ((0,q,r) × c)·n / V
        x_ctrl = fin_delta[i - 4] if af.is_control[i] > 0.0 else 0.0
        k_pan = -qs * af.panel_slope[i] / beta_m
        k_car = -qs * af.carry_slope[i] / beta_m
        k_f = k_pan + k_car
        # moments: panel force at c: c × n; carry-over at (c0, 0, 0): (0, −c0 n2, c0 n1)
        m0 = k_pan * (c1 * n2 - c2 * n1)
        m1 = k_pan * (c2 * n0 - c0 * n2) - k_car * c0 * n2
        m2 = k_pan * (c0 * n1 - c1 * n0) + k_car * c0 * n1
        for part, x in ((0, x_alpha), (1, x_rate), (2, x_ctrl)):
            acc[part, 0] += k_f * x * n0
            acc[part, 1] += k_f * x * n1
            acc[part, 2] += k_f * x * n2
            acc[part, 3] += m0 * x
            acc[part, 4] += m1 * x
            acc[part, 5] += m2 * x
        acc[1, 3] -= qs * af.dref * (omega[0] * af.dref / speed) * af.panel_roll_damp[i] / beta_m
    force, moment = np.empty(3), np.empty(3)
    for k in range(3):
        force[k] = scale.lift * acc[0, k] + scale.control * acc[2, k] + acc[1, k]
        moment[k] = scale.moment * acc[0, 3 + k] + scale.control * acc[2, 3 + k] + acc[1, 3 + k]
    return force, moment
