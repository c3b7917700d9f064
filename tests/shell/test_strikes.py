"""The strike envelope's move of a fin's loads along its leading edge (flexnet_fe/shell/strikes.py),
against closed forms on a swept trapezoid."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexnet_fe.shell.strikes import move_along_leading_edge, planform

# radar rudder_2's planform (root at the body radius 0.1015 m, 35° sweep, chords 0.4 / 0.18 m)
TAN = math.tan(math.radians(35.0))
CORNERS = np.array([[-3.64, 0.0, 0.1015], [-3.24, 0.0, 0.1015],
                    [-3.24 - 0.3035 * TAN, 0.0, 0.405], [-3.24 - 0.3035 * TAN + (-0.18), 0.0, 0.405]])
RISE = 0.22 - 0.3035 * TAN
"""[m] how far forward the trailing edge lies at the tip than at the root"""


def le_point(s):
    """The leading edge at span s [m] (closed form)."""
    return np.array([-3.24 - s * TAN, 0.0, 0.1015 + s])


def test_a_point_on_the_leading_edge_moves_along_it_by_the_span_offset():
    pf = planform(CORNERS)
    assert pf.span == pytest.approx(0.3035, abs=1e-12)
    for s0, off in [(0.0015, 0.00225), (0.0065, -0.0045), (0.15, 0.0045)]:
        moved = move_along_leading_edge(le_point(s0)[None], pf, off)[0]
        np.testing.assert_allclose(moved, le_point(s0 + off), atol=1e-12)


def test_points_stay_on_the_planform_and_keep_their_offset_from_its_plane():
    pf = planform(CORNERS)
    # below the root after the move: clipped to it (on the leading edge: the root corner)
    np.testing.assert_allclose(move_along_leading_edge(le_point(0.0015)[None], pf, -0.0045)[0], CORNERS[1],
                               atol=1e-12)
    # beyond the tip: clipped to the tip corner
    np.testing.assert_allclose(move_along_leading_edge(le_point(0.30)[None], pf, 0.01)[0], CORNERS[2],
                               atol=1e-12)
    # a point on the trailing edge 1 mm above the root, 2 mm off the plane (the fin's surface), moved out: the
    # trailing edge there lies at x = -3.64 + RISE s / 0.3035 (closed form), so it is kept on it
    p = np.array([-3.64 + RISE * 0.001 / 0.3035, 0.002, 0.1015 + 0.001])
    m = move_along_leading_edge(p[None], pf, 0.004)[0]
    assert m[1] == 0.002 and m[2] == pytest.approx(0.1065, abs=1e-12)
    assert m[0] == pytest.approx(-3.64 + RISE * 0.005 / 0.3035, abs=1e-12)
    # many random points on the planform stay on it under any move
    rng = np.random.default_rng(1)
    s = rng.uniform(0, 0.3035, 500)
    x = -3.64 + RISE * s / 0.3035 + rng.uniform(0, 1, 500) * (0.4 - 0.22 * s / 0.3035)
    pts = np.column_stack([x, np.zeros(500), 0.1015 + s])
    for off in (-0.0045, 0.00225, 0.05):
        m = move_along_leading_edge(pts, pf, off)
        sm = m[:, 2] - 0.1015
        assert np.all((sm >= -1e-12) & (sm <= 0.3035 + 1e-12))
        assert np.all(m[:, 0] <= -3.24 - sm * TAN + 1e-12) and np.all(m[:, 0] >= -3.64 + RISE * sm / 0.3035 - 1e-12)


def test_a_point_on_the_rounded_edges_keeps_its_place_on_them():
    # the collision's contact points lie on the rounded plate: up to t/2 ahead of the leading edge
    # line (in u: t / (2 cos 35°)) and beyond the tip line; a rigid move keeps them there
    pf = planform(CORNERS)
    ahead = le_point(0.05) + np.array([0.0024, 0.0, 0.0])
    np.testing.assert_allclose(move_along_leading_edge(ahead[None], pf, 0.0045)[0],
                               le_point(0.0545) + np.array([0.0024, 0.0, 0.0]), atol=1e-12)
    beyond = le_point(0.3035) + np.array([-0.05, 0.0, 0.0015])  # 1.5 mm beyond the tip line
    np.testing.assert_allclose(move_along_leading_edge(beyond[None], pf, 0.0045)[0], beyond, atol=1e-12)
    np.testing.assert_allclose(move_along_leading_edge(beyond[None], pf, -0.0045)[0],
                               beyond + np.array([0.0045 * TAN, 0.0, -0.0045]), atol=1e-12)
