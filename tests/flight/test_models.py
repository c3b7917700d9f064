"""Atmosphere, airframe trim, autopilot pole placement, target turn, damage multipliers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexnet_fe.atmosphere import isa
from flexnet_fe.flight import airframe as AF
from flexnet_fe.flight.aero import CoefficientScale, loads, supersonic_beta
from flexnet_fe.flight.autopilot import (
    closed_loop_poles_target, linearize, loop_margins, loop_matrix, plane_derivatives, roll_gains,
    three_loop_gains, zarchan_gains)
from flexnet_fe.flight.config import DamageConfig, DamageModel, FlightConfig
from flexnet_fe.flight.stage import airframe_of, damaged_airframe, design_autopilot, fin_damage
from flexnet_fe.flight.target import level_turn, turn_rate

ONE = CoefficientScale(1.0, 1.0, 1.0)


def test_isa_at_8km_geometric():
    air = isa(8000.0)
    # ISO 2533 / U.S. Standard Atmosphere 1976 table at 8000 m geometric: ρ = 0.52579 kg/m³,
    # a = 308.105 m/s (table values given to 5–6 digits: tolerance half a unit in the last digit).
    assert abs(air.density - 0.52579) < 0.5e-5
    assert abs(air.speed_of_sound - 308.105) < 0.5e-3


@pytest.fixture(scope="module")
def design():
    af = airframe_of(None)
    air = isa(9000.0)
    v = 1000.0
    beta_m = supersonic_beta(v / air.speed_of_sound)
    qbar = 0.5 * air.density * v * v
    cn_trim = af.mass * 9.81 * 10.0 / (qbar * af.sref)
    der = plane_derivatives(AF.pitch_slopes(af, beta_m), cn_trim)
    lin = linearize(der, qbar, v, af.mass, af.inertia[1], af.sref, af.dref)
    return af, beta_m, cn_trim, der, lin, v, qbar


def test_trim_point_balances_moment(design):
    af, beta_m, cn_trim, der, _, v, qbar = design
    # Trim from Zarchan's quadratic must make the full 6-DOF force law (aero.loads, the vector sum
    # of the components) give C_M = 0 and C_N = C_N,trim at (α_tr, δ_tr = −C_M(α_tr, 0)/C_M,δ).
    alpha = der.alpha_trim
    vb = np.array([v * math.cos(alpha), -v * math.sin(alpha), 0.0])

    def cn_cm(delta):
        f, m = loads(af, ONE, vb, np.zeros(3), np.array([0.0, delta, 0.0, -delta]), qbar, beta_m)
        return f[1] / (qbar * af.sref), m[2] / (qbar * af.sref * af.dref)

    cm0 = cn_cm(0.0)[1]
    delta = -cm0 / der.cm_delta
    cn, cm = cn_cm(delta)
    # the force law resolves along the body axes with sin α (the quadratic uses α): error O(α³)
    assert abs(cm) < 2e-3 * abs(cm0)
    assert cn == pytest.approx(cn_trim, rel=2e-3)


def test_three_loop_gains_place_the_designed_poles(design):
    _, _, _, _, lin, v, _ = design
    wcr, zeta, tau = 50.0, 0.7, 0.3
    g = three_loop_gains(lin, v, wcr, zeta, tau)
    # Independent model: the physical short-period equations with pitch damping M_q (written out
    # here, not autopilot.loop_matrix): α̇ = q + Z_α α + Z_δ δ, q̇ = M_α α + M_q q + M_δ δ,
    # n_L = −V (Z_α α + Z_δ δ), ẋ = ω_I (q + K_A (n_L − K_DC n_c)), δ = K_R (x + q).
    # Closed-loop poles must be the design's −1/τ and ω(−ζ ± i√(1−ζ²)); DC gain n_L/n_c = 1.
    za, zd, ma, md, mq = lin.z_alpha, lin.z_delta, lin.m_alpha, lin.m_delta, lin.m_q
    kr, wi, ka, kdc = g.k_r, g.omega_i, g.k_a, g.k_dc
    a_mat = np.array([
        [za, 1 + zd * kr, zd * kr],
        [ma, mq + md * kr, md * kr],
        [wi * ka * (-v) * za, wi * (1 + ka * (-v) * (zd * kr)), wi * ka * (-v) * zd * kr],
    ])
    b = np.array([0.0, 0.0, -wi * ka * kdc])
    poles = np.sort_complex(np.linalg.eigvals(a_mat))
    target = np.sort_complex(closed_loop_poles_target(wcr, zeta, tau, lin))
    assert np.allclose(poles, target, rtol=1e-9), f"{poles} vs {target}"
    xss = np.linalg.solve(a_mat, -b)          # steady state for n_c = 1
    delta = kr * (xss[2] + xss[1])
    n_l = -v * (za * xss[0] + zd * delta)
    assert abs(n_l - 1.0) < 1e-9


def test_pole_solve_reduces_to_zarchans_closed_form_without_pitch_damping(design):
    # Zarchan's published gain formulas (ch. 23) are exact for M_q = 0: the Newton solve started
    # from them must return them (to its tolerance) on the airframe with M_q set to 0.
    _, _, _, _, lin, v, _ = design
    import dataclasses
    lin0 = dataclasses.replace(lin, m_q=0.0, omega_af=math.sqrt(-lin.m_alpha),
                               zeta_af=-lin.z_alpha / (2 * math.sqrt(-lin.m_alpha)))
    g, gz = three_loop_gains(lin0, v, 50.0, 0.7, 0.3), zarchan_gains(lin0, v, 50.0, 0.7, 0.3)
    assert (g.k_a, g.omega_i, g.k_r, g.k_dc) == pytest.approx((gz.k_a, gz.omega_i, gz.k_r, gz.k_dc), rel=1e-7)


def test_undamaged_loop_crossover_and_margins(design):
    _, _, _, _, lin, v, _ = design
    g = three_loop_gains(lin, v, 50.0, 0.7, 0.3)
    no_act = loop_margins(lin, g, v)
    with_act = loop_margins(lin, g, v, (150.0, 0.7))
    # Zarchan's ω_cr is the design parameter of his formulas, not the exact gain crossover: on his
    # own M_q = 0 airframe his closed form gives a crossover of 57.3 rad/s for ω_cr = 50 (measured,
    # test above makes the gains equal). Ours must sit within 2 % of that (M_q is small: −0.88 1/s).
    gz = zarchan_gains(lin, v, 50.0, 0.7, 0.3)
    assert no_act["crossover_radps"] == pytest.approx(loop_margins(lin, gz, v)["crossover_radps"], rel=0.02)
    assert 50.0 < no_act["crossover_radps"] < 60.0
    # classical design requirements (6 dB gain margin, 30° phase margin) with the 150 rad/s actuator
    assert with_act["gain_margin_db"] > 6.0 and with_act["phase_margin_deg"] > 30.0
    # the margins are those of the closed loop's poles: all stable, as loop_matrix says
    assert np.all(np.linalg.eigvals(loop_matrix(lin, g, v, (150.0, 0.7))).real < 0)


def test_roll_gains_place_poles():
    l_p, l_d, w, z = -3.0, -2.0e4, 20.0, 0.7
    k_phi, k_p = roll_gains(l_p, l_d, w, z)
    # ṗ = l_p p + l_d δ, δ = −(k_φ φ + k_p p): characteristic s² + (l_d k_p − l_p) s + l_d k_φ
    poles = np.roots([1.0, l_d * k_p - l_p, l_d * k_phi])
    assert np.allclose(np.sort_complex(poles), np.sort_complex(np.roots([1, 2 * z * w, w * w])), rtol=1e-12)


def test_level_turn_kinematics():
    g, v, n = 9.80665, 272.0, 5.0
    om = turn_rate(v, n, g)
    p0, fwd, ctr = np.array([7000.0, 0, 0]), np.array([1.0, 0, 0]), np.array([0, 0, -1.0])
    h = 1e-4
    for t in (0.2, 1.3, 4.0):  # away from the kink of a(t) at the turn start
        p, vel, acc = level_turn(t + 0.5, p0, fwd, ctr, v, om, 0.5)
        pp = level_turn(t + 0.5 + h, p0, fwd, ctr, v, om, 0.5)[0]
        pm = level_turn(t + 0.5 - h, p0, fwd, ctr, v, om, 0.5)[0]
        # Level turn at load factor n: |a| = g √(n² − 1) horizontal, ⟂ v, speed constant; the
        # closed-form position must differentiate (central differences, error O(h²)) to v and a.
        assert abs(np.linalg.norm(acc) - g * math.sqrt(n * n - 1)) < 1e-9
        assert abs(np.dot(acc, vel)) < 1e-6 and abs(acc[1]) < 1e-12 and abs(np.linalg.norm(vel) - v) < 1e-9
        assert np.allclose((pp - pm) / (2 * h), vel, atol=1e-5)
        assert np.allclose((pp - 2 * p + pm) / (h * h), acc, atol=2e-2)


@pytest.mark.parametrize("reading, k_mom", [(DamageModel.magnitude, 1.4), (DamageModel.toward_instability, 0.6)])
def test_paper_40_percent_wing_damage_readings(reading, k_mom):
    # Paper §VI: lift and side-force slopes −40 %; stability moment "+40 %": ×1.4 in magnitude,
    # or m + 0.4|m| = 0.6 m for the (negative) stable m^α. Geometry untouched.
    af = airframe_of(None)
    dmg = DamageConfig(wing_damage=0.4, model=reading)
    af2, scale = damaged_airframe(af, reading, fin_damage(dmg))
    assert af2 is af and scale == pytest.approx((0.6, k_mom, 1.0))


def test_geometry_damage_removes_panel_lift():
    af = airframe_of(None)
    dmg = DamageConfig(wing_damage=0.4, rudder_effectiveness=0.5)
    af2, scale = damaged_airframe(af, DamageModel.geometry, fin_damage(dmg))
    assert scale == (1.0, 1.0, 1.0)
    assert af2.panel_slope == pytest.approx(af.panel_slope * np.array([0.6] * 4 + [0.5] * 4), rel=1e-15)


def test_unstable_design_airframe_is_an_error():
    from flexnet_fe.errors import FlexnetError
    from flexnet_fe.missile.config import MissileConfig
    from flexnet_fe.missile.build import build_missile

    # CG moved aft of every centre of pressure (3.4 m of 3.66 m): M_α > 0, no three-loop design.
    m = MissileConfig(preset="radar", mass_model="given", mass=231.0, cg=(-3.4, 0.0, 0.0),
                      inertia=((2.5, 0, 0), (0, 216.0, 0), (0, 0, 216.0)))
    af = AF.build_airframe(build_missile(m))
    air = isa(9000.0)
    with pytest.raises(FlexnetError, match="statically unstable"):
        design_autopilot(af, FlightConfig(), air.density, air.speed_of_sound, 9.81)
