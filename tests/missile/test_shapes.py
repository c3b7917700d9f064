"""Contact shapes: exact values at special points, self-consistency, segment-vs-thin-fin."""

import numpy as np
import pytest

from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.missile.build import build_missile
from flexnet_fe.missile.shapes import (FIN_PART_OFFSET, PART_BODY, PART_NOSE, body_closest_point,
                                       closest_points, fin_closest_point, pack_shapes, part_names,
                                       segment_body_closest, segment_core_closest)

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


def _core(missile, fin):
    sh = pack_shapes(missile)
    return sh.fin_origin[fin.index], sh.fin_axes[fin.index], sh.fin_poly[fin.index]


def _closest(missile, fin, a, b):
    """segment_core_closest with q as a point in B."""
    o, ax, poly = _core(missile, fin)
    d, s, qu, qv, crossed = segment_core_closest(np.asarray(a, float), np.asarray(b, float), o, ax, poly)
    return d, s, o + qu * ax[0] + qv * ax[1], crossed


def test_capsule_core_face_edge_corner(missile):
    # Reference: closed forms of point/segment distances to a planar polygon.
    fin = _wing1(missile)
    tip_mid = 0.5 * (fin.corners[2] + fin.corners[3])
    # face: a chordwise segment 10 mm above the mid-plane, over the plate: dist 10 mm, q below it
    a, b = tip_mid - 0.05 * fin.e1 + 0.01 * fin.n - 0.01 * fin.e2, tip_mid - 0.05 * fin.e1 + 0.01 * fin.n + 0.01 * fin.e2
    d, s, q, crossed = _closest(missile, fin, a, b)
    p = a + s * (b - a)
    assert not crossed and d == pytest.approx(0.01, abs=EXACT)
    np.testing.assert_allclose((p - q) / d, fin.n, atol=1e-9)
    # tip edge: a segment along n, 4 mm outboard of the tip, crossing the mid-plane: dist 4 mm,
    # normal = the tip's outward in-plane normal e1, closest point at the crossing
    a, b = tip_mid + 0.004 * fin.e1 + 0.03 * fin.n, tip_mid + 0.004 * fin.e1 - 0.01 * fin.n
    d, s, q, crossed = _closest(missile, fin, a, b)
    assert not crossed and d == pytest.approx(0.004, abs=EXACT) and s == pytest.approx(0.75, abs=1e-12)
    np.testing.assert_allclose(q, tip_mid, atol=EXACT)
    # edge, off the plane: chordwise segment 3 mm outboard and 4 mm above: dist 5 mm (3-4-5)
    a, b = tip_mid + 0.003 * fin.e1 + 0.004 * fin.n - 0.01 * fin.e2, tip_mid + 0.003 * fin.e1 + 0.004 * fin.n + 0.01 * fin.e2
    d, s, q, crossed = _closest(missile, fin, a, b)
    p = a + s * (b - a)
    assert d == pytest.approx(0.005, abs=EXACT)
    np.testing.assert_allclose((p - q) / d, 0.6 * fin.e1 + 0.8 * fin.n, atol=1e-9)
    # corner: the tip leading-edge corner, a segment ending 2 mm beyond it along both edges' outward
    # bisector and 1 mm above: dist = |p − corner|
    c = fin.corners[2]
    t_le = fin.uv[2] - fin.uv[1]
    n_le = np.array([t_le[1], -t_le[0]]) / np.linalg.norm(t_le)  # outward normal of the leading edge
    n_uv = n_le + np.array([1.0, 0.0])  # + the tip's (e1): the bisector lies in the corner's region
    out = n_uv[0] * fin.e1 + n_uv[1] * fin.e2
    out /= np.linalg.norm(out)
    p = c + 0.002 * out + 0.001 * fin.n
    d, s, q, crossed = _closest(missile, fin, p, p + 0.03 * out)
    assert s == 0.0 and d == pytest.approx(np.linalg.norm(p - c), abs=EXACT)
    np.testing.assert_allclose(q, c, atol=EXACT)
    # through the face: crossed, dist 0, at the crossing
    a, b = tip_mid - 0.05 * fin.e1 + 0.02 * fin.n, tip_mid - 0.05 * fin.e1 - 0.02 * fin.n
    d, s, q, crossed = _closest(missile, fin, a, b)
    assert crossed and d == 0.0 and s == pytest.approx(0.5, abs=1e-12)


def test_capsule_normal_is_continuous_from_face_to_edge(missile):
    # Reference: the closest-point map of a convex set is 1-Lipschitz, so the normal
    # n = (p − q)/|p − q| turns by at most |Δp|/dist when the segment moves by Δp. A chordwise
    # segment 2 mm above the mid-plane slides outboard across the tip (face → edge → free):
    # the normal must turn smoothly from n to e1 (no jump at the face/edge switch).
    fin = _wing1(missile)
    tip_mid = 0.5 * (fin.corners[2] + fin.corners[3])
    us = np.linspace(-0.004, 0.004, 801)
    normals, dists = [], []
    for u in us:
        a = tip_mid + u * fin.e1 + 0.002 * fin.n - 0.01 * fin.e2
        d, s, q, _ = _closest(missile, fin, a, a + 0.02 * fin.e2)
        normals.append((a + s * 0.02 * fin.e2 - q) / d)
        dists.append(d)
    normals = np.array(normals)
    turn = np.linalg.norm(np.diff(normals, axis=0), axis=1)
    assert np.all(turn <= (us[1] - us[0]) / min(dists) * (1 + 1e-9))
    np.testing.assert_allclose(normals[0], fin.n, atol=1e-12)
    np.testing.assert_allclose(normals[-1], (0.004 * fin.e1 + 0.002 * fin.n) / np.hypot(0.004, 0.002), atol=1e-12)
    assert np.all(np.abs(np.linalg.norm(normals, axis=1) - 1.0) < 1e-12)


def test_segment_body_closest_matches_dense_sampling(missile):
    # Reference (second model): the minimum of the body's point-wise signed distance over 4001
    # points of the segment; sampling resolves the minimum to ~ (|b − a|/4000)² curvature terms.
    rng = np.random.default_rng(5)
    sh = pack_shapes(missile)
    for _ in range(60):
        x = -rng.uniform(0.0, missile.length)
        a = np.array([x, *rng.normal(scale=0.15, size=2)])
        b = a + rng.normal(scale=0.1, size=3)
        d, s, *_rest, part = segment_body_closest(a, b, sh.prof_kind, sh.prof_data, sh.prof_part)
        ts = np.linspace(0.0, 1.0, 4001)
        sdf = np.array([body_closest_point(a + t * (b - a), sh.prof_kind, sh.prof_data, sh.prof_part)[0] for t in ts])
        assert d <= sdf.min() + 1e-12
        assert d == pytest.approx(sdf.min(), abs=2e-7)


def test_segment_body_closest_cutoff_never_changes_the_contact_answer(missile):
    # Reference: the exact search (no cutoff). With a cutoff c the search may stop at the lower
    # bound of the convex distance along the segment (its end tangents' crossing): the returned d
    # must then be ≤ the exact minimum and ≥ c, so "d < c" (in contact for c = the rope radius)
    # is answered the same; below the cutoff the result is the exact one, bit for bit.
    rng = np.random.default_rng(11)
    sh = pack_shapes(missile)
    cut = 2.25e-3
    skipped = 0
    for _ in range(400):
        x = -rng.uniform(0.0, missile.length)
        a = np.array([x, *rng.normal(scale=0.12, size=2)])
        b = a + rng.normal(scale=0.05, size=3)
        exact = segment_body_closest(a, b, sh.prof_kind, sh.prof_data, sh.prof_part)
        fast = segment_body_closest(a, b, sh.prof_kind, sh.prof_data, sh.prof_part, cut)
        assert (fast[0] < cut) == (exact[0] < cut)
        if fast[0] < cut:
            assert fast == exact
        else:
            assert fast[0] <= exact[0] + 1e-15
            skipped += fast != exact
    assert skipped > 20  # the shortcut was taken
