"""Acceleration autopilot design (fixed gains for the undamaged missile).

Pitch and yaw: Zarchan's three-loop autopilot (*Tactical and Strategic Missile Guidance*, 6th ed.,
ch. 23, Listing 23.1): with body rate θ̇ (rate gyro), achieved acceleration n_L (accelerometer at
the CG) and command n_c,

    ẋ = ω_I (θ̇ + K_A (n_L − K_DC n_c)),      δ_c = K_R (x + θ̇).

The gains place the closed-loop poles (without actuator) at the roots of
(1 + τ s)(1 + 2ζ s/ω + s²/ω²) for a chosen open-loop crossover ω_cr (Zarchan's design formulas,
here in SI with accelerations in m/s² and angles in rad, so Zarchan's 1845 = 32.2·57.3 becomes 1).
Departure: Zarchan's airframe has no pitch damping; ours has M_q (the panels' rate term), so his
closed-form gains are only the starting point of a Newton solve that places the same poles on
the airframe with M_q (:func:`three_loop_gains`). The airframe is linearised at the trim
incidence of ``design_load_g`` (Zarchan ch. 21 trim, secant slopes).

Roll: PD roll-angle hold δ_roll = −(K_φ φ + K_p p), poles of s² + 2ζω s + ω².
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scipy.optimize import fsolve

from flexnet_fe.errors import CaseError
from flexnet_fe.flight.airframe import PlaneSlopes


@dataclass(frozen=True)
class PlaneDerivatives:
    """Secant coefficient slopes of one plane at a trim incidence (Zarchan ch. 21) [1/rad]."""

    cn_alpha: float
    cn_delta: float
    cm_alpha: float
    cm_delta: float
    cm_q: float
    """pitch damping ∂C_M/∂(q d/V)"""
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
    m_q: float
    """M_q [1/s]"""
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


def plane_derivatives(sl: PlaneSlopes, cn_trim: float, alpha: float | None = None) -> PlaneDerivatives:
    """Trim incidence for normal-force coefficient ``cn_trim`` and the secant slopes there
    (Zarchan ch. 21: moment balance C_M = 0 with δ eliminated, then a quadratic in α), or the
    secant slopes at a given incidence ``alpha`` [rad] (a damaged airframe flown at the design
    point, which it may not be able to trim). C_N = y1 α + y2 α² + y3 δ, C_M = y4 α + y5 α² + y6 δ."""
    y1, y2, y3 = sl.cn_alpha, sl.cn_alpha2, sl.cn_delta
    y4, y5, y6 = sl.cm_alpha, sl.cm_alpha2, sl.cm_delta
    if alpha is not None:
        return PlaneDerivatives(cn_alpha=y1 + y2 * alpha, cn_delta=y3, cm_alpha=y4 + y5 * alpha, cm_delta=y6,
                                cm_q=sl.cm_q, alpha_trim=alpha)
    p2 = y2 - y3 * y5 / y6
    p3 = y1 - y3 * y4 / y6
    disc = p3 * p3 + 4 * p2 * cn_trim
    if disc < 0:
        raise CaseError("[flight]", "autopilot.design_load_g",
                        f"the airframe cannot trim C_N = {cn_trim:.3g} (no real trim incidence)")
    alpha = (-p3 + math.sqrt(disc)) / (2 * p2) if p2 != 0 else cn_trim / p3
    return PlaneDerivatives(cn_alpha=y1 + y2 * alpha, cn_delta=y3, cm_alpha=y4 + y5 * alpha, cm_delta=y6,
                            cm_q=sl.cm_q, alpha_trim=alpha)


def linearize(der: PlaneDerivatives, qbar: float, speed: float, mass: float, inertia: float,
              sref: float, dref: float) -> AirframeLinear:
    """Short-period derivatives and Zarchan's airframe parameters from the slopes at dynamic
    pressure ``qbar`` [Pa], speed [m/s], mass [kg], pitch inertia [kg m²], reference area [m²]
    and length [m]."""
    ma = qbar * sref * dref * der.cm_alpha / inertia
    md = qbar * sref * dref * der.cm_delta / inertia
    mq = qbar * sref * dref * dref * der.cm_q / (inertia * speed)
    za = -qbar * sref * der.cn_alpha / (mass * speed)
    zd = -qbar * sref * der.cn_delta / (mass * speed)
    det = ma * zd - md * za
    # Zarchan's parameters exist for a statically stable airframe (M_α < 0); NaN otherwise
    # (a damaged airframe is linearised for its loop poles, which need only Z, M).
    stable = ma < 0 and zd != 0 and det != 0
    omega_z = math.sqrt(det / zd) if stable and det / zd > 0 else math.nan
    omega_af = math.sqrt(za * mq - ma) if za * mq - ma > 0 else math.nan   # s² − (Z_α + M_q) s + (Z_α M_q − M_α)
    zeta_af = -(za + mq) / (2 * omega_af)
    k1 = -speed * det / ma if stable else math.nan
    t_alpha = md / det if stable else math.nan
    return AirframeLinear(ma, md, mq, za, zd, omega_z, omega_af, zeta_af, k1, t_alpha, k1 / speed)


def zarchan_gains(lin: AirframeLinear, speed: float, omega_cr: float, zeta: float,
                  tau: float) -> ThreeLoopGains:
    """Zarchan ch. 23 (Listing 23.1) gain formulas in SI (exact for M_q = 0)."""
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


def loop_matrix(lin: AirframeLinear, g: ThreeLoopGains, speed: float,
                actuator: tuple[float, float] | None = None) -> np.ndarray:
    """Closed-loop matrix of the short-period airframe + three-loop autopilot (+ a 2nd-order
    actuator (ω_a, ζ_a) if given): states (α, q, x[, δ, δ̇]), command n_c = 0.

        α̇ = q + Z_α α + Z_δ δ,  q̇ = M_α α + M_q q + M_δ δ,  n_L = −V (Z_α α + Z_δ δ),
        ẋ = ω_I (q + K_A n_L),  δ_c = K_R (x + q)."""
    za, zd, ma, md, mq = lin.z_alpha, lin.z_delta, lin.m_alpha, lin.m_delta, lin.m_q
    if actuator is None:       # δ = δ_c = K_R (x + q)
        kr = g.k_r
        return np.array([
            [za, 1 + zd * kr, zd * kr],
            [ma, mq + md * kr, md * kr],
            [-g.omega_i * g.k_a * speed * za, g.omega_i * (1 - g.k_a * speed * zd * kr),
             -g.omega_i * g.k_a * speed * zd * kr]])
    wa, zeta_a = actuator
    return np.array([
        [za, 1.0, 0.0, zd, 0.0],
        [ma, mq, 0.0, md, 0.0],
        [-g.omega_i * g.k_a * speed * za, g.omega_i, 0.0, -g.omega_i * g.k_a * speed * zd, 0.0],
        [0.0, 0.0, 0.0, 0.0, 1.0],
        [0.0, wa * wa * g.k_r, wa * wa * g.k_r, -wa * wa, -2 * zeta_a * wa]])


def three_loop_gains(lin: AirframeLinear, speed: float, omega_cr: float, zeta: float,
                     tau: float) -> ThreeLoopGains:
    """Gains placing the closed-loop poles (no actuator) at Zarchan's design poles on the
    airframe with pitch damping M_q: Newton solve (scipy ``fsolve``) on the characteristic
    polynomial, started from Zarchan's closed form. K_DC = 1 + 1/(K_A V) gives unit DC gain
    (steady turn q = n_L/V; independent of M_q)."""
    target = np.real(np.poly(closed_loop_poles_target(omega_cr, zeta, tau, lin)))
    g0 = zarchan_gains(lin, speed, omega_cr, zeta, tau)

    def residual(x):
        g = ThreeLoopGains(x[0], x[1], x[2], 1.0)
        return (np.real(np.poly(loop_matrix(lin, g, speed))) - target)[1:] / np.abs(target[1:])

    x, _info, ier, msg = fsolve(residual, [g0.k_a, g0.omega_i, g0.k_r], full_output=True, xtol=1e-13)
    if ier != 1 or np.max(np.abs(residual(x))) > 1e-9:
        raise CaseError("[flight]", "autopilot", f"three-loop pole placement did not converge ({msg})")
    return ThreeLoopGains(x[0], x[1], x[2], 1 + 1 / (x[0] * speed))


def open_loop_at_actuator(lin: AirframeLinear, g: ThreeLoopGains, speed: float, omega: np.ndarray,
                          actuator: tuple[float, float] | None = None) -> np.ndarray:
    """Loop transfer L(jω) broken at the fin command (closed loop: 1 + L = 0), shape like omega:
    L = −K_R [(1 + ω_I/s) q(s) + (ω_I K_A/s) n_L(s)]/δ(s) × A(s) with A the actuator (or 1)."""
    za, zd, ma, md, mq = lin.z_alpha, lin.z_delta, lin.m_alpha, lin.m_delta, lin.m_q
    s = 1j * np.asarray(omega, dtype=float)
    # (sI − A)⁻¹ b for A = [[Z_α, 1], [M_α, M_q]], b = (Z_δ, M_δ), by Cramer's rule
    det = (s - za) * (s - mq) - ma
    alpha = ((s - mq) * zd + md) / det
    q = (ma * zd + (s - za) * md) / det
    n_l = -speed * (za * alpha + zd)
    act = 1.0 if actuator is None else actuator[0] ** 2 / (s * s + 2 * actuator[1] * actuator[0] * s + actuator[0] ** 2)
    return -g.k_r * ((1 + g.omega_i / s) * q + g.omega_i * g.k_a / s * n_l) * act


def loop_margins(lin: AirframeLinear, g: ThreeLoopGains, speed: float,
                 actuator: tuple[float, float] | None = None) -> dict:
    """Stability margins of :func:`open_loop_at_actuator` (scan 0.1–1e4 rad/s, 20 001 log points,
    linear interpolation between points): gain crossover ω_c [rad/s] (last |L| = 1), phase margin
    180° + ∠L(jω_c) [deg], and at every phase crossover (∠L = ±180°) the gain margin −20 log|L|
    [dB]; the one closest to 0 dB is reported."""
    w = np.logspace(-1, 4, 20001)
    lw = open_loop_at_actuator(lin, g, speed, w, actuator)
    mag = np.abs(lw)
    out: dict = {}
    i = np.nonzero((mag[:-1] >= 1) & (mag[1:] < 1))[0]
    if len(i):
        k = i[-1]
        f = np.log(mag[k]) / (np.log(mag[k]) - np.log(mag[k + 1]))
        out["crossover_radps"] = float(w[k] * (w[k + 1] / w[k]) ** f)
        lc = lw[k] + f * (lw[k + 1] - lw[k])
        out["phase_margin_deg"] = float((math.degrees(np.angle(lc)) + 360.0) % 360.0 - 180.0)
    j = np.nonzero((np.sign(lw.imag[:-1]) != np.sign(lw.imag[1:])) & (lw.real[:-1] < 0))[0]
    if len(j):
        gms = [(-20 * math.log10(abs(lw[k].real - lw[k].imag * (lw[k + 1].real - lw[k].real)
                                     / (lw[k + 1].imag - lw[k].imag))), float(w[k])) for k in j]
        gm, wp = min(gms, key=lambda t: abs(t[0]))
        out["gain_margin_db"], out["phase_crossover_radps"] = float(gm), wp
    return out


def roll_gains(l_p: float, l_delta: float, omega: float, zeta: float) -> tuple[float, float]:
    """(K_φ [-], K_p [s]) so that ṗ = l_p p + l_delta δ, δ = −(K_φ φ + K_p p) has poles
    s² + 2ζω s + ω² (l_p [1/s], l_delta [1/s²] per rad)."""
    return omega * omega / l_delta, (2 * zeta * omega + l_p) / l_delta
