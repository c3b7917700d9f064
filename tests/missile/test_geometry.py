"""Fin placement and body profile against the definitions in flexnet_fe.frames / geometry."""

import numpy as np
import pytest

from flexnet_fe.missile.config import MissileConfig, NoseShape
from flexnet_fe.missile.geometry import FinKind, body_profile, nose_radius
from flexnet_fe.missile.build import build_missile


@pytest.mark.parametrize("preset", ["radar", "infrared"])
def test_fins_placed_per_frames(preset):
    cfg = MissileConfig(preset=preset)
    mis = build_missile(cfg)
    assert [f.name for f in mis.fins] == [f"wing_{i}" for i in range(1, 5)] + \
        [f"rudder_{i}" for i in range(1, 5)]
    for fin in mis.fins:
        fs = cfg.wings if fin.kind is FinKind.WING else cfg.rudders
        phi = np.radians(fs.roll_angles_deg[fin.index % 4])
        # roll angle from +y_b towards +z_b (flexnet_fe.frames): e1 = (0, cos φ, sin φ)
        np.testing.assert_allclose(fin.e1, [0, np.cos(phi), np.sin(phi)], atol=1e-15)
        np.testing.assert_allclose(fin.e2, [-1, 0, 0])
        axes = np.stack([fin.e1, fin.e2, fin.n])
        np.testing.assert_allclose(axes @ axes.T, np.eye(3), atol=1e-15)
        assert np.linalg.det(axes) > 0
        # root chord on the body surface (r = R) from station s_LE to s_LE + c_r
        root_te, root_le, tip_le, tip_te = fin.corners
        np.testing.assert_allclose(np.hypot(root_le[1], root_le[2]), mis.radius, rtol=1e-15)
        np.testing.assert_allclose(np.hypot(root_te[1], root_te[2]), mis.radius, rtol=1e-15)
        np.testing.assert_allclose([-root_le[0], -root_te[0]],
                                   [fs.root_le_station, fs.root_le_station + fs.root_chord])
        # tip at r = R + b, its leading edge swept back by b tan Λ, tip chord c_t
        np.testing.assert_allclose(np.hypot(tip_le[1], tip_le[2]), mis.radius + fs.span)
        np.testing.assert_allclose(-tip_le[0], fs.root_le_station
                                   + fs.span * np.tan(np.radians(fs.leading_edge_sweep_deg)))
        np.testing.assert_allclose(tip_le[0] - tip_te[0], fs.tip_chord)
        np.testing.assert_allclose(fin.area, 0.5 * (fs.root_chord + fs.tip_chord) * fs.span)


@pytest.mark.parametrize("shape,ln", [(NoseShape.CONE, 0.4), (NoseShape.TANGENT_OGIVE, 0.6),
                                      (NoseShape.TANGENT_OGIVE, 0.1), (NoseShape.HEMISPHERE, 0.1)])
def test_nose_profile_ends_and_tangency(shape, ln):
    R = 0.1
    s = np.array([0.0, ln])
    # the nose starts at the apex (r = 0) and meets the cylinder (r = R)
    np.testing.assert_allclose(nose_radius(s, R, shape, ln), [0.0, R], atol=1e-15)
    if shape is not NoseShape.CONE:
        # tangent ogive / hemisphere: dr/ds = 0 where the nose meets the cylinder (tangency)
        eps = 1e-7
        slope = (nose_radius(ln, R, shape, ln) - nose_radius(ln - eps, R, shape, ln)) / eps
        assert abs(slope) < 1e-5  # one-sided difference: O(eps * curvature)
    prof = body_profile(3.0, R, shape, ln)
    assert [p.part for p in prof] == [1, 0, 0]
