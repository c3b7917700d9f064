"""Time step and contact stiffness: limits against closed forms; the stiffness never depends on dt."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.collide.timestep import choose_step, contact_limit, contact_stiffness, line_density_min, spring_limit
from flexnet_fe.contact.law import DAMPING_CODE, hysteresis_factor
from flexnet_fe.contact.stiffness import crossed_cylinders_stiffness, hertz_max_penetration, hertz_stiffness


def test_spring_limit_is_two_mass_oscillator():
    # Reference: two masses on a spring, ω² = K (1/m1 + 1/m2); central difference stable for ω dt < 2
    assert spring_limit(np.array([4.0]), np.array([1.0]), np.array([1.0])) == pytest.approx(2 / math.sqrt(8.0))


def test_undamped_contact_limit():
    # Reference: the tangent stiffness of K δ^1.5 at the Hertz penetration, ω² = 1.5 K δ^0.5 / m;
    # with n capsules at a node the stiffness adds up (ω² × n); δ is capped at the layer
    dt, delta = contact_limit(1e9, 1.5, 1e-3, 100.0, 0.0, 1.0)
    assert delta == pytest.approx((5 * 1e-3 * 100.0 ** 2 / (4 * 1e9)) ** 0.4, rel=1e-12)
    assert dt == pytest.approx(2 / math.sqrt(1.5 * 1e9 * delta ** 0.5 / 1e-3), rel=1e-12)
    dt4, _ = contact_limit(1e9, 1.5, 1e-3, 100.0, 0.0, 1.0, n_seg=4)
    assert dt4 == pytest.approx(dt / 2, rel=1e-12)
    _, capped = contact_limit(1e9, 1.5, 1e-3, 100.0, 0.0, 1e-4)
    assert capped == 1e-4


def test_crossed_cylinders_is_eq30_for_equal_radii():
    # Reference: Eq. (30) for two spheres of radius R is 4/3 E* sqrt(R/2); crossed cylinders of equal
    # radii R touch like a sphere of radius R on a plane: 4/3 E* sqrt(R) (Johnson §4.2)
    r, e = 2.25e-3, 1e11
    assert crossed_cylinders_stiffness(r, r, e) == pytest.approx(hertz_stiffness(r, math.inf, e, 0.0, math.inf, 0.0),
                                                                 rel=1e-14)


def test_stiffness_comes_from_the_rope_not_from_dt():
    # The cases' rule: K depends only on the rope radius, its transverse modulus and ν and the parts'
    # radii; dt follows from K (contact limit) — a finer dt does not change K.
    cfg = CollideConfig()
    k_body, k_fin = contact_stiffness(cfg, 2.25e-3, 1e11, 0.3, 3e-3, 0.1015)
    e_star = 1e11 / (1 - 0.09)
    assert k_fin == pytest.approx(4 / 3 * e_star * (2.25e-3 * 3e-3) ** 0.25, rel=1e-14)
    assert k_body == pytest.approx(4 / 3 * e_star * (2.25e-3 * 0.1015) ** 0.25, rel=1e-14)
    st = choose_step(cfg, np.array([300.0]), np.array([1.6e-3]), np.array([1.6e-3]), 1.6e-3, 4, 2.25e-3, 3e-3, k_body)
    chi = hysteresis_factor(DAMPING_CODE[cfg.damping_model], cfg.restitution, 500.0)
    dt_c, delta = contact_limit(k_body, 1.5, 1.6e-3, 500.0, chi, 2.25e-3 + 3e-3, 4)
    assert st.dt_contact == pytest.approx(dt_c, rel=1e-12)
    assert dt_c < contact_limit(k_body, 1.5, 1.6e-3, 500.0, 0.0, 2.25e-3 + 3e-3, 4)[0]  # damping shortens it
    assert st.dt_travel == pytest.approx(0.1 * 2.25e-3 / 500.0, rel=1e-12)
    assert st.dt == min(0.5 * st.dt_contact, 0.5 * st.dt_spring, st.dt_travel)


def test_paper_rope_modulus_is_far_too_soft_for_the_contact():
    # Eq. (30) with E_t = 1 MPa (the paper's axial modulus), crossed rope (r = 2.25 mm) and fin edge
    # (h/2 = 3 mm): K ≈ 7.4e4 N/m^1.5; a 1.6 g rope node at 500 m/s would sink ≈ 0.14 m (Hertz
    # estimate), 25 × the rope radius + half-thickness: the rope passes through a 6 mm fin.
    k = crossed_cylinders_stiffness(2.25e-3, 3e-3, 1e6 / 0.91)
    assert hertz_max_penetration(1.6e-3, 500.0, k, 1.5) > 20 * (2.25e-3 + 3e-3)
    # with the cases' E_t = 100 GPa it stays within the layer (~1 mm)
    k = crossed_cylinders_stiffness(2.25e-3, 3e-3, 1e11 / 0.91)
    assert hertz_max_penetration(1.6e-3, 500.0, k, 1.5) < 0.5 * (2.25e-3 + 3e-3)


def test_line_density_is_the_mass_per_rest_length():
    # Reference: closed form. A chain of three free nodes (masses 1, 2, 1 g) on two segments of
    # rest length 10 mm and 20 mm: the tributary rest lengths are 5, 15, 10 mm, so m/L0 = 0.2, 0.1333,
    # 0.1 kg/m and the smallest is the last node's; a held node is not counted. (The line law's
    # stiffness is per metre of rest length, kernel._line_contact: stretching does not enter.)
    seg = np.array([[0, 1], [1, 2]])
    rest = np.array([0.01, 0.02])
    mass = np.array([1e-3, 2e-3, 1e-3])
    free = np.ones(3, bool)
    assert line_density_min(seg, rest, mass, free) == pytest.approx(0.1, rel=1e-12)
    free[2] = False
    assert line_density_min(seg, rest, mass, free) == pytest.approx(2e-3 / 15e-3, rel=1e-12)
