"""Sampling a fin's normal displacement for the collision kernel (``study.fin_motion``): the grid, the
interpolation, the time resampling and the sampler, against closed forms."""

from __future__ import annotations

import numpy as np

from flexnet_fe.missile.build import build_missile
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.missile.shapes import pack_shapes
from flexnet_fe.shell.forms import NDOF_NODE
from flexnet_fe.study.fin_motion import _Sampler, grid_of, grid_points, interpolation, resample


def test_the_grid_covers_every_fins_contact_polygon():
    # Reference: the contact polygons of the radar missile (root extension included,
    # missile.shapes.pack_shapes): every corner lies within the grid, and the grid's extreme points
    # are the polygon's bounding box (to round-off).
    for poly in pack_shapes(build_missile(MissileConfig(preset="radar"))).fin_poly:
        g = grid_of(poly, 41, 31)
        pts = grid_points(g, 41, 31)
        assert pts.shape == (41 * 31, 2)
        np.testing.assert_allclose(pts.min(axis=0), poly.min(axis=0), atol=1e-15)
        np.testing.assert_allclose(pts.max(axis=0), poly.max(axis=0), atol=1e-12)
        assert np.all(poly >= pts.min(axis=0) - 1e-15) and np.all(poly <= pts.max(axis=0) + 1e-12)
        np.testing.assert_array_equal(pts[1 * 31 + 2], [g[0] + g[1], g[2] + 2 * g[3]])  # row i·nv + j


def test_interpolation_is_exact_for_a_linear_field_and_nearest_outside():
    # Reference: a linear field a + b u + c v is reproduced exactly (round-off) by linear
    # interpolation on any triangulation of its nodes; a point outside the nodes' hull takes its
    # nearest node's value.
    rng = np.random.default_rng(3)
    nodes = rng.uniform(0.0, 1.0, (400, 2))
    nodes[:4] = [[0, 0], [1, 0], [0, 1], [1, 1]]
    f = 0.3 + 2.0 * nodes[:, 0] - 1.5 * nodes[:, 1]
    pts = np.vstack([rng.uniform(0.0, 1.0, (50, 2)), [[1.5, 0.5], [-0.2, -0.3]]])
    P = interpolation(nodes, pts)
    vals = P @ f
    np.testing.assert_allclose(vals[:50], 0.3 + 2.0 * pts[:50, 0] - 1.5 * pts[:50, 1], atol=1e-13)
    for k, p in ((50, pts[50]), (51, pts[51])):
        assert vals[k] == f[np.argmin(np.linalg.norm(nodes - p, axis=1))]


def test_resample_is_linear_in_time_onto_the_regular_grid():
    # Reference: a field linear in time, sampled at irregular times, is reproduced at the regular
    # times t0 + j dt up to the last sample.
    t = np.array([1.0e-3, 1.0007e-3, 1.0021e-3, 1.0030e-3, 1.00305e-3, 1.0042e-3])
    w = np.outer(t - 1e-3, [1.0, -2.0])
    out = resample(t, w, t[0], 1e-6)
    tj = 1e-3 + 1e-6 * np.arange(5)  # up to 1.004e-3 ≤ t[-1]
    assert out.shape == (5, 2)
    np.testing.assert_allclose(out, np.outer(tj - 1e-3, [1.0, -2.0]), atol=1e-18)


def test_the_sampler_takes_the_normal_component_and_skips_a_repeated_instant():
    # Reference: closed form. Nodes with displacement (1, 2, 3) mm × k and normal (0, 0.6, 0.8)
    # have u·n = 3.6 mm × k; a frame at a time already taken (a running peak's) is not kept.
    n = 3
    u = np.zeros(n * NDOF_NODE)
    u.reshape(-1, NDOF_NODE)[:, :3] = np.outer(np.arange(1, n + 1), [1e-3, 2e-3, 3e-3])
    s = _Sampler(interpolation(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), np.array([[0.0, 0.0], [0.0, 1.0]])),
                 np.array([0.0, 0.6, 0.8]))
    s.write(1e-6, u)
    s.write(1e-6, 2 * u)
    s.write(2e-6, 2 * u)
    assert s.t == [1e-6, 2e-6]
    np.testing.assert_allclose(s.w[0], [3.6e-3, 3 * 3.6e-3], rtol=1e-14)
    np.testing.assert_allclose(s.w[1], [7.2e-3, 6 * 3.6e-3], rtol=1e-14)
