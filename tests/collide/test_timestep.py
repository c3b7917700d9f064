"""Time step, contact stiffness rules and the Eq. (31) softness check."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.collide.simulate import simulate
from flexnet_fe.collide.timestep import choose_step, contact_limit, spring_limit
from flexnet_fe.contact.stiffness import hertz_max_penetration, rigid_target_stiffness
from flexnet_fe.errors import NumericalError


def test_spring_limit_is_two_mass_oscillator():
    # Reference: two masses on a spring, ω² = K (1/m1 + 1/m2); central difference stable for ω dt < 2
    assert spring_limit(np.array([4.0]), np.array([1.0]), np.array([1.0])) == pytest.approx(2 / math.sqrt(8.0))


def test_undamped_contact_limit():
    # Reference: the tangent stiffness of K δ^1.5 at the Hertz penetration, ω² = 1.5 K δ^0.5 / m
    dt, delta = contact_limit(1e9, 1.5, 1e-3, 100.0, 0.0)
    assert delta == pytest.approx((5 * 1e-3 * 100.0 ** 2 / (4 * 1e9)) ** 0.4, rel=1e-12)
    assert dt == pytest.approx(2 / math.sqrt(1.5 * 1e9 * delta ** 0.5 / 1e-3), rel=1e-12)


def test_penalty_keeps_penetration_a_fraction_of_the_rope_radius():
    # The penalty rule k = s m/dt² with dt from the no-pass-through limit gives (undamped Hertz
    # estimate) δ = ((m+1)/(2s))^(1/(m+1)) (f r)^(2/(m+1)) (δ_ref)^((m−1)/(m+1)); with s = 0.1,
    # f = 0.1, δ_ref = 0.1 r: δ ≈ 0.275 r, independent of mass and speed.
    cfg = CollideConfig()
    r = 2.25e-3
    for mass, v in ((1e-3, 500.0), (0.5, 200.0)):
        cfg_v = cfg.model_copy(update={"impact_speed": v})
        st = choose_step(cfg_v, np.array([1.0]), np.array([mass]), np.array([mass]), mass, r, 1e6, 3e-3)
        assert st.governed_by == "no-pass-through"
        assert st.dt == pytest.approx(0.1 * r / v, rel=1e-12)
        assert st.expected_penetration / r == pytest.approx((1.25 / 0.1) ** 0.4 * 0.1, rel=1e-9)
        assert st.dt_contact > st.dt  # the contact itself is resolved by the step


def test_eq31_is_far_too_soft_for_the_paper_rope():
    # Eq. (31) with E = 1 MPa, ν = 0.3, R = 2.25 mm: K ≈ 4.9e4 N/m^1.5. A 1.2 g rope node at
    # 500 m/s then sinks ~0.1 m (Hertz estimate) — 40 rope radii, 30 fin thicknesses.
    k = rigid_target_stiffness(2.25e-3, 1e6, 0.3)
    assert k == pytest.approx(4 / 3 * math.sqrt(2.25e-3 / 2) * 1e6 / 0.91, rel=1e-12)
    assert hertz_max_penetration(1.2e-3, 500.0, k, 1.5) > 0.05


def test_eq31_stiffness_tunnels_in_the_impact(radar, log, scenes):
    net = scenes.flat_net(0.6, 0.05)
    cfg = CollideConfig(net_source="flat_taut", duration=1e-3, aim_point=(0.025, 0.025), crop=False,
                        stiffness_rule="hertz_eq31")
    with pytest.raises(NumericalError, match="tunnelling"):
        simulate(net, radar, cfg, 9.81, log)

