"""Net–missile impact: conservation laws, segment test, crop, output format (issue 4)."""

from __future__ import annotations

import numpy as np
import pytest

from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.collide.simulate import simulate
from flexnet_fe.errors import NumericalError
from flexnet_fe.rigid import quat_to_matrix


def test_momentum_balance_is_round_off(radar, log, scenes):
    # Reference: Newton's third law. Every contact impulse F dt is applied to the net point and,
    # opposite, to the missile in the same step; rope forces are equal and opposite; held nodes'
    # reactions are accumulated. Gravity off → p_missile + p_net + J_held is constant to round-off.
    net = scenes.flat_net(1.0, 0.05)
    cfg = CollideConfig(net_source="flat_taut", duration=1.5e-3, aim_point=(0.025, 0.025), crop=False)
    res = simulate(net, radar, cfg, 9.81, log)
    s = res.summary
    assert s["dv_over_v"] > 1e-7  # the missile did lose momentum to the net
    # ~4e4 steps × a few ulp of the momentum (|p| ≈ 1.2e5 N s) relative to Δp ≈ 1e-3 |p|
    assert s["momentum_error_rel"] < 1e-8, s["momentum_error_rel"]


@pytest.mark.parametrize("k_n", [2e9])
def test_energy_balance_converges_with_the_step(radar, log, scenes, k_n):
    # Reference: energy conservation, E_kin(missile, net) + rope elastic + contact elastic
    # + dissipated (rope damping, contact damping, friction) = E(0). Symplectic Euler with a
    # force that depends on velocity has an O(dt) energy error: halving dt halves it.
    # The contact stiffness is fixed ("given") so both runs solve the same problem.
    net = scenes.flat_net(0.6, 0.05)
    errs = []
    for frac in (0.2, 0.1):
        cfg = CollideConfig(net_source="flat_taut", duration=1.0e-3, aim_point=(0.025, 0.025), crop=False,
                            stiffness_rule="given", contact_stiffness=k_n, pass_through_fraction=frac)
        res = simulate(net, radar, cfg, 9.81, log)
        errs.append(res.summary["energy_error_rel"])
    assert errs[0] / errs[1] == pytest.approx(2.0, rel=0.35), errs  # first order in dt
    assert errs[1] < 0.05, errs  # 5 % of the energy the missile gave the net at pass_through_fraction 0.1


def _fin_edge_scene(scenes):
    """A 0.1 m square of rope centred 0.3 m above the path: its two x-ropes cross wing_1's plane
    (x = 0) at their midpoints, 5 cm from any node, and no node can touch the missile."""
    net = scenes.flat_net(0.1, 0.1)
    x = np.array(net.x)
    x[:, 1] += 0.3
    return scenes.moved(net, x)


def test_fin_edge_caught_by_segment_test(radar, log, scenes):
    # Reference: geometry. With no detection points between the nodes, only the segment test can
    # see the wing's leading edge cut the ropes; with it the rope is pushed (fin impulse > 0) and
    # nothing tunnels.
    cfg = CollideConfig(net_source="flat_taut", duration=4.5e-3, detection_points_per_segment=0, crop=False)
    res = simulate(_fin_edge_scene(scenes), radar, cfg, 9.81, log)
    s = res.summary
    assert s["fin_impulse_ns"]["wing_1"] > 0.0
    assert sum(v for k, v in s["fin_impulse_ns"].items() if k != "wing_1") == 0.0
    assert not s["tunnelling"]


def test_fin_edge_without_segment_test_reports_tunnelling(radar, log, scenes):
    cfg = CollideConfig(net_source="flat_taut", duration=4.5e-3, detection_points_per_segment=0, crop=False)
    with pytest.raises(NumericalError, match="tunnelling.*wing_1.*segment test off"):
        simulate(_fin_edge_scene(scenes), radar, cfg, 9.81, log, fin_segment_test=False)
    allowed = cfg.model_copy(update={"allow_tunnelling": True})
    res = simulate(_fin_edge_scene(scenes), radar, allowed, 9.81, log, fin_segment_test=False)
    assert res.summary["tunnelling"] and res.summary["segment_crossings_unresolved"] > 0
    assert res.summary["fin_impulse_ns"]["wing_1"] == 0.0  # passed through silently but flagged


def test_fin_loads_carry_the_missile_impulse(radar, log, scenes):
    # Reference: momentum. In the fin-edge scene every contact is on wing_1, so the fin loads of
    # fin_contacts (mean force × interval, body frame) must add up to the missile's momentum change
    # (world frame; the attitude changes by < 1e-5 rad, which bounds the frame-rotation error).
    cfg = CollideConfig(net_source="flat_taut", duration=4.5e-3, detection_points_per_segment=0, crop=False)
    res = simulate(_fin_edge_scene(scenes), radar, cfg, 9.81, log)
    ld = res.loads
    assert ld.row_start[0] == 0 and ld.row_start[-1] == ld.fin.size and np.all(np.diff(ld.row_start) >= 0)
    assert ld.t.size + 1 == ld.row_start.size
    j_b = ld.force.sum(axis=0) * cfg.output_interval
    r0 = quat_to_matrix(res.snap_q[0])
    h = res.history
    dp = radar.mass * np.array([h[f"vel_{c}_mps"][-1] - h[f"vel_{c}_mps"][0] for c in "xyz"])
    assert res.summary["max_attitude_change_rad"] < 1e-5
    np.testing.assert_allclose(r0 @ j_b, dp, rtol=1e-4, atol=1e-6 * np.linalg.norm(dp))
    # contact points lie on wing_1's plate (within its half-thickness of the mid-plane)
    fin = radar.fins[0]
    w = (ld.point - fin.origin) @ fin.n
    assert np.all(np.abs(w) <= 0.5 * fin.thickness + 1e-9)


def test_crop_matches_full_net(radar, log, scenes):
    # Reference: a second model (the full net). Within the simulated time the disturbance cannot
    # reach the held nodes, so the peak acceleration must agree within 1 % (issue 4).
    net = scenes.flat_net(3.0, 0.05)
    cfg = CollideConfig(net_source="flat_taut", duration=2.0e-3, aim_point=(0.025, 0.025),
                        crop_wave_speed_factor=4.0, crop_margin=0.1)
    full = simulate(net, radar, cfg, 9.81, log, crop=False)
    crop = simulate(net, radar, cfg, 9.81, log, crop=True)
    assert crop.summary["free_nodes"] < 0.5 * full.summary["free_nodes"]
    assert crop.summary["crop_boundary_motion_m"] < 1e-6  # the wave never reached the held nodes
    assert crop.summary["peak_accel_mps2"] == pytest.approx(full.summary["peak_accel_mps2"], rel=0.01)


def test_unstable_step_is_caught(radar, log, scenes, monkeypatch):
    # Reference: the central-difference stability limit ω dt < 2 of the contact (timestep.py).
    # A step 3× above the contact limit must stop with a NumericalError naming dt and the limit,
    # never finish with a garbage result (energy-growth guard or non-finite state).
    import dataclasses

    import flexnet_fe.collide.simulate as sim

    real = sim.choose_step

    def too_large(*args, **kw):
        st = real(*args, **kw)
        return dataclasses.replace(st, dt=3.0 * st.dt_contact)

    monkeypatch.setattr(sim, "choose_step", too_large)
    net = scenes.flat_net(0.6, 0.05)
    cfg = CollideConfig(net_source="flat_taut", duration=1.0e-3, aim_point=(0.025, 0.025), crop=False,
                        stiffness_rule="given", contact_stiffness=2e9, pass_through_fraction=1.0)
    with pytest.raises(NumericalError, match="dt = "):
        simulate(net, radar, cfg, 9.81, log)
