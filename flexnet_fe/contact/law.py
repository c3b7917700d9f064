"""Normal contact force, damping models and regularised friction: small numba functions.

Sign convention (departs from the paper's Eq. (28), which writes penetration as δ < 0): here the
penetration depth ``delta`` [m] is POSITIVE when the bodies overlap and ``delta_dot`` [m/s] is its
rate (positive while approaching). All three damping models are of Hunt–Crossley form

    F_n = K_n δ^m (1 + χ δ̇),        χ [s/m] the hysteresis damping factor,

which is Eq. (28)+(29) with C δ̇ = χ K_n δ^m δ̇. A normal force never pulls: F_n < 0 (possible
late in restitution when χ δ̇ < -1) is set to 0 — this is the physical "no adhesion" condition
of a unilateral contact, not a numerical clamp.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from flexnet_fe.contact.models import DAMPING_CODE, DampingModel  # noqa: F401  (re-exported)


@njit(cache=True)
def hysteresis_factor(model_code, restitution, v_k):
    """Damping factor χ [s/m] of a contact with approach speed ``v_k`` [m/s] > 0 (``approach_speed``).

    model_code: ``DAMPING_CODE[model]``; restitution e ∈ (0, 1]. Eq. (29) for Lankarani–Nikravesh.
    Raises ValueError for an unknown code or v_k <= 0 (a contact that starts at rest has no
    impact speed; the caller decides what that means).
    """
    e = restitution
    if model_code == 0:
        return 0.0
    if v_k <= 0.0:
        raise ValueError("hysteresis_factor: impact speed v_k must be > 0")
    if model_code == 1:
        return 3.0 * (1.0 - e * e) / (4.0 * v_k)
    if model_code == 2:
        return 3.0 * (1.0 - e) / (2.0 * v_k)
    if model_code == 3:
        return 8.0 * (1.0 - e) / (5.0 * e * v_k)
    raise ValueError("hysteresis_factor: unknown damping model code")


@njit(cache=True)
def normal_force(delta, delta_dot, k_n, exponent, chi, damp_cap=np.inf):
    """Normal contact force magnitude [N], Eq. (28)–(29): F = K_n δ^m + min(K_n δ^m χ, cap) δ̇,
    never negative.

    delta [m] penetration (> 0 in contact), delta_dot [m/s] its rate, k_n [N/m^m] contact
    stiffness, exponent m (1.5 Hertz), chi [s/m] hysteresis factor. Zero when delta <= 0.

    damp_cap [kg/s] (default: no cap) bounds the dashpot C = K_n δ^m χ, the damping force per
    unit approach speed — the normal counterpart of :func:`friction_force`'s ``stick``. An
    explicit step of dt with a contact point of effective mass m_eff passes
    ``damp_cap = f m_eff / dt`` (f ≤ 1): the damping impulse of one step then removes at most
    the fraction f of the normal approach speed, never reverses it. Without it a dashpot on a
    lagged velocity is unstable once C dt / m_eff > 2: a contact that began slowly (χ = c / v_k
    with v_k at its floor) and is then pressed hard has C = χ × (elastic force), and a light rope
    piece's normal force alternates from step to step (measured: infrared × traction's rudders,
    ±360 N on 940 N for 0.65 ms at dt = 0.3125 µs, gone at dt / 2; docs/validation.md, "Contact
    damping at the explicit limit"). The cap acts only there: as dt → 0 it recovers Eq. (29).
    """
    if delta <= 0.0:
        return 0.0
    fe = k_n * delta ** exponent
    c = fe * chi
    if c > damp_cap:
        c = damp_cap
    f = fe + c * delta_dot
    return f if f > 0.0 else 0.0


@njit(cache=True)
def contact_potential(delta, k_n, exponent):
    """Elastic energy [J] stored by the spring part of Eq. (28): K_n δ^(m+1)/(m+1), δ > 0."""
    if delta <= 0.0:
        return 0.0
    return k_n * delta ** (exponent + 1.0) / (exponent + 1.0)


@njit(cache=True)
def approach_speed(v_k, delta_dot, v_floor):
    """The speed v_k [m/s] that sets χ = c/v_k in Eq. (29), updated at each step of a contact.

    Rule (documented departure from "v_k = the approach speed at first touch"): v_k is the
    LARGEST approach speed δ̇ seen since the contact began, and at least ``v_floor`` [m/s] > 0.
    For a single impact this is the impact speed (the approach slows down after touch). For a
    contact that began slowly and is later compressed fast — a rope sliding from the body onto
    a fin edge — v_k follows, so χ δ̇ ≤ c while approaching: the damping force is bounded by c
    times the elastic force (c ≤ 0.75 for Lankarani–Nikravesh) instead of growing as δ̇/v_touch.
    v_k (the previous value; 0 or −1 when not in contact) must be reset to 0 by the caller when
    the contact ends."""
    v = v_k if v_k > delta_dot else delta_dot
    return v if v > v_floor else v_floor


@njit(cache=True)
def friction_force(f_n, mu, vt0, vt1, vt2, v_reg, stick=np.inf):
    """Regularised Coulomb friction, Eq. (32): F_t = −min(μ F_n tanh(|v_t|/v_reg), stick |v_t|) v_t/|v_t|.

    f_n [N] normal force (>= 0), mu friction coefficient, (vt0, vt1, vt2) [m/s] relative
    tangential velocity of the net point with respect to the missile surface, v_reg [m/s] > 0
    regularisation speed. Departs from Eq. (32)'s sign(v): tanh(|v|/v_reg) replaces sign so the
    force is continuous at zero slip (its magnitude is below μF_n by the factor tanh(|v|/v_reg),
    i.e. less than 0.1 % short once |v| > 4 v_reg).

    stick [kg/s] (default: no cap) bounds the force per unit slip speed. An explicit step of dt
    with a contact point of effective mass m_eff passes ``stick = f m_eff / dt`` (f ≤ 1): the
    friction impulse of one step then removes at most the fraction f of the slip, the discrete
    form of sticking (v_t → 0 without reversing). Without it the regularised law's slope
    μF_n/v_reg exceeds the explicit limit m_eff/dt whenever F_n > m_eff v_reg/(μ dt) (≈ 500 N on a
    1.4 mm rope piece at dt = 40 ns), and the slip chatters at ±μF_n dt/m_eff (tens of m/s) instead
    of sticking. The cap acts only there: as dt → 0 it recovers the regularised law.
    Returns the force (3 floats) [N]; its power −F_t·v_t ≥ 0 is always dissipated.
    """
    s = np.sqrt(vt0 * vt0 + vt1 * vt1 + vt2 * vt2)
    if s == 0.0 or f_n == 0.0:
        return 0.0, 0.0, 0.0
    a = -min(mu * f_n * np.tanh(s / v_reg), stick * s) / s
    return a * vt0, a * vt1, a * vt2
