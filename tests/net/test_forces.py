"""Force laws at their special points (paper Eq. (1)–(10))."""

import math

import numpy as np
import pytest

from flexnet_fe.net.forces import aero_coefficients, rope_tension, segment_aero_force, spring_force
from flexnet_fe.net.kernels import DeployModel, DeployState, net_forces, spring_blocks

K, C, L0 = 200.0, 3.0, 0.05


def production_forces(x, v, springs, rest, k, c, diameter, air=False, wind=(0.0, 0.0, 0.0), rho=1.0):
    """Forces of the production deploy kernel (``net.kernels.net_forces``) with gravity off and
    no hub: f (n, 3) [N], tension (m,) [N]."""
    n, m = len(x), len(springs)
    f, t = np.zeros((n, 3)), np.zeros(m)
    springs = np.asarray(springs, np.uint32)
    model = DeployModel(springs, np.full(m, rest), np.full(m, k), np.full(m, c), np.zeros(m),
                        np.full(m, diameter), np.zeros(m, np.bool_), np.zeros(0, np.int64), np.zeros(m), np.ones(n),
                        -1, 0.1, 0.01, 1.0, np.zeros(3),
                        float(rho), np.asarray(wind, float), air, spring_blocks(springs, np.zeros(m, np.bool_)))
    state = DeployState(np.asarray(x, float), np.asarray(v, float), np.zeros(2), np.zeros(m), t, np.zeros(2))
    net_forces(model, state, f, np.zeros(n))
    return f, t


def test_spring_force_mapper_hand_values():
    # the shared mapper (deploy and collide kernels): 3-4-5 triangle, taut, stretching at 2 m/s
    t, u0, u1, u2, lf, ldot, stretch = spring_force((0.03, 0.04, 0.0), (0.6, 0.8, 0.0), 0.0, (0.04, K, C, 0.0))
    assert (u0, u1, u2) == pytest.approx((0.6, 0.8, 0.0), abs=1e-15)
    assert lf == pytest.approx(0.05, rel=1e-15) and ldot == pytest.approx(1.0, rel=1e-15)
    assert stretch == pytest.approx(0.01, rel=1e-12) and t == pytest.approx(K * 0.01 + C * 1.0, rel=1e-12)
    # wrapped length (hub link): the extra length counts in the stretch, not in the direction
    t2, *_ = spring_force((0.03, 0.04, 0.0), (0.0, 0.0, 0.0), 0.005, (0.05, K, 0.0, 0.0))
    assert t2 == pytest.approx(K * 0.005, rel=1e-12)


def test_tension_taut_slack_and_offset():
    # Eq. (2): T = K (l - l0) + c l̇ while taut — exact arithmetic, so tolerance = round-off
    assert rope_tension(0.06, L0, K, C, 0.0, 0.5) == pytest.approx(K * 0.01 + C * 0.5, rel=1e-14)
    # slack (l <= l0): zero force AND zero damping, whatever the rate
    assert rope_tension(0.049, L0, K, C, 0.0, 10.0) == 0.0
    assert rope_tension(0.049, L0, K, C, 0.0, -10.0) == 0.0
    assert rope_tension(L0, L0, K, C, 0.0, 10.0) == 0.0
    # LINK167 offset > 0 (pretension): taut from l0 - offset, T = K (l - l0 + offset)
    assert rope_tension(L0, L0, K, 0.0, 0.01, 0.0) == pytest.approx(K * 0.01, rel=1e-14)
    # offset < 0 (slack rope): no force until l exceeds l0 + |offset|
    assert rope_tension(0.055, L0, K, C, -0.01, 1.0) == 0.0
    assert rope_tension(0.065, L0, K, 0.0, -0.01, 0.0) == pytest.approx(K * 0.005, rel=1e-12)


def test_tension_never_pushes():
    # taut but shortening fast: K·stretch + c·l̇ < 0 -> a rope cannot push, T = 0
    assert K * 0.001 + C * (-1.0) < 0
    assert rope_tension(L0 + 0.001, L0, K, C, 0.0, -1.0) == 0.0


def test_spring_forces_action_reaction_and_direction():
    x = np.array([[0.0, 0, 0], [0.0, 0.06, 0], [0.0, 0.0, 0.04]])
    v = np.zeros((3, 3))
    springs = np.array([[0, 1], [0, 2]], dtype=np.int64)
    f, t = production_forces(x, v, springs, L0, K, 0.0, 4e-3)
    # spring 0 taut (0.06 > 0.05): pulls node 0 towards +y, node 1 towards -y; spring 1 slack
    assert t[0] == pytest.approx(K * 0.01) and t[1] == 0.0
    np.testing.assert_allclose(f[0], [0, K * 0.01, 0], atol=1e-12)
    np.testing.assert_allclose(f[1], [0, -K * 0.01, 0], atol=1e-12)
    np.testing.assert_allclose(f.sum(axis=0), 0.0, atol=1e-12)  # Newton's third law


def test_aero_coefficients_special_points():
    # Eq. (7)-(8) evaluated by hand
    cd0, cl0 = aero_coefficients(0.0)
    assert cd0 == pytest.approx(0.022, abs=1e-15) and cl0 == 0.0
    cd90, cl90 = aero_coefficients(1.0)
    assert cd90 == pytest.approx(1.122, abs=1e-15) and cl90 == pytest.approx(0.0, abs=1e-15)
    # max C_L: d/dα (sin²α cos α) = 0 -> tan²α = 2, α* = atan(√2) = 54.7356°,
    # C_L* = 1.1 · (2/3) · (1/√3) = 0.42339
    a_star = math.atan(math.sqrt(2.0))
    assert math.degrees(a_star) == pytest.approx(54.7356, abs=1e-4)
    assert aero_coefficients(math.sin(a_star))[1] == pytest.approx(0.4234, abs=5e-5)
    alphas = np.linspace(0, np.pi / 2, 20001)  # grid step 0.0045° -> C_L within 1e-8 of its max
    cl = np.array([aero_coefficients(math.sin(a))[1] for a in alphas])
    assert math.degrees(alphas[np.argmax(cl)]) == pytest.approx(54.7356, abs=0.005)


@pytest.mark.parametrize("alpha_deg", [0.0, 20.0, 54.7356, 90.0])
def test_segment_force_is_drag_plus_lift(alpha_deg):
    """Independent evaluation of Eq. (5)-(8) (with |v|², see forces.py): drag along -v̂ with C_D,
    lift ⟂ v̂ in the (v, segment) plane, away from the cross-flow, with C_L."""
    rho, d, l, vmag = 0.5258, 4e-3, 0.07, 900.0
    a = math.radians(alpha_deg)
    e = np.array([math.cos(a), math.sin(a), 0.0])       # segment axis
    v = np.array([vmag, 0.0, 0.0])                       # relative velocity along +x
    out = np.array(segment_aero_force((e[0], e[1], e[2]), l, (v[0], v[1], v[2]), rho, d)[:3])
    cd, cl = aero_coefficients(math.sin(a))
    q = 0.5 * rho * d * l * vmag**2
    vn = v - (v @ e) * e                                  # cross-flow velocity (along -y or 0)
    # lift direction: perpendicular to v, in the plane, opposite to the cross-flow's ⟂ part
    e_lift = -np.sign(vn[1]) * np.array([0.0, 1.0, 0.0]) if abs(vn[1]) > 0 else np.zeros(3)
    expected = -q * cd * v / vmag + q * cl * e_lift
    np.testing.assert_allclose(out, expected, rtol=1e-12, atol=1e-12 * q)


def test_aero_split_half_to_each_end_and_no_wind_no_force():
    x = np.array([[0.0, 0, 0], [0.05, 0, 0]])
    springs = np.array([[0, 1]], dtype=np.int64)
    v = np.array([[0.0, 0, 100.0], [0.0, 0, 100.0]])
    f, _ = production_forces(x, v, springs, 1.0, K, 0.0, 4e-3, air=True)  # rest 1 m: slack, aero only
    # broadside (α = 90°): F = ½ ρ 1.122 d l |v|², Eq. (9)-(10): half to each node
    total = 0.5 * 1.0 * 1.122 * 4e-3 * 0.05 * 100.0**2
    np.testing.assert_allclose(f[:, 2], [-total / 2, -total / 2], rtol=1e-13)
    f, _ = production_forces(x, v, springs, 1.0, K, 0.0, 4e-3, air=True, wind=(0.0, 0.0, 100.0))
    assert np.all(f == 0.0)  # moving with the wind: no load
