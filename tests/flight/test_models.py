"""Atmosphere, airframe trim, autopilot pole placement, target turn, damage multipliers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexnet_fe.atmosphere import isa
from flexnet_fe.flight import aero as A
from flexnet_fe.flight.autopilot import (
    closed_loop_poles_target, linearize, plane_derivatives, roll_gains, three_loop_gains)
from flexnet_fe.flight.config import AirframeConfig, DamageConfig, StabilityDamage
from flexnet_fe.flight.stage import damage_multipliers
from flexnet_fe.flight.target import level_turn, turn_rate


def test_isa_at_8km_geometric():
    air = isa(8000.0)
    # ISO 2533 / U.S. Standard Atmosphere 1976 table at 8000 m geometric: ρ = 0.52579 kg/m³,
    # a = 308.105 m/s (table values given to 5–6 digits: tolerance half a unit in the last digit).
    assert abs(air.density - 0.52579) < 0.5e-5
    assert abs(air.speed_of_sound - 308.105) < 0.5e-3


@pytest.fixture(scope="module")
def design():
    af = AirframeConfig()
    a = A.aero_coefficients(af)
    air = isa(9000.0)
    v = 1000.0
    beta_m = A.supersonic_beta(v / air.speed_of_sound)
    qbar = 0.5 * air.density * v * v
    cn_trim = af.mass * 9.81 * 10.0 / (qbar * a[A.SREF])
    der = plane_derivatives(a, beta_m, cn_trim)
    lin = linearize(der, qbar, v, af.mass, A.inertia_diagonal(af)[1], a[A.SREF], a[A.DREF])
    return af, a, beta_m, cn_trim, der, lin, v


def test_trim_point_balances_moment(design):
    _, a, beta_m, cn_trim, der, _, _ = design
    # Trim from Zarchan's quadratic must make the full nonlinear law (plane_coefficients) give
    # C_M = 0 and C_N = C_N,trim at (α_tr, δ_tr = −C_M,α-part/C_M,δ).
    alpha = der.alpha_trim
    _, cm_no_delta = A.plane_coefficients(alpha, abs(alpha), 0.0, beta_m, a, 1.0, 1.0, 1.0)
    _, cm_unit = A.plane_coefficients(0.0, 0.0, 1.0, beta_m, a, 1.0, 1.0, 1.0)
    delta = -cm_no_delta / cm_unit
    cn, cm = A.plane_coefficients(alpha, abs(alpha), delta, beta_m, a, 1.0, 1.0, 1.0)
    assert abs(cm) < 1e-12 * max(1.0, abs(cm_no_delta))
    assert abs(cn - cn_trim) < 1e-10 * cn_trim


def test_three_loop_gains_place_the_designed_poles(design):
    _, _, _, _, _, lin, v = design
    wcr, zeta, tau = 50.0, 0.7, 0.3
    g = three_loop_gains(lin, v, wcr, zeta, tau)
    # Independent model: the physical short-period equations (not Zarchan's transfer functions)
    #   α̇ = q + Z_α α + Z_δ δ,  q̇ = M_α α + M_δ δ,  n_L = −V (Z_α α + Z_δ δ),
    #   ẋ = ω_I (q + K_A (n_L − K_DC n_c)),  δ = K_R (x + q)    (no actuator, as in the design).
    # Its closed-loop poles must be the design's: −1/τ and ω(−ζ ± i√(1−ζ²)); DC gain n_L/n_c = 1.
    za, zd, ma, md = lin.z_alpha, lin.z_delta, lin.m_alpha, lin.m_delta
    kr, wi, ka, kdc = g.k_r, g.omega_i, g.k_a, g.k_dc
    # state (α, q, x); δ = kr x + kr q
    a_mat = np.array([
        [za, 1 + zd * kr, zd * kr],
        [ma, md * kr, md * kr],
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


@pytest.mark.parametrize("reading, k_mom", [(StabilityDamage.magnitude, 1.4), (StabilityDamage.toward_instability, 0.6)])
def test_paper_40_percent_wing_damage_readings(reading, k_mom):
    # Paper §VI: lift and side-force slopes −40 %; stability moment "+40 %": ×1.4 in magnitude,
    # or m + 0.4|m| = 0.6 m for the (negative) stable m^α.
    k_lift, km, k_ctrl = damage_multipliers(DamageConfig(wing_damage=0.4, stability=reading))
    assert (k_lift, k_ctrl) == (pytest.approx(0.6), 1.0) and km == pytest.approx(k_mom)


def test_unstable_design_airframe_is_a_case_error():
    from flexnet_fe.errors import CaseError
    from flexnet_fe.flight.config import FlightConfig
    from flexnet_fe.flight.stage import simulate_flight

    # CG moved aft of every centre of pressure (x_cg = 5.9 m of 6.1 m): M_α > 0, no three-loop design.
    with pytest.raises(CaseError, match="statically unstable"):
        simulate_flight(FlightConfig(airframe=AirframeConfig(x_cg=5.9)), 8000.0)
