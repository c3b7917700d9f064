"""Acceleration autopilot design (fixed gains for the undamaged missile).

Pitch and yaw: Zarchan's three-loop autopilot (*Tactical and Strategic Missile Guidance*, 6th ed.,
ch. 23, Listing 23.1): with body rate θ̇ (rate gyro), achieved acceleration n_L (accelerometer at
the CG) and command n_c,

    ẋ = ω_I (θ̇ + K_A (n_L − K_DC n_c)),      δ_c = K_R (x + θ̇).

The gains place the closed-loop poles (without actuator) at the roots of
(1 + τ s)(1 + 2ζ s/ω + s²/ω²) for a chosen open-loop crossover ω_cr (Zarchan's design formulas,
here in SI with accelerations in m/s² and angles in rad, so Zarchan's 1845 = 32.2·57.3 becomes 1).
The airframe is linearised at the trim incidence of ``design_load_g`` (Zarchan ch. 21 trim).

Roll: PD roll-angle hold δ_roll = −(K_φ φ + K_p p), poles of s² + 2ζω s + ω².
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexnet_fe.errors import CaseError
from flexnet_fe.flight import aero as A


@dataclass(frozen=True)
class PlaneDerivatives:
    """Secant coefficient slopes of one plane at a trim incidence (Zarchan ch. 21) [1/rad]."""

    cn_alpha: float
    cn_delta: float
    cm_alpha: float
    cm_delta: float
    alpha_trim: float
    """trim incidence [rad]"""


@dataclass(frozen=True)
class AirframeLinear:
    """Zarchan's linear airframe (ch. 21): n_L/δ = K1 (1 − s²/ω_z²)/(s²/ω_af² + 2ζ_af s/ω_af + 1),
    θ̇/δ = K3 (1 + T_α s)/(same)."""

    m_alpha: float
    """M_α = q S d C_mα / I [1/s²]"""
    m_delta: float
    """M_δ [1/s²]"""
    z_alpha: float
    """Z_α = −q S C_Nα / (m V) [1/s]"""
    z_delta: float
    """Z_δ [1/s]"""
    omega_z: float
    """right-half-plane zero [rad/s]"""
    omega_af: float
    """airframe natural frequency [rad/s]"""
    zeta_af: float
    """airframe damping [-]"""
    k1: float
    """acceleration gain [m/s² per rad]"""
    t_alpha: float
    """turning-rate time constant [s]"""
    k3: float
    """rate gain [1/s]"""


@dataclass(frozen=True)
class ThreeLoopGains:
    """Three-loop autopilot gains (Zarchan ch. 23)."""

    k_a: float
    """accelerometer gain [s/m]"""
    omega_i: float
    """integrator gain ω_I [rad/s]"""
    k_r: float
    """rate gain [s] (rad of fin per rad/s)"""
    k_dc: float
    """command scaling for unit DC gain [-]"""


def plane_derivatives(a: np.ndarray, beta_m: float, cn_trim: float) -> PlaneDerivatives:
    """Trim incidence for normal-force coefficient ``cn_trim`` and the secant slopes there
    (Zarchan ch. 21: moment balance C_M = 0 with δ eliminated, then a quadratic in α)."""
    y1 = a[A.CN_NOSE] + (a[A.CN_WING] + a[A.CN_TAIL]) / beta_m
    y2 = a[A.CN_BODY]
    y3 = a[A.CN_TAIL] / beta_m
    y4 = a[A.CN_NOSE] * a[A.ARM_NOSE] + (a[A.CN_WING] * a[A.ARM_WING] + a[A.CN_TAIL] * a[A.ARM_TAIL]) / beta_m
    y5 = a[A.CN_BODY] * a[A.ARM_BODY]
    y6 = a[A.CN_TAIL] * a[A.ARM_TAIL] / beta_m
    p2 = y2 - y3 * y5 / y6
    p3 = y1 - y3 * y4 / y6
    disc = p3 * p3 + 4 * p2 * cn_trim
    if disc < 0:
        raise CaseError("[flight]", "autopilot.design_load_g",
                        f"the airframe cannot trim C_N = {cn_trim:.3g} (no real trim incidence)")
    alpha = (-p3 + math.sqrt(disc)) / (2 * p2) if p2 != 0 else cn_trim / p3
    return PlaneDerivatives(
        cn_alpha=y1 + y2 * alpha, cn_delta=y3, cm_alpha=y4 + y5 * alpha, cm_delta=y6, alpha_trim=alpha)


def linearize(der: PlaneDerivatives, qbar: float, speed: float, mass: float, inertia: float,
              sref: float, dref: float) -> AirframeLinear:
    """Zarchan's airframe parameters from the slopes at dynamic pressure ``qbar`` [Pa], speed [m/s],
    mass [kg], pitch inertia [kg m²], reference area [m²] and length [m]."""
    ma = qbar * sref * dref * der.cm_alpha / inertia
    md = qbar * sref * dref * der.cm_delta / inertia
    za = -qbar * sref * der.cn_alpha / (mass * speed)
    zd = -qbar * sref * der.cn_delta / (mass * speed)
    if ma >= 0:
        raise CaseError("[flight]", "airframe", f"the design airframe is statically unstable "
                        f"(M_alpha = {ma:.3g} 1/s^2): Zarchan's three-loop design needs M_alpha < 0")
    det = ma * zd - md * za
    omega_z = math.sqrt(det / zd)
    omega_af = math.sqrt(-ma)
    zeta_af = 0.5 * omega_af * za / ma
    k1 = -speed * det / ma
    t_alpha = md / det
    return AirframeLinear(ma, md, za, zd, omega_z, omega_af, zeta_af, k1, t_alpha, k1 / speed)


def three_loop_gains(lin: AirframeLinear, speed: float, omega_cr: float, zeta: float,
                     tau: float) -> ThreeLoopGains:
    """Zarchan ch. 23 (Listing 23.1) gain formulas in SI."""
    w = (tau * omega_cr * (1 + 2 * lin.zeta_af * lin.omega_af / omega_cr) - 1) / (2 * zeta * tau)
    w0 = w / math.sqrt(tau * omega_cr)
    z0 = 0.5 * w0 * (2 * zeta / w + tau - lin.omega_af ** 2 / (w0 * w0 * omega_cr))
    kc = ((-w0 ** 2 / lin.omega_z ** 2 - 1 + 2 * z0 * w0 * lin.t_alpha)
          / (1 - 2 * z0 * w0 * lin.t_alpha + w0 * w0 * lin.t_alpha ** 2))
    k_a = lin.k3 / (lin.k1 * kc)
    omega_i = kc * lin.t_alpha * w0 * w0 / (1 + kc + w0 ** 2 / lin.omega_z ** 2)
    k0 = -w * w / (tau * lin.omega_af ** 2)
    k = k0 / (lin.k1 * (1 + kc))
    k_r = k / (k_a * omega_i)
    k_dc = 1 + 1 / (k_a * speed)
    return ThreeLoopGains(k_a, omega_i, k_r, k_dc)


def closed_loop_poles_target(omega_cr: float, zeta: float, tau: float, lin: AirframeLinear) -> np.ndarray:
    """The poles the design places: −1/τ and the pair of natural frequency ω (Zarchan ch. 23), shape (3,)."""
    w = (tau * omega_cr * (1 + 2 * lin.zeta_af * lin.omega_af / omega_cr) - 1) / (2 * zeta * tau)
    return np.roots(np.polymul([tau, 1.0], [1 / w ** 2, 2 * zeta / w, 1.0]))


def roll_gains(l_p: float, l_delta: float, omega: float, zeta: float) -> tuple[float, float]:
    """(K_φ [-], K_p [s]) so that ṗ = l_p p + l_delta δ, δ = −(K_φ φ + K_p p) has poles
    s² + 2ζω s + ω² (l_p [1/s], l_delta [1/s²] per rad)."""
    return omega * omega / l_delta, (2 * zeta * omega + l_p) / l_delta
