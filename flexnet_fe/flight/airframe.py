"""Component build-up of a wing–body–tail missile (the flight stage's airframe).

The airframe is the case's ``[missile]`` geometry (``flexnet_fe.missile``, AIM-7M class by default)
seen as lifting components, each with its own normal-force slope and centre of pressure:

* **Nose** (slender-body theory, Munk 1924; e.g. Nielsen, *Missile Aerodynamics*, 1960, ch. 3):
  C_Nα = 2 on the base area π R², centre of pressure at x_cp = L_n − V_nose/(π R²) (exact for
  any nose in slender-body theory: 2/3 L_n for a cone, 0.466 L_n for a tangent ogive of 3 calibres).
* **Body cross-flow** (viscous cross-flow, Allen & Perkins NACA TR 1048, in Zarchan's form
  *Tactical and Strategic Missile Guidance*, 6th ed., ch. 21): C_N = 1.5 (S_plan/S_ref) α_t α
  at the centroid of the body planform (nose planform taken as 2/3 L_n d, as Zarchan).
* **Fin panels** (each of the 4 wings and 4 rudders separately): linear supersonic (Ackeret)
  panel theory, normal-force slope 4/β_M per panel area (β_M = √(M² − 1); valid while every
  leading edge is supersonic, M cos Λ_LE > 1), centre of pressure at the panel's area centroid
  (uniform loading of Ackeret theory), times the slender-body wing–body interference factors of
  Pitts, Nielsen & Kaattari (NACA Report 1307, 1957) at τ = R/(R + b):

      K_W(B) = 2/π [ (1 + τ⁴)(½ atan(½(1/τ − τ)) + π/4) − τ²((1/τ − τ) + 2 atan τ) ] / (1 − τ)²
      K_B(W) = (1 + τ)² − K_W(B)

  K_W(B) acts on the panel (at its centroid), K_B(W) is the lift the panel carries over onto the
  body (at the body axis, at the panel's centroid station). Roll control and roll damping come
  from the same panels (strip theory: the damping of a panel is (4/β) ∫ c(r) r² dr).

Departures (stated; each is a refinement, not a change of the method): the tip Mach-cone lift
loss is neglected (rectangular-panel estimate 1 − 1/(2βA) ≈ 0.90 for the wings at Mach 3.2); a
deflected panel uses the same interference factors as a panel at incidence (NACA 1307's k_W(B),
k_B(W) are ≈ 10 % lower); no wing-to-tail downwash; body pitch damping neglected (the panels give
the damping); C_A = 0 (thrust balances drag, as Zarchan's constant-speed airframe).

Damage (paper §VI by geometry): panel i keeps a fraction ``remaining[i]`` of its lift, carry-over
and roll damping (its area, for a panel that loses a share of its area uniformly along the span;
its centre of pressure stays). So the centre of pressure, static margin, control effectiveness
and damping move as the component moments say. The paper's own coefficient-scaling readings act
as multipliers on the whole-airframe α-, δ-terms instead (``flexnet_fe.flight.config.DamageModel``).

Frames: body axes of ``flexnet_fe.flight`` (x_b forward, origin at the CG). Stations s are
distances aft of the nose apex (``flexnet_fe.frames`` frame B, s = −x_b).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from flexnet_fe.missile.geometry import Fin, FinKind, Missile, nose_radius

N_PANELS = 8
"""wing_1..wing_4, rudder_1..rudder_4 (the order of ``flexnet_fe.missile.geometry.build_fins``)."""
BODY_CROSSFLOW = 1.5
"""Zarchan's body cross-flow factor (η C_dc ≈ 1.5) of C_N = 1.5 (S_plan/S_ref) α_t α [-]"""


class Airframe(NamedTuple):
    """The missile as lifting components (numba-readable: floats and float64 arrays; SI units).

    Stations s are aft of the nose apex [m]; panel arrays have shape (8,) or (8, 3), order
    wing_1..4, rudder_1..4. Slopes are per rad and per S_ref and still to be divided by β_M.
    """

    mass: float
    """[kg]"""
    inertia: np.ndarray
    """principal moments (I_xx, I_yy, I_zz) about the CG [kg m²], shape (3,)"""
    s_cg: float
    """CG station [m]"""
    sref: float
    """reference area π d²/4 [m²]"""
    dref: float
    """reference length d [m]"""
    nose_slope: float
    """slender-body nose C_Nα = 2 [-]"""
    s_nose: float
    """nose centre of pressure station [m]"""
    crossflow: float
    """1.5 S_plan/S_ref [-]"""
    s_crossflow: float
    """body planform centroid station [m]"""
    panel_slope: np.ndarray
    """β_M × C_Nα of each panel on the body, 4 K_W(B) S_panel/S_ref [-], shape (8,)"""
    carry_slope: np.ndarray
    """β_M × C_Nα of the lift each panel carries onto the body, 4 K_B(W) S_panel/S_ref, shape (8,)"""
    panel_cp: np.ndarray
    """panel centroid relative to the CG in body axes [m], shape (8, 3)"""
    panel_normal: np.ndarray
    """unit panel normal n = e1 × e2 (``flexnet_fe.missile.geometry``), body axes, shape (8, 3)"""
    panel_roll_damp: np.ndarray
    """4 K_W(B) ∫ c r² dr / (S_ref d²) of each panel (× 1/β_M) [-], shape (8,)"""
    is_control: np.ndarray
    """1.0 for a rudder (deflected by its actuator), 0.0 for a wing, shape (8,)"""
    mach_min: float
    """lowest Mach at which every leading edge is supersonic (1/cos Λ_LE of the most swept) [-]"""


def interference_factors(tau: float) -> tuple[float, float]:
    """(K_W(B), K_B(W)) of slender-body theory, NACA Report 1307 (τ = body radius / semispan
    incl. the body, 0 ≤ τ < 1). K_W(B) + K_B(W) = (1 + τ)² (lift of the combination)."""
    if not 0.0 <= tau < 1.0:
        raise ValueError(f"interference factors need 0 <= tau < 1, got {tau}")
    if tau == 0.0:
        return 1.0, 0.0
    t2, t4 = tau * tau, tau ** 4
    num = (1 + t4) * (0.5 * math.atan(0.5 * (1 / tau - tau)) + math.pi / 4) - t2 * ((1 / tau - tau) + 2 * math.atan(tau))
    kwb = 2 / math.pi * num / (1 - tau) ** 2
    return kwb, (1 + tau) ** 2 - kwb


def panel_centroid(fin: Fin) -> tuple[float, float]:
    """(spanwise u, chordwise v) of the trapezoid's area centroid in the fin frame [m]
    (u from the root along the span, v aft of the root leading edge)."""
    cr, ct, b = fin.root_chord, fin.tip_chord, fin.span
    xt = b * math.tan(fin.leading_edge_sweep)
    u = b * (cr + 2 * ct) / (3 * (cr + ct))
    v = (xt * (cr + 2 * ct) + cr * cr + cr * ct + ct * ct) / (3 * (cr + ct))
    return u, v


def panel_r2_integral(fin: Fin, r0: float) -> float:
    """∫_0^b c(u) (r0 + u)² du [m⁴] for the chord c(u) = c_r + (c_t − c_r) u/b (3-point
    Gauss–Legendre: exact for this cubic)."""
    x, w = np.polynomial.legendre.leggauss(3)
    u = 0.5 * fin.span * (x + 1)
    c = fin.root_chord + (fin.tip_chord - fin.root_chord) * u / fin.span
    return float(0.5 * fin.span * np.sum(w * c * (r0 + u) ** 2))


def nose_centre_of_pressure(missile: Missile) -> float:
    """Slender-body nose centre of pressure station L_n − V_nose/(π R²) [m] (Munk)."""
    x, w = np.polynomial.legendre.leggauss(64)
    s = 0.5 * missile.nose_length * (x + 1)
    r = nose_radius(s, missile.radius, missile.nose_shape, missile.nose_length)
    vol = float(0.5 * missile.nose_length * np.sum(w * np.pi * r * r))
    return missile.nose_length - vol / (math.pi * missile.radius ** 2)


def build_airframe(missile: Missile) -> Airframe:
    """The component airframe of ``missile`` (undamaged; see :func:`damaged`)."""
    d = 2 * missile.radius
    L, ln, R = missile.length, missile.nose_length, missile.radius
    sref = math.pi * R * R
    s_cg = -float(missile.cg[0])
    a_nose, a_body = 2.0 / 3.0 * ln * d, (L - ln) * d                 # planforms (Zarchan)
    s_cf = (a_nose * 2.0 / 3.0 * ln + a_body * (ln + 0.5 * (L - ln))) / (a_nose + a_body)
    slope, carry, cp, normal, damp, ctrl = (np.zeros(N_PANELS), np.zeros(N_PANELS), np.zeros((N_PANELS, 3)),
                                            np.zeros((N_PANELS, 3)), np.zeros(N_PANELS), np.zeros(N_PANELS))
    for i, fin in enumerate(missile.fins):
        kwb, kbw = interference_factors(R / (R + fin.span))
        u, v = panel_centroid(fin)
        p = fin.origin + u * fin.e1 + v * fin.e2                       # centroid in B (apex origin)
        cp[i] = p - missile.cg
        normal[i] = fin.n
        slope[i] = 4 * kwb * fin.area / sref
        carry[i] = 4 * kbw * fin.area / sref
        damp[i] = 4 * kwb * panel_r2_integral(fin, R) / (sref * d * d)
        ctrl[i] = 1.0 if fin.kind is FinKind.RUDDER else 0.0
    mach_min = max(1.0 / math.cos(f.leading_edge_sweep) for f in missile.fins)
    inertia = np.linalg.eigvalsh(missile.inertia) if not np.allclose(
        missile.inertia, np.diag(np.diag(missile.inertia))) else np.diag(missile.inertia).copy()
    return Airframe(mass=float(missile.mass), inertia=np.asarray(inertia, dtype=float), s_cg=s_cg,
                    sref=sref, dref=d, nose_slope=2.0, s_nose=nose_centre_of_pressure(missile),
                    crossflow=BODY_CROSSFLOW * (a_nose + a_body) / sref, s_crossflow=s_cf,
                    panel_slope=slope, carry_slope=carry, panel_cp=cp, panel_normal=normal,
                    panel_roll_damp=damp, is_control=ctrl, mach_min=mach_min)


def damaged(af: Airframe, remaining: np.ndarray) -> Airframe:
    """The airframe with panel i keeping the fraction ``remaining[i]`` ∈ [0, 1] of its lift,
    carry-over and roll damping (shape (8,), order wing_1..4, rudder_1..4)."""
    rem = np.asarray(remaining, dtype=float)
    if rem.shape != (N_PANELS,) or np.any(rem < 0) or np.any(rem > 1):
        raise ValueError(f"remaining must be 8 fractions in [0, 1], got {remaining!r}")
    return af._replace(panel_slope=af.panel_slope * rem, carry_slope=af.carry_slope * rem,
                       panel_roll_damp=af.panel_roll_damp * rem)


class PlaneSlopes(NamedTuple):
    """Linear normal-force and moment slopes of one plane (pitch, symmetric airframe) at Mach
    number with β_M; moments about the CG, positive nose-up, on S_ref and d [1/rad]."""

    cn_alpha: float
    """linear C_Nα (nose + panels + carry-over) [-]"""
    cm_alpha: float
    """C_Mα = −Σ C_Nα,i (s_i − s_cg)/d [-]"""
    cn_alpha2: float
    """coefficient of α_t α in C_N (body cross-flow) [-]"""
    cm_alpha2: float
    """coefficient of α_t α in C_M [-]"""
    cn_delta: float
    """C_Nδ of the pitch deflection (δ1 − δ3)/2 [-]"""
    cm_delta: float
    cm_q: float
    """pitch damping ∂C_M/∂(q d/V) [-]"""


def pitch_slopes(af: Airframe, beta_m: float) -> PlaneSlopes:
    """The pitch-plane slopes of the component sum (closed form of the same components the
    6-DOF force law :func:`flexnet_fe.flight.aero.aero_loads` adds up): panel i contributes with
    the share n_y² of its normal that lies in the pitch plane."""
    ny2 = af.panel_normal[:, 1] ** 2
    arm = af.panel_cp[:, 0] / af.dref                                  # (x_i − x_cg)/d, + forward
    a_pan = (af.panel_slope + af.carry_slope) * ny2 / beta_m
    cn_a = af.nose_slope + a_pan.sum()
    cm_a = af.nose_slope * (af.s_cg - af.s_nose) / af.dref + np.sum(a_pan * arm)
    ctrl = a_pan * af.is_control
    return PlaneSlopes(
        cn_alpha=float(cn_a), cm_alpha=float(cm_a), cn_alpha2=af.crossflow,
        cm_alpha2=af.crossflow * (af.s_cg - af.s_crossflow) / af.dref,
        cn_delta=float(ctrl.sum()) , cm_delta=float(np.sum(ctrl * arm)),
        cm_q=-float(np.sum(a_pan * arm * arm)))


def centre_of_pressure(af: Airframe, beta_m: float) -> float:
    """Station of the linear (α → 0) centre of pressure, s_cp = s_cg − d C_Mα/C_Nα [m]."""
    sl = pitch_slopes(af, beta_m)
    return af.s_cg - af.dref * sl.cm_alpha / sl.cn_alpha


def static_margin(af: Airframe, beta_m: float) -> float:
    """(s_cp − s_cg)/d [calibres]: positive = statically stable."""
    return (centre_of_pressure(af, beta_m) - af.s_cg) / af.dref
