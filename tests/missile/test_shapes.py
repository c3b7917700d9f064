"""Contact shapes: exact values at special points, self-consistency, segment-vs-thin-fin."""

import numpy as np
import pytest

from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.missile.geometry import build_missile
from flexnet_fe.missile.shapes import (FIN_PART_OFFSET, PART_BODY, PART_NOSE, closest_points,
                                       fin_closest_point, pack_shapes, part_names,
                                       segment_fin_contacts)

EXACT = 1e-12  # [m] all special-point values are closed forms: round-off only


@pytest.fixture(scope="module", params=["radar", "infrared", "cone"])
def missile(request):
    if request.param == "cone":
        cfg = MissileConfig(preset="radar", name="cone", nose_shape="cone", nose_length=0.5)
    else:
        cfg = MissileConfig(preset=request.param)
    return build_missile(cfg)


def one(missile, p):
    d, n, q, part = closest_points(np.array([p], float), pack_shapes(missile))
    return d[0], n[0], q[0], part[0]


def test_part_names(missile):
    names = part_names(missile)
    assert names[:2] == ["body", "nose"]
    assert names[FIN_PART_OFFSET:] == [f"wing_{i}" for i in range(1, 5)] + \
        [f"rudder_{i}" for i in range(1, 5)]


def test_ahead_of_apex(missile):
    # on the axis ahead of the apex the nearest point is the apex: d = a, n = +x_b
    d, n, q, part = one(missile, (0.3, 0, 0))
    assert part == PART_NOSE
    np.testing.assert_allclose([d, *n, *q], [0.3, 1, 0, 0, 0, 0, 0], atol=EXACT)


def test_on_axis_inside_cylinder(missile):
    # at mid-cylinder on the axis the nearest surface is the cylinder at distance R; the radial
    # direction on the axis is +y_b by convention
    s = 0.5 * (missile.nose_length + missile.length)
    d, n, q, part = one(missile, (-s, 0, 0))
    assert part == PART_BODY
    np.testing.assert_allclose([d, *n, *q], [-missile.radius, 0, 1, 0, -s, missile.radius, 0],
                               atol=EXACT)


@pytest.mark.parametrize("phi", [0.3, 2.0, 4.0])
@pytest.mark.parametrize("a", [-0.05, 0.0, 0.02])
def test_radial_from_cylinder(missile, phi, a):
    # between fins (phi not a multiple of 90°), station mid-way between wings and rudders
    s = 2.8
    r = missile.radius + a
    d, n, q, part = one(missile, (-s, r * np.cos(phi), r * np.sin(phi)))
    assert part == PART_BODY
    er = np.array([0, np.cos(phi), np.sin(phi)])
    np.testing.assert_allclose(d, a, atol=EXACT)
    np.testing.assert_allclose(n, er, atol=EXACT)
    np.testing.assert_allclose(q, [-s, *(missile.radius * er[1:])], atol=EXACT)


def test_behind_base(missile):
    d, n, q, part = one(missile, (-missile.length - 0.1, 0, 0))
    assert part == PART_BODY
    np.testing.assert_allclose([d, *n, *q], [0.1, -1, 0, 0, -missile.length, 0, 0], atol=EXACT)


def _nose_surface_points(missile, k=7):
    """Points on the nose surface with their exact outward normals (from the profile's closed
    form: arc -> radial from the arc centre; cone -> constant normal)."""
    kind, data = missile.profile[0].kind, missile.profile[0].data
    out = []
    for i, phi in enumerate(np.linspace(0.2, 6.0, k)):
        f = (i + 0.5) / k
        if kind.name == "ARC":
            sc, rc, rho, th0, th1 = data
            th = th0 + f * (th1 - th0)
            s, r = sc + rho * np.cos(th), rc + rho * np.sin(th)
            ns, nr = np.cos(th), np.sin(th)
        else:
            s0, r0, s1, r1 = data
            s, r = s0 + f * (s1 - s0), r0 + f * (r1 - r0)
            ln = np.hypot(s1 - s0, r1 - r0)
            ns, nr = -(r1 - r0) / ln, (s1 - s0) / ln
        er = np.array([np.cos(phi), np.sin(phi)])
        out.append((np.array([-s, *(r * er)]), np.array([-ns, *(nr * er)])))
    return out


@pytest.mark.parametrize("a", [0.0, 1e-3, -1e-3, 0.05])
def test_nose_offsets_along_normal(missile, a):
    # a point moved by a along the exact outward normal of a smooth convex surface point is at
    # signed distance a from it (for |a| below the radius of curvature and the local radius)
    for x, n_ref in _nose_surface_points(missile):
        d, n, q, part = one(missile, x + a * n_ref)
        assert part == PART_NOSE
        np.testing.assert_allclose(d, a, atol=EXACT)
        np.testing.assert_allclose(n, n_ref, atol=1e-9)
        np.testing.assert_allclose(q, x, atol=1e-11)


def test_hemisphere_is_a_sphere():
    mis = build_missile(MissileConfig(preset="infrared"))
    c = np.array([-mis.radius, 0, 0])
    rng = np.random.default_rng(1)
    u = rng.normal(size=(200, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    u[:, 0] = np.abs(u[:, 0])  # forward half: the dome
    a = rng.uniform(-0.5, 2.0, 200) * mis.radius
    d, n, _, part = closest_points(c + (mis.radius + a)[:, None] * u, pack_shapes(mis))
    # sphere of radius R centred at (-R, 0, 0): d = |p - c| - R, n = (p - c)/|p - c|
    np.testing.assert_allclose(d, a, atol=EXACT)
    np.testing.assert_allclose(n, u, atol=1e-12)
    assert (part == PART_NOSE).all()
    # the apex itself: on the surface (d = 0), normal +x_b (the sphere's normal there)
    d, n, q, part = closest_points(np.zeros((1, 3)), pack_shapes(mis))
    np.testing.assert_allclose([d[0], *n[0], *q[0]], [0, 1, 0, 0, 0, 0, 0], atol=EXACT)


def test_fin_special_points(missile):
    shapes = pack_shapes(missile)
    for i, fin in enumerate(missile.fins):
        h2 = 0.5 * fin.thickness
        centre = fin.origin + 0.5 * fin.span * fin.e1 + 0.25 * fin.uv[:, 1].sum() * fin.e2
        for w in (0.03, -0.02, 0.5 * h2, -0.25 * h2):
            # above/below the mid-span face, far from edges: d = |w| - h/2, n = sign(w) n_fin
            d, n, q, part = one(missile, centre + w * fin.n)
            assert part == FIN_PART_OFFSET + i
            np.testing.assert_allclose(d, abs(w) - h2, atol=EXACT)
            np.testing.assert_allclose(n, np.sign(w) * fin.n, atol=EXACT)
            np.testing.assert_allclose(q, centre + np.sign(w) * h2 * fin.n, atol=EXACT)
        # beyond the tip leading-edge corner, along the bisector of the leading-edge normal
        # (sin Λ e1 - cos Λ e2) and the tip normal (e1): the corner line is nearest, d = 0.01 m
        lam = fin.leading_edge_sweep
        bis = (np.sin(lam) + 1) * fin.e1 - np.cos(lam) * fin.e2
        bis /= np.linalg.norm(bis)
        tip_le = fin.corners[2]
        d, n, q, part = one(missile, tip_le + 0.01 * bis + 0.5 * h2 * fin.n)
        assert part == FIN_PART_OFFSET + i
        np.testing.assert_allclose(d, 0.01, atol=EXACT)
        np.testing.assert_allclose(q, tip_le + 0.5 * h2 * fin.n, atol=EXACT)
        np.testing.assert_allclose(n, bis, atol=1e-12)
        # straight out of the tip: d = a, n = e1
        mid_tip = 0.5 * (fin.corners[2] + fin.corners[3])
        d, n, _, _ = one(missile, mid_tip + 0.02 * fin.e1)
        np.testing.assert_allclose([d, *n], [0.02, *fin.e1], atol=EXACT)


def test_closest_point_self_consistency(missile):
    # independent checks on random points around the missile: |p - q| = |d|, q lies on the zero
    # level, and n is the gradient of d (central differences, step 1e-6 m: error O(step²) away
    # from the medial axis, where d has a kink -> those few points are skipped)
    rng = np.random.default_rng(7)
    n_pts = 3000
    p = np.column_stack([rng.uniform(-missile.length - 0.2, 0.2, n_pts),
                         rng.uniform(-0.6, 0.6, n_pts), rng.uniform(-0.6, 0.6, n_pts)])
    shapes = pack_shapes(missile)
    d, n, q, _ = closest_points(p, shapes)
    np.testing.assert_allclose(np.linalg.norm(p - q, axis=1), np.abs(d), atol=1e-12)
    dq = closest_points(q, shapes)[0]
    assert np.abs(dq).max() < 1e-12
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)
    hstep = 1e-6
    grad = np.empty_like(p)
    for k in range(3):
        e = np.zeros(3)
        e[k] = hstep
        grad[:, k] = (closest_points(p + e, shapes)[0]
                      - closest_points(p - e, shapes)[0]) / (2 * hstep)
    smooth = np.abs(np.linalg.norm(grad, axis=1) - 1.0) < 1e-6
    assert smooth.mean() > 0.95
    np.testing.assert_allclose(n[smooth], grad[smooth], atol=1e-5)
    inside = d < 0
    assert 0 < inside.sum() < n_pts


# ---------------------------------------------------------------------- segment vs thin fin


def _wing1(missile):
    fin = missile.fin("wing_1")
    assert abs(fin.n @ [0, 0, 1] - 1) < 1e-15  # roll 0: plate in the x-y plane, normal +z_b
    return fin


def test_segment_crossing_leading_edge_between_samples(missile):
    fin = _wing1(missile)
    u = 0.5 * fin.span
    e = 0.004  # the rope sits e (in the plate plane, normal to the edge) behind the leading edge
    lam = fin.leading_edge_sweep
    le_point = fin.origin + u * fin.e1 + u * np.tan(lam) * fin.e2
    # outward in-plane normal of the leading edge (u, v) direction (cos Λ, sin Λ) -> (sin Λ, -cos Λ)
    edge_normal = np.sin(lam) * fin.e1 - np.cos(lam) * fin.e2
    x0 = le_point - e * edge_normal
    a = x0 + 0.05 * fin.n + 0.01 * fin.e1
    b = x0 - 0.05 * fin.n - 0.01 * fin.e1
    # 14 point samples (7.1 mm apart through the thickness) miss the 6 mm plate: all outside
    t_s = (np.arange(14) + 0.5) / 14
    samples = a + t_s[:, None] * (b - a)
    assert closest_points(samples, pack_shapes(missile))[0].min() > 0
    part, t, point, depth, normal = segment_fin_contacts(a, b, pack_shapes(missile))
    assert part[0] == FIN_PART_OFFSET + fin.index
    # the segment crosses the mid-plane at t = 1/2, at x0: depth e, normal = the edge normal
    np.testing.assert_allclose(t[0], 0.5, atol=EXACT)
    np.testing.assert_allclose(point[0], x0, atol=EXACT)
    np.testing.assert_allclose(depth[0], e, atol=EXACT)
    np.testing.assert_allclose(normal[0], edge_normal, atol=EXACT)


def test_segment_near_tip_and_miss(missile):
    fin = _wing1(missile)
    mid_tip = 0.5 * (fin.corners[2] + fin.corners[3])
    shapes = pack_shapes(missile)
    # crossing 3 mm inboard of the tip, mid-chord: the tip is the nearest free edge
    x0 = mid_tip - 0.003 * fin.e1
    part, t, point, depth, normal = segment_fin_contacts(x0 + 0.1 * fin.n, x0 - 0.02 * fin.n,
                                                         shapes)
    assert part[0] == FIN_PART_OFFSET + fin.index
    np.testing.assert_allclose([t[0], depth[0], *normal[0]], [0.1 / 0.12, 0.003, *fin.e1],
                               atol=EXACT)
    # the same segment 3 mm outboard of the tip misses
    x1 = mid_tip + 0.003 * fin.e1
    part, *_ = segment_fin_contacts(x1 + 0.1 * fin.n, x1 - 0.02 * fin.n, shapes)
    assert part[0] == -1


def test_segment_dipping_into_a_face(missile):
    fin = _wing1(missile)
    h2 = 0.5 * fin.thickness
    x0 = fin.origin + 0.5 * fin.span * fin.e1 + (0.5 * fin.span * np.tan(fin.leading_edge_sweep)
                                                 + 0.5 * fin.tip_chord) * fin.e2
    # a V-free straight segment lying 1 mm below the upper face, parallel to it, well inside
    a = x0 + (h2 - 0.001) * fin.n - 0.02 * fin.e2
    b = x0 + (h2 - 0.001) * fin.n + 0.02 * fin.e2
    part, t, point, depth, normal = segment_fin_contacts(a, b, pack_shapes(missile))
    assert part[0] == FIN_PART_OFFSET + fin.index
    np.testing.assert_allclose([depth[0], *normal[0]], [0.001, *fin.n], atol=EXACT)
    # a segment descending from 5 mm above the face to 0.5 mm below it (not reaching the
    # mid-plane): deepest point is the lower end b, depth 0.5 mm
    a = x0 + (h2 + 0.005) * fin.n
    b = x0 + (h2 - 0.0005) * fin.n + 0.003 * fin.e2
    part, t, point, depth, normal = segment_fin_contacts(a, b, pack_shapes(missile))
    np.testing.assert_allclose([t[0], depth[0], *normal[0]], [1.0, 0.0005, *fin.n], atol=EXACT)


def test_segments_agree_with_dense_point_sampling():
    # second model: sample each random segment at 2001 points with the plate's point-wise
    # signed distance. Sampling resolves depths to about |b - a|/2000 <= 1e-4 m.
    missile = build_missile(MissileConfig(preset="radar"))
    rng = np.random.default_rng(3)
    shapes = pack_shapes(missile)
    fin = missile.fin("rudder_2")
    i = fin.index
    n_seg = 200
    centre = fin.origin + 0.5 * fin.span * fin.e1 + 0.1 * fin.e2
    a = centre + rng.normal(scale=0.08, size=(n_seg, 3))
    b = centre + rng.normal(scale=0.08, size=(n_seg, 3))
    # second half: grazing segments on one side of the mid-plane (w in (0, 3h/2)), which dip
    # into the face without crossing the mid-plane
    half = n_seg // 2
    for x in (a, b):
        x[half:] -= np.outer((x[half:] - fin.origin) @ fin.n, fin.n)
        x[half:] += np.outer(rng.uniform(1e-4, 1.5 * fin.thickness, n_seg - half), fin.n)
    part, t, point, depth, normal = segment_fin_contacts(a, b, shapes)
    ts = np.linspace(0.0, 1.0, 2001)
    n_hits = [0, 0]
    for k in range(n_seg):
        sdf = np.array([fin_closest_point(a[k] + tt * (b[k] - a[k]), shapes.fin_origin[i],
                                          shapes.fin_axes[i], shapes.fin_poly[i],
                                          shapes.fin_half_thickness[i])[0] for tt in ts])
        res = np.linalg.norm(b[k] - a[k]) / 2000
        if sdf.min() < -res:
            assert part[k] == FIN_PART_OFFSET + i
        if part[k] == FIN_PART_OFFSET + i:
            assert sdf.min() < res
            w_a = (a[k] - fin.origin) @ fin.n
            w_b = (b[k] - fin.origin) @ fin.n
            n_hits[int(w_a * w_b > 0)] += 1
            if w_a * w_b > 0:  # not crossing the mid-plane: depth = -min of the plate SDF
                np.testing.assert_allclose(depth[k], -sdf.min(), atol=res)
            else:
                # crossing: t is where w = 0 and depth the in-plane distance from that point to
                # the nearest free edge line (leading edge, tip, trailing edge of fin.uv)
                np.testing.assert_allclose(t[k], w_a / (w_a - w_b), atol=1e-12)
                uv = fin.to_plane(point[k])[0, :2]
                dist = []
                for e in (1, 2, 3):
                    c0, c1 = fin.uv[e], fin.uv[(e + 1) % 4]
                    tan = (c1 - c0) / np.linalg.norm(c1 - c0)
                    dist.append(abs(np.cross(tan, uv - c0)))
                np.testing.assert_allclose(depth[k], min(dist), atol=1e-12)
                # escaping over an edge needs at least the plate's local depth
                assert depth[k] >= -sdf[np.argmin(np.abs(ts - t[k]))] - res
    assert min(n_hits) > 10  # both branches (crossing, not crossing) exercised
