"""Rounded tip corners of the fin planform (missile.planform) and the rope contact against them
(missile.shapes.segment_core_closest on ShapeArrays.fin_core)."""

import numpy as np
import pytest
from pydantic import ValidationError

from flexnet_fe.missile.build import build_missile
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.missile.planform import (ARC_SEGMENTS, TIP_CORNERS, round_tip_corners, tip_corner_room,
                                         trapezoid)
from flexnet_fe.missile.shapes import pack_shapes, segment_core_closest

R = 0.01  # [m]
SETS = {"wings": (0.4085, 0.80, 0.20, 55.0), "rudders": (0.3035, 0.40, 0.18, 35.0)}  # the presets'


def _inward_offset_intersection(p, k, r):
    """Reference centre of corner k's arc: the point at distance r inside both edge lines, by a
    2 × 2 solve of n_i · x = n_i · p_i − r (n_i the edges' outward normals) — not the code's
    bisector construction."""
    n = len(p)
    rows, rhs = [], []
    for a, b in ((p[k - 1], p[k]), (p[k], p[(k + 1) % n])):
        t = b - a
        nrm = np.array([t[1], -t[0]]) / np.linalg.norm(t)  # outward for a counter-clockwise polygon
        rows.append(nrm)
        rhs.append(nrm @ a - r)
    return np.linalg.solve(np.array(rows), np.array(rhs))


@pytest.mark.parametrize("name", SETS)
def test_rounded_core_geometry(name):
    # References: the arc's centre from the offset lines; the area of a rounded corner in closed
    # form: the corner loses r² (cot(θ/2) − (π − θ)/2), and the inscribed chords a further
    # m · r²/2 (α − sin α), α = (π − θ)/m (circular segments).
    p = trapezoid(*SETS[name])
    q = round_tip_corners(p, R)
    assert q.shape == (4 + 2 * ARC_SEGMENTS, 2)
    nq = len(q)
    cross = [np.cross(q[(i + 1) % nq] - q[i], q[(i + 2) % nq] - q[(i + 1) % nq]) for i in range(nq)]
    assert min(cross) > 0.0  # convex, counter-clockwise, no repeated or collinear vertex
    area = lambda v: 0.5 * np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1])  # noqa: E731
    loss = 0.0
    for j, k in enumerate(TIP_CORNERS):
        arc = q[k + j * ARC_SEGMENTS: k + j * ARC_SEGMENTS + ARC_SEGMENTS + 1]
        centre = _inward_offset_intersection(p, k, R)
        np.testing.assert_allclose(np.linalg.norm(arc - centre, axis=1), R, rtol=1e-12)
        d1, d2 = p[k - 1] - p[k], p[(k + 1) % 4] - p[k]
        theta = np.arccos(d1 @ d2 / np.linalg.norm(d1) / np.linalg.norm(d2))
        alpha = (np.pi - theta) / ARC_SEGMENTS
        loss += R * R * (1.0 / np.tan(theta / 2) - (np.pi - theta) / 2) + ARC_SEGMENTS * R * R / 2 * (alpha - np.sin(alpha))
        # the arc's ends are the tangent points on the two edges
        for end, d in ((arc[0], d1), (arc[-1], d2)):
            assert abs(np.cross(d, end - p[k])) < 1e-15
    assert area(q) == pytest.approx(area(p) - loss, rel=1e-12)
    assert np.array_equal(round_tip_corners(p, 0.0), p)


def test_room_and_refusal():
    # Reference: with the largest radius the tangent points of one edge meet (or reach its end).
    for name, args in SETS.items():
        room = tip_corner_room(*args)
        q = round_tip_corners(trapezoid(*args), room)
        gaps = np.linalg.norm(np.diff(q, axis=0), axis=1)
        assert gaps.min() < 1e-9 * room  # two vertices meet: no room left
        MissileConfig(preset="radar", **{name: {"tip_corner_radius": 0.99 * room}})
        with pytest.raises(ValidationError, match="tip_corner_radius"):
            MissileConfig(preset="radar", **{name: {"tip_corner_radius": 1.01 * room}})


@pytest.fixture(scope="module")
def rounded():
    """The radar preset with R-rounded wing tips: (missile, shapes, wing_1, its index, its core,
    the reference centre of its tip leading-edge arc)."""
    mis = build_missile(MissileConfig(preset="radar", wings={"tip_corner_radius": R}))
    sh = pack_shapes(mis)
    fin = mis.fin("wing_1")
    core = sh.fin_core[fin.index, :sh.fin_ncore[fin.index]]
    return mis, sh, fin, fin.index, core, _inward_offset_intersection(np.asarray(fin.uv), TIP_CORNERS[0], R)


def test_capsule_distance_round_the_corner(rounded):
    # Reference: the distance from a point at height w over the fin plane, whose projection lies
    # outside the corner's arc, to a planar disk-rounded corner is sqrt((|ρ − c| − R)² + w²),
    # c the arc's centre (offset-line reference above); the chords lie inside the arc by at most
    # the sagitta R (1 − cos(α/2)), which bounds the difference.
    mis, sh, fin, i, core, centre = rounded
    k = TIP_CORNERS[0]
    d1, d2 = fin.uv[k - 1] - fin.uv[k], fin.uv[k + 1] - fin.uv[k]
    theta = np.arccos(d1 @ d2 / np.linalg.norm(d1) / np.linalg.norm(d2))
    sag = R * (1 - np.cos((np.pi - theta) / ARC_SEGMENTS / 2))
    # directions across the arc, from the leading edge's outward normal to the tip's (+u)
    n_le = np.array([d1[1], -d1[0]]) * -1 / np.linalg.norm(d1)
    phi0, phi1 = np.arctan2(n_le[1], n_le[0]), 0.0
    for phi in np.linspace(phi0, phi1, 23):
        for gap, w in ((0.003, 0.0015), (0.001, 0.0), (0.004, 0.002)):
            uv = centre + (R + gap) * np.array([np.cos(phi), np.sin(phi)])
            p = fin.origin + uv[0] * fin.e1 + uv[1] * fin.e2 + w * fin.n
            # a segment from p away from the plane: its closest point is p itself
            dist, s, qu, qv, crossed = segment_core_closest(p, p + 0.01 * fin.n, sh.fin_origin[i],
                                                            sh.fin_axes[i], core)
            assert not crossed and s == 0.0
            assert np.hypot(gap, w) - 1e-12 <= dist <= np.hypot(gap + sag, w) + 1e-12  # round-off
    # a fin set left sharp keeps its trapezoid as the core
    r1 = mis.fin("rudder_1").index
    assert sh.fin_ncore[r1] == 4 and np.array_equal(sh.fin_core[r1, :4], sh.fin_poly[r1])


def test_normal_turns_continuously_round_the_corner(rounded):
    # Reference: the closest-point map of a convex set is 1-Lipschitz, so the normal (p − q)/|p − q|
    # turns by at most |Δp|/dist per move Δp. A point 2 mm outside the sharp corner's bisector
    # sweeps the whole corner at 1.5 mm above the plane.
    _, sh, fin, i, core, centre = rounded
    normals, dists, steps = [], [], []
    last = None
    for phi in np.linspace(np.pi / 2 + 0.6, -0.6, 1201):
        uv = centre + (R + 0.002) * np.array([np.cos(phi), np.sin(phi)])
        p = fin.origin + uv[0] * fin.e1 + uv[1] * fin.e2 + 0.0015 * fin.n
        dist, s, qu, qv, _ = segment_core_closest(p, p + 0.01 * fin.n, sh.fin_origin[i], sh.fin_axes[i], core)
        q = fin.origin + qu * fin.e1 + qv * fin.e2
        normals.append((p - q) / dist)
        dists.append(dist)
        if last is not None:
            steps.append(np.linalg.norm(p - last))
        last = p
    turn = np.linalg.norm(np.diff(np.array(normals), axis=0), axis=1)
    assert np.all(turn <= np.array(steps) / min(dists) * (1 + 1e-9))
