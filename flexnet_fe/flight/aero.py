"""Aerodynamics of Zarchan's tail-controlled missile, extended to a cruciform 6-DOF airframe.

Reference: P. Zarchan, *Tactical and Strategic Missile Guidance*, 6th ed., AIAA 2012,
ch. 21 (airframe: slender-body nose and body, linear supersonic wing and tail panels, Eqs. in
Listings 21.2 / 23.1). Per plane (pitch: incidence α, yaw: α'), with β_M = √(M² − 1):

    C_N = 2 α + 1.5 (S_plan/S_ref) α_t α + 8 S_w α / (β_M S_ref) + 8 S_t (α + δ) / (β_M S_ref)
    C_M = 2 α (x_cg − x_cpn)/d + 1.5 (S_plan/S_ref) α_t α (x_cg − x_cpb)/d
          + 8 S_w α (x_cg − x_cpw)/(β_M S_ref d) + 8 S_t (α + δ)(x_cg − x_hl)/(β_M S_ref d)

(C_M positive nose-up about the plane's normal). Departures from Zarchan, and why:
- Zarchan's airframe is a pitch-plane model; the yaw plane uses the same law (axisymmetric
  cruciform missile). His body term 1.5 S_plan α²/S_ref becomes 1.5 S_plan α_t α/S_ref with the
  total incidence α_t = √(α² + α'²), so the body cross-flow force points along the cross flow.
- Zarchan has no roll channel. Roll control and roll damping come from the same linear
  supersonic panel theory (normal-force slope 4/β_M per panel area, strip theory): each
  triangular panel's force acts at its area centroid r_cp = d/2 + h/3 for control, and the roll
  damping moment is −q (4/β_M)(p/V) Σ_panels ∫ c(r) r² dr.
- Paper §VI damage multipliers act on whole-airframe derivatives (as the paper states them):
  k_lift on every α-term of C_N (paper C_y^α, C_z^β), k_moment on every α-term of C_M
  (m_z^α, m_y^β), k_ctrl on every δ-term (control force and moment). Roll damping of the wing
  panels scales with k_lift, of the tail panels with k_ctrl (the paper does not say).

The coefficients are a float64 array indexed by the constants below, so the numba kernel can
read them; β_M divides the panel terms at run time.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from flexnet_fe.flight.config import AirframeConfig

CN_NOSE = 0
"""slender-body nose normal-force slope (2) [-]"""
CN_WING = 1
"""8 S_w / S_ref (× 1/β_M) [-]"""
CN_TAIL = 2
"""8 S_t / S_ref (× 1/β_M) [-]"""
CN_BODY = 3
"""1.5 S_plan / S_ref [-]"""
ARM_NOSE = 4
"""(x_cg − x_cp,nose)/d [-]"""
ARM_WING = 5
"""(x_cg − x_cp,wing)/d [-]"""
ARM_TAIL = 6
"""(x_cg − x_hinge)/d [-]"""
ARM_BODY = 7
"""(x_cg − x_cp,body)/d [-]"""
CL_DELTA = 8
"""roll-control coefficient per rad of mean fin deflection (× 1/β_M) [-]; negative"""
ROLL_DAMP_WING = 9
"""16 ∫c r² dr of one wing panel: M_x = −q (p/V)/β_M Σ [m^4]"""
ROLL_DAMP_TAIL = 10
"""same for one tail panel [m^4]"""
CA = 11
"""axial force coefficient [-]"""
SREF = 12
"""reference area π d²/4 [m^2]"""
DREF = 13
"""reference length d [m]"""
N_AERO = 14


def triangle_panel_r2_integral(root_chord: float, span: float, r0: float) -> float:
    """∫_0^h c(s) (r0 + s)² ds for a panel with chord c(s) = c_r (1 − s/h) [m^4]
    (closed form: c_r (r0² h/2 + r0 h²/3 + h³/12))."""
    h = span
    return root_chord * (r0 * r0 * h / 2 + r0 * h * h / 3 + h ** 3 / 12)


def aero_coefficients(af: AirframeConfig) -> np.ndarray:
    """Zarchan ch. 21 coefficient set of airframe ``af`` (see module doc), shape (N_AERO,)."""
    d, L, ln = af.diameter, af.length, af.nose_length
    sref = np.pi * d * d / 4
    s_wing = 0.5 * af.wing_span * af.wing_root_chord          # one panel, tip chord 0
    s_tail = 0.5 * af.tail_span * af.tail_root_chord
    s_plan = (L - ln) * d + 0.67 * ln * d                     # Zarchan: (L-Ln) d + 1.33 Ln d / 2
    a_nose = 0.67 * ln * d
    a_body = (L - ln) * d
    x_cpn = 2 * ln / 3
    x_cpb = (0.67 * a_nose * ln + a_body * (ln + 0.5 * (L - ln))) / (a_nose + a_body)
    x_cpw = af.wing_root_le + 0.7 * af.wing_root_chord        # Zarchan: +0.7 C_r − 0.2 C_t, C_t = 0
    r0 = d / 2
    r_cp_tail = r0 + af.tail_span / 3                         # centroid of the triangular panel
    a = np.zeros(N_AERO)
    a[CN_NOSE] = 2.0
    a[CN_WING] = 8 * s_wing / sref
    a[CN_TAIL] = 8 * s_tail / sref
    a[CN_BODY] = 1.5 * s_plan / sref
    a[ARM_NOSE] = (af.x_cg - x_cpn) / d
    a[ARM_WING] = (af.x_cg - x_cpw) / d
    a[ARM_TAIL] = (af.x_cg - af.x_hinge) / d
    a[ARM_BODY] = (af.x_cg - x_cpb) / d
    # 4 panels × (4/β) S_t/S_ref × r_cp/d, sign: a positive mean deflection rolls negatively
    # (frame doc in flexnet_fe.flight).
    a[CL_DELTA] = -16 * s_tail * r_cp_tail / (sref * d)
    a[ROLL_DAMP_WING] = 16 * triangle_panel_r2_integral(af.wing_root_chord, af.wing_span, r0)
    a[ROLL_DAMP_TAIL] = 16 * triangle_panel_r2_integral(af.tail_root_chord, af.tail_span, r0)
    a[CA] = af.axial_force_coefficient
    a[SREF] = sref
    a[DREF] = d
    return a


def inertia_diagonal(af: AirframeConfig) -> np.ndarray:
    """(I_xx, I_yy, I_zz) [kg m^2], shape (3,): Zarchan's I_yy = m (3 r² + L²)/12 and a solid
    cylinder's I_xx = m r²/2 unless the case gives them."""
    r = af.diameter / 2
    iyy = af.pitch_inertia if af.pitch_inertia is not None else af.mass * (3 * r * r + af.length ** 2) / 12
    ixx = af.roll_inertia if af.roll_inertia is not None else af.mass * r * r / 2
    return np.array([ixx, iyy, iyy])


@njit(cache=True)
def supersonic_beta(mach):
    """β_M = √(M² − 1) of linear supersonic theory [-]; valid for M > 1."""
    return np.sqrt(mach * mach - 1.0)


@njit(cache=True)
def plane_coefficients(alpha, alpha_total, delta, beta_m, a, k_lift, k_moment, k_ctrl):
    """(C_N, C_M) of one plane (Zarchan ch. 21 law in the module doc, with damage multipliers).

    alpha: incidence in the plane [rad]; alpha_total: total incidence [rad]; delta: fin
    deflection of the plane [rad]; beta_m: √(M²−1); a: coefficient array (aero_coefficients).
    """
    cn_alpha = a[CN_NOSE] + a[CN_BODY] * alpha_total + (a[CN_WING] + a[CN_TAIL]) / beta_m
    cm_alpha = (a[CN_NOSE] * a[ARM_NOSE] + a[CN_BODY] * a[ARM_BODY] * alpha_total
                + (a[CN_WING] * a[ARM_WING] + a[CN_TAIL] * a[ARM_TAIL]) / beta_m)
    cn_delta = a[CN_TAIL] / beta_m
    cm_delta = a[CN_TAIL] * a[ARM_TAIL] / beta_m
    cn = k_lift * cn_alpha * alpha + k_ctrl * cn_delta * delta
    cm = k_moment * cm_alpha * alpha + k_ctrl * cm_delta * delta
    return cn, cm


@njit(cache=True)
def roll_moment(qbar, speed, p, delta_roll, beta_m, a, k_lift, k_ctrl):
    """Roll moment M_x [N m] from mean fin deflection ``delta_roll`` [rad] and roll rate ``p``
    [rad/s] (strip theory with the 4/β_M panel slope, module doc)."""
    control = qbar * a[SREF] * a[DREF] * k_ctrl * a[CL_DELTA] / beta_m * delta_roll
    damping = -qbar * (p / speed) / beta_m * (k_lift * a[ROLL_DAMP_WING] + k_ctrl * a[ROLL_DAMP_TAIL])
    return control + damping
