"""Rotary net: steady spinning warp (closed form) and the hybrid ODE model (second model)."""

import math

import numpy as np
import pytest

from .hybrid_reference import HybridWarp, initial_state as hybrid_initial_state, simulate
from flexnet_fe.net.state import Environment, initial_state, step_many
from flexnet_fe.net.timestep import spring_limit

NO_LOADS = Environment(gravity=np.zeros(3), rho=0.0, wind=np.zeros(3), air=False)
R0 = 0.1  # hub radius [m]


def warp_model(make_chain, n_seg, seg_len, seg_mass, ea, tip_mass, spin, radii, hub_inertia=1e12,
               tip_speed=None, lag=0.0):
    """One warp on a hub: node 0 = hub centre (1e12 kg, fixed), nodes 1..n_seg along +x at
    ``radii``; the hub link starts on the rim at angle 0. Rigid rotation at ``spin``, the velocity
    being that of the rigid rotation ``lag`` [rad] earlier (the scheme's v at t = -dt/2)."""
    n = n_seg + 1
    x0 = np.zeros((n, 3))
    x0[1:, 0] = radii
    mass = np.full(n, seg_mass)
    mass[0] = 1e12
    mass[-1] = 0.5 * seg_mass + tip_mass
    v0 = np.zeros((n, 3))
    v0[:, 0] = spin * x0[:, 0] * math.sin(lag)
    v0[:, 1] = spin * x0[:, 0] * math.cos(lag)
    if tip_speed is not None:
        v0[-1, 1] = tip_speed
    springs = [[0, 1]] + [[i, i + 1] for i in range(1, n_seg)]
    return make_chain(x0, v0, mass, springs, seg_len, ea, hub_node=0,
                      hub_link=np.array([True] + [False] * (n_seg - 1)), anchor_angle=np.zeros(n_seg),
                      hub_radius=R0, hub_length=1.0, hub_inertia=hub_inertia, hub_spin0=spin)


def test_spinning_warp_tension_profile(make_chain):
    """Steady spin Ω: T(r) = M Ω² R + μ Ω² (R² − r²)/2 (tip mass M at radius R, rope of mass μ per
    length). The warp starts on the rim, stiff (strain ~1e-4) so μ is the unstretched value to
    1e-4; started at the discrete equilibrium, the lumped model must hold it and its tensions
    must follow the closed form."""
    n_seg, h, M, spin = 20, 0.05, 0.01, 10.0
    mu = 1000 * math.pi * 0.004**2 / 4  # rope mass per length [kg/m]
    ea = 16000.0
    K = ea / h
    r = R0 + h * np.arange(1, n_seg + 1)
    for _ in range(50):  # fixed point: segment tension = centripetal load of everything outside it
        m_node = np.full(n_seg, mu * h); m_node[-1] = 0.5 * mu * h + M
        t_seg = np.cumsum((m_node * spin**2 * r)[::-1])[::-1]
        r = R0 + np.cumsum(h + t_seg / K)
    dt = 0.2 * spring_limit(warp_model(make_chain, n_seg, h, mu * h, ea, M, spin, r))
    # symplectic Euler reads the initial velocity as v(-dt/2): start the rotation there, else the
    # Ω dt/2 direction error excites a radial oscillation of ~0.4 % of the stretch
    model = warp_model(make_chain, n_seg, h, mu * h, ea, M, spin, r, lag=spin * dt / 2)
    st = initial_state(model)
    period = 2 * math.pi / spin
    step_many(model, st, NO_LOADS, dt, int(period / dt))
    rad = np.hypot(st.x[1:, 0], st.x[1:, 1])
    R = rad[-1]
    r_in = np.concatenate([[R0], rad[:-1]])
    r_mid = 0.5 * (r_in + rad)
    expected = M * spin**2 * R + mu * spin**2 * (R**2 - r_mid**2) / 2
    # lumped vs continuous mass: half-node masses at the segment ends instead of a uniform μ
    # put the tension at the midpoint off by exactly μ Ω² h²/8 (trapezoid rule on a linear
    # load; 3.9e-4 N here); the stretch (strain <= 1.2e-4) changes μ per current length by as much
    np.testing.assert_allclose(st.tension, expected, rtol=2e-4, atol=mu * spin**2 * h**2 / 8)
    # and the state stayed steady (no breathing): radius of the tip unchanged to 1e-6
    assert R == pytest.approx(r[-1], rel=1e-6)


def lumped_tip(make_chain, warp, hub_spin, tip_speed, dt, t_out):
    model = warp_model(make_chain, 1, warp.rest_length, 0.0, warp.stiffness_ea, warp.tip_mass, hub_spin,
                       np.array([R0 + warp.rest_length]), hub_inertia=warp.hub_inertia, tip_speed=tip_speed)
    # the 1e12 kg hub node is the fixed centre of the hybrid model; no rope mass
    st = initial_state(model)
    tips, spins, wraps = [st.x[1, :2].copy()], [st.hub[1]], [0.0]
    n = int(round((t_out[1] - t_out[0]) / dt))
    for _ in t_out[1:]:
        step_many(model, st, NO_LOADS, dt, n)
        tips.append(st.x[1, :2].copy()); spins.append(st.hub[1]); wraps.append(st.wrap[0])
    return np.array(tips), np.array(spins), np.array(wraps)


def test_hybrid_model_matches_lumped_warp(make_chain):
    """Paper's hybrid model Eq. (13), (16)-(19) (scipy DOP853, rtol 1e-10) vs the lumped-mass
    kernel for one massless warp with a tip mass: the spinning hub pulls the resting tip, the
    warp reaches φ = -π/2, winds onto the hub (wound phase), then goes slack."""
    warp = HybridWarp(n=1, hub_radius=R0, hub_inertia=0.014, tip_mass=0.5, stiffness_ea=50.0, rest_length=1.0)
    t_out = np.linspace(0.0, 0.6, 61)
    hyb = simulate(warp, hybrid_initial_state(warp, 10.0, 0.0, 0.0), 0.6, t_out)
    assert len(hyb["switches"]) == 1 and hyb["wrap"].min() < -1.0  # the wound phase is exercised
    errs = []
    for dt in (1e-4, 5e-5):
        tips, spins, wraps = lumped_tip(make_chain, warp, 10.0, 0.0, dt, t_out)
        errs.append((np.abs(tips - hyb["tip"]).max(), np.abs(spins - hyb["hub_spin"]).max(),
                     np.abs(wraps - hyb["wrap"]).max()))
    (p1, w1, a1), (p2, w2, a2) = errs
    # positions: second order (symplectic Euler) -> < 1e-6 m at dt = 1e-4 s and falling ≥ 3×
    assert p1 < 1e-6 and p2 < p1 / 3
    # hub spin is a half-step velocity and the wrap angle lags one step: first order, O(dt ω̇)
    assert w1 < 3e-3 and w2 == pytest.approx(w1 / 2, rel=0.1)
    assert a1 < 2e-3 and a2 == pytest.approx(a1 / 2, rel=0.1)


@pytest.mark.parametrize("phi_w", [0.3, -1.2, 2.0 * math.pi + 0.5, -7.0])
def test_wrap_geometry_tangent_point(phi_w):
    """A rope wound by ϕ from the anchor β leaves the rim tangentially at γ = β + ϕ:
    p = r0 e(γ) + s · sign(ϕ) e⊥(γ) (closed form). wrap_geometry must recover ϕ (tracked by
    continuity beyond 2π from a previous value 0.01 rad away) and γ."""
    from flexnet_fe.net.hub import wrap_geometry
    beta, s = 0.7, 0.4
    g = beta + phi_w
    sg = math.copysign(1.0, phi_w)
    p = R0 * np.array([math.cos(g), math.sin(g)]) + s * sg * np.array([-math.sin(g), math.cos(g)])
    gamma, w = wrap_geometry(p[0], p[1], beta, R0, phi_w - math.copysign(0.01, phi_w))
    assert w == pytest.approx(phi_w, abs=1e-12) and gamma == pytest.approx(g, abs=1e-12)
    # a node in front of the anchor's tangent line (|φ| < π/2) is not wound, whatever it was
    front = (R0 + s) * np.array([math.cos(beta + 0.1), math.sin(beta + 0.1)])
    assert wrap_geometry(front[0], front[1], beta, R0, 0.0) == (beta, 0.0)
