"""Component build-up of the wing–body–tail airframe (flexnet_fe.flight.airframe, .aero)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from flexnet_fe.flight import airframe as AF
from flexnet_fe.flight.aero import CoefficientScale, loads
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.missile.build import build_missile

BETA = math.sqrt((1000.0 / 308.1) ** 2 - 1)     # launch: 1000 m/s at ~8–9 km
ONE = CoefficientScale(1.0, 1.0, 1.0)


@pytest.fixture(scope="module")
def missile():
    return build_missile(MissileConfig(preset="radar"))


@pytest.fixture(scope="module")
def af(missile):
    return AF.build_airframe(missile)


@pytest.mark.parametrize("tau", [0.1, 0.2, 0.33, 0.5, 0.7, 0.9])
def test_interference_factors_against_slender_body_span_loading(tau):
    # Independent reference: slender-body theory of a wing–body (Nielsen, Missile Aerodynamics,
    # ch. 5): across the wing (a ≤ y ≤ s) the potential jumps by Δφ = 2Vα √((s + a²/s)² − (y + a²/y)²),
    # across the exposed panels joined alone by 2Vα √((s − a)² − y²); the lift is ρV ∫Δφ dy, so
    # K_W(B) = ∫_a^s √(...) dy / (π (s − a)²/4), here by adaptive quadrature (error < 1e-10).
    a, s = tau, 1.0
    panels = quad(lambda y: math.sqrt(max((s + a * a / s) ** 2 - (y + a * a / y) ** 2, 0.0)), a, s,
                  epsabs=1e-13, epsrel=1e-12)[0]
    kwb, kbw = AF.interference_factors(tau)
    assert kwb == pytest.approx(panels / (math.pi * (s - a) ** 2 / 4), rel=1e-8)
    # combination: 2πα s²(1 − τ²)² over the wing alone 2πα (s − a)² (NACA Report 1307)
    assert kwb + kbw == pytest.approx((1 + tau) ** 2, rel=1e-14)


def test_nose_centre_of_pressure_slender_body(missile):
    # Munk: x_cp = L_n − V/(π R²): a cone gives 2/3 L_n exactly; a tangent ogive of fineness
    # L_n/D = 2.96 (the radar preset) gives ≈ 0.466 L_n (Barrowman's ogive value, which is the
    # slender-body value for ogives of fineness ≈ 3; difference < 1 %).
    cone = build_missile(MissileConfig(preset="radar", nose_shape="cone"))
    assert AF.nose_centre_of_pressure(cone) == pytest.approx(2 / 3 * cone.nose_length, rel=1e-12)
    assert AF.nose_centre_of_pressure(missile) / missile.nose_length == pytest.approx(0.466, rel=0.01)


def test_panel_centroid_is_the_polygon_centroid(missile):
    # shoelace centroid of the fin's corner polygon (fin frame u, v): independent formula
    for fin in missile.fins[::4]:
        u, v = fin.uv[:, 0], fin.uv[:, 1]
        cross = u * np.roll(v, -1) - np.roll(u, -1) * v
        area = 0.5 * cross.sum()
        cu = ((u + np.roll(u, -1)) * cross).sum() / (6 * area)
        cv = ((v + np.roll(v, -1)) * cross).sum() / (6 * area)
        assert AF.panel_centroid(fin) == pytest.approx((cu, cv), rel=1e-12)
        assert abs(area) == pytest.approx(fin.area, rel=1e-12)


def _fd_slopes(af, beta, h=1e-6):
    """(C_Nα, C_Mα, C_Nδ, C_Mδ) by central differences of the 6-DOF force law (aero.loads)."""
    v = 1000.0

    def coeff(alpha, dp):
        vb = np.array([v * math.cos(alpha), -v * math.sin(alpha), 0.0])
        f, m = loads(af, ONE, vb, np.zeros(3), np.array([0.0, dp, 0.0, -dp]), 1.0, beta)
        return np.array([f[1] / af.sref, m[2] / (af.sref * af.dref)])

    d_alpha = (coeff(h, 0.0) - coeff(-h, 0.0)) / (2 * h)
    d_delta = (coeff(0.0, h) - coeff(0.0, -h)) / (2 * h)
    return d_alpha[0], d_alpha[1], d_delta[0], d_delta[1]


def test_closed_form_slopes_equal_the_6dof_force_law(af):
    # Two implementations of the same components: the closed-form sums (airframe.pitch_slopes) and
    # the vector force law the 6-DOF integrates (aero.loads), differentiated numerically (central
    # differences, h = 1e-6: error O(h²) plus the α|α| cross-flow term, which has zero slope at 0).
    sl = AF.pitch_slopes(af, BETA)
    cn_a, cm_a, cn_d, cm_d = _fd_slopes(af, BETA)
    assert cn_a == pytest.approx(sl.cn_alpha, rel=1e-6)
    assert cm_a == pytest.approx(sl.cm_alpha, rel=1e-6)
    assert cn_d == pytest.approx(sl.cn_delta, rel=1e-6)
    assert cm_d == pytest.approx(sl.cm_delta, rel=1e-6)
    # pitch damping: ∂C_M/∂(q d/V) of the panels' rate incidence
    v, d, h = 1000.0, af.dref, 1e-3
    m = [loads(af, ONE, np.array([v, 0, 0.0]), np.array([0.0, 0.0, s * h]), np.zeros(4), 1.0, BETA)[1][2]
         for s in (1, -1)]
    cm_q = (m[0] - m[1]) / (2 * h) / (af.sref * d) * v / d
    assert cm_q == pytest.approx(sl.cm_q, rel=1e-9)


def test_removing_the_wings_shifts_the_centre_of_pressure_by_the_component_moments(af):
    # Closed form: s_cp = Σ N_i s_i / Σ N_i over components; removing the wing pairs (normal-force
    # slope N_w at station s_w) gives s_cp' = (N s_cp − N_w s_w)/(N − N_w).
    sl = AF.pitch_slopes(af, BETA)
    s_cp = AF.centre_of_pressure(af, BETA)
    n_w = float(((af.panel_slope + af.carry_slope) * af.panel_normal[:, 1] ** 2)[:4].sum() / BETA)
    s_w = af.s_cg - af.panel_cp[0, 0]
    expect = (sl.cn_alpha * s_cp - n_w * s_w) / (sl.cn_alpha - n_w)
    no_wings = AF.damaged(af, np.array([0, 0, 0, 0, 1, 1, 1, 1.0]))
    assert AF.centre_of_pressure(no_wings, BETA) == pytest.approx(expect, rel=1e-12)
    # the AIM-7M-class wings sit ahead of the CG (centroid 1.81 m, CG 1.98 m): losing them moves
    # the centre of pressure aft, i.e. the static margin grows (the paper's "m_z^α increases")
    assert AF.static_margin(no_wings, BETA) > AF.static_margin(af, BETA) > 0


def test_one_wing_lost_rolls_the_missile(af):
    # Asymmetric damage: wing_2 (right, +z) lost; at incidence α the left wing's lift F at radius
    # r_cp is no longer balanced: M_x = r_cp F (r × F with r = (·, 0, −r_cp), F = (0, F, 0)).
    rem = np.ones(8)
    rem[1] = 0.0
    dmg = AF.damaged(af, rem)
    alpha, v = 0.05, 1000.0
    vb = np.array([v * math.cos(alpha), -v * math.sin(alpha), 0.0])
    mx = loads(dmg, ONE, vb, np.zeros(3), np.zeros(4), 1.0, BETA)[1][0]
    f_left = af.panel_slope[3] / BETA * af.sref * math.sin(alpha)      # panel force only (carry-over on the axis)
    assert mx == pytest.approx(abs(af.panel_cp[3, 2]) * f_left, rel=1e-12)


def test_coefficient_scaling_readings_scale_whole_airframe_terms(af):
    # paper §VI readings: α-force × k_lift, α-moment × k_moment, control × k_ctrl; rates unscaled
    v, alpha = 1000.0, 0.02
    vb = np.array([v * math.cos(alpha), -v * math.sin(alpha), 0.0])
    fins = np.array([0.0, 0.01, 0.0, -0.01])
    f1, m1 = loads(af, ONE, vb, np.zeros(3), np.zeros(4), 1.0, BETA)
    fd, md = loads(af, ONE, np.array([v, 0, 0.0]), np.zeros(3), fins, 1.0, BETA)
    f, m = loads(af, CoefficientScale(0.6, 1.4, 0.5), vb, np.zeros(3), fins, 1.0, BETA)
    assert f[1] == pytest.approx(0.6 * f1[1] + 0.5 * fd[1], rel=1e-12)
    assert m[2] == pytest.approx(1.4 * m1[2] + 0.5 * md[2], rel=1e-12)
