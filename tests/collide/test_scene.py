"""Scene set-up against the frame conventions (flexnet_fe.frames) and the crop geometry."""

from __future__ import annotations

import numpy as np
import pytest

from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.collide.crop import active_segments, boundary_nodes, free_nodes
from flexnet_fe.collide.scene import missile_attitude, place_missile


def test_attitude_follows_the_frames():
    # frames.py: the missile flies along world +z with x_b forward; y_b = world +y before roll
    r = missile_attitude(0.0, 0.0)
    np.testing.assert_allclose(r @ [1, 0, 0], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(r @ [0, 1, 0], [0, 1, 0], atol=1e-15)
    assert np.linalg.det(r) == pytest.approx(1.0, abs=1e-14)
    # incidence i pitches the path about world x: d = (0, −sin i, cos i); roll keeps the axis
    r = missile_attitude(0.3, 0.7)
    np.testing.assert_allclose(r @ [1, 0, 0], [0, -np.sin(0.3), np.cos(0.3)], atol=1e-15)
    np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-14)


def test_missile_starts_standoff_before_the_net(radar, scenes):
    net = scenes.flat_net(1.0, 0.05)
    cfg = CollideConfig(net_source="flat_taut", standoff=0.03, aim_point=(0.1, -0.2))
    st = place_missile(radar, net.x, cfg)
    np.testing.assert_allclose(st.apex, [0.1, -0.2, -0.03], atol=1e-12)  # flat net at z = 0
    np.testing.assert_allclose(st.v_cg, [0, 0, 500.0], atol=1e-12)


def test_crop_sets():
    x = np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0], [3.0, 0, 0]])
    springs = np.array([[0, 1], [1, 2], [2, 3]])
    free = free_nodes(x, np.zeros(3), np.array([0.0, 0.0, 1.0]), 1.5)
    np.testing.assert_array_equal(free, [True, True, False, False])
    np.testing.assert_array_equal(active_segments(springs, free), [0, 1])
    np.testing.assert_array_equal(boundary_nodes(springs, free), [1])
