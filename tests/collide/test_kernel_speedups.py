"""The collision kernel's candidate list (``collide.kernel``: contacts are evaluated only for the
segments whose clearance is within CANDIDATE_SKIN, until some node has moved by its margin) must
never skip a contact. Each test states its reference."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexnet_fe.collide import kernel as K
from flexnet_fe.collide import model as M
from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.collide.simulate import build
from flexnet_fe.missile.shapes import pack_shapes, segment_body_closest, segment_core_closest

R = 2.25e-3  # rope radius [m]
H = 3.0e-3  # wing half-thickness [m]


def _copy(st):
    return st._replace(**{f: getattr(st, f).copy() for f in st._fields})


PER_CALL = [M.A_IMP_B, M.A_IMP_B + 1, M.A_IMP_B + 2, M.A_PEN_INT, M.A_NCONTACT, M.A_FCONTACT]
"""accumulators that each call of ``advance`` restarts from 0 (they differ between call lengths)"""


def _same_state(a, b):
    """Bit-identical states, except the per-call accumulators."""
    whole_run = np.setdiff1d(np.arange(M.N_ACC), PER_CALL)
    return (all(np.array_equal(getattr(a, f), getattr(b, f)) for f in a._fields if f != "acc")
            and np.array_equal(a.acc[whole_run], b.acc[whole_run]))


def test_segment_thrown_from_five_skins_away_in_one_call(radar, scenes):
    # Reference: (1) the Hertz impact of a mass m at speed v on a rigid flat with F = K δ^1.5,
    # δ_max = (5 m v²/(4K))^(2/5) (as tests/collide/test_contact_kernel.py); (2) the same motion
    # in calls of one step, which rebuild the candidate list at every step. The segment starts
    # 5 skins from the wing face, outside the candidate list: in one call of ≈ 22 000 steps it is
    # caught only if the margin check rebuilds the list on the way in. A skipped contact would
    # tunnel (status TUNNEL) or change the state; the two runs must agree bit for bit.
    m, v, kc = 1.6e-3, 100.0, 1e9
    a = np.array([-1.8, 0.3, H + R + 5 * K.CANDIDATE_SKIN])
    km, st = scenes.segment_scene(radar, a, a + [0, 0, 0.05], [0, 0, -v], [0, 0, 0], mass=m, k_contact=kc,
                                  free=(True, False))
    dmax = (5 * m * v * v / (4 * kc)) ** 0.4
    t_c = 2 * dmax / v * 0.4 * math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9)
    dt = t_c / 4000
    n = int(round((5 * K.CANDIDATE_SKIN / v + 1.5 * t_c) / dt))
    one = _copy(st)
    assert K.advance(km, one, n, dt) == M.OK
    for _ in range(n):
        assert K.advance(km, st, 1, dt) == M.OK
    assert one.acc[M.A_PEN] == pytest.approx(dmax, rel=2e-3)
    assert one.v[0, 2] == pytest.approx(v, rel=2e-3)  # elastic rebound: the contact did act
    assert _same_state(one, st)


@pytest.mark.parametrize("law, aim_x", [("segment", 0.0), ("line", 0.025)])
def test_net_impact_in_long_calls_equals_one_step_calls(radar, log, scenes, law, aim_x):
    # Reference: the same impact advanced in calls of one step (the candidate list is rebuilt at
    # every step, so every segment within CANDIDATE_SKIN of touching is tested every step)
    # against calls of 400 steps (the list is rebuilt only when a node reaches its margin). A
    # 0.4 m net hit at 500 m/s, 1 200 steps (113–120 mm of travel): state,
    # contact slots, fin loads and accumulators must be bit-identical. Segment law: the nose's tip
    # is aimed at a rope (x = 0) 20 mm ahead, the first touch ≈ 200 steps into the first long call.
    # Line law: aimed between two ropes (x = 0.025), the nose's flanks meet both — its tip on this
    # unsplit 5 cm rope at 100 GPa goes through (stopped: TUNNEL, collide.config.ContactLaw).
    net = scenes.flat_net(0.4, 0.05)
    cfg = CollideConfig(net_source="flat_taut", duration=1e-3, aim_point=(aim_x, 0.02), crop=False, contact_law=law)
    setup = build(net, radar, cfg, 9.81, log, False)
    km, s = setup.model, setup.start
    st = M.new_state(net.x[setup.used], km.seg.shape[0], km.fin_half.shape[0], s.x_cg, s.v_cg, s.q)
    dt = 0.5 * setup.step.dt
    n_steps = 1200
    long = _copy(st)
    for _ in range(n_steps // 400):
        assert K.advance(km, long, 400, dt) == M.OK
    for _ in range(n_steps):
        assert K.advance(km, st, 1, dt) == M.OK
    assert st.acc[M.A_DISS_CONTACT] > 0.0 and long.part_imp.sum() > 0.0  # contacts were active
    assert _same_state(long, st)


def _exact_touch(a, b, sh):
    """Does the capsule a–b (radius R) touch or cross any part? Exact narrow phase of every part
    (``missile.shapes``), no broad phase."""
    d, *_ = segment_body_closest(a, b, sh.prof_kind, sh.prof_data, sh.prof_part)
    if d <= R:
        return True
    for fi in range(len(sh.fin_half_thickness)):
        dist, *_ = segment_core_closest(a, b, sh.fin_origin[fi], sh.fin_axes[fi], sh.fin_poly[fi])
        if dist <= R + sh.fin_half_thickness[fi]:
            return True
    return False


def test_clearance_is_a_one_lipschitz_lower_bound(radar, scenes):
    # Reference: the exact distances of ``missile.shapes`` (every part, no broad phase). The
    # candidate list's proof needs: a capsule whose clearance c is > 0 cannot touch any part
    # after each of its ends moved by less than c. 3 000 random capsules (3–100 mm) near the
    # fins' roots, edges and tips and the body; each with c > 0 is moved three ways by 0.999 c
    # per end — translated towards the nearest part, both ends in random directions, the ends
    # apart along the segment (the length change the bounding-cylinder term divides by 3) — and
    # must not touch. Every touching capsule must have c ≤ 0.
    sh = pack_shapes(radar)
    km, _ = scenes.segment_scene(radar, [-1.3, 0.1015, 0.0], [-1.75, 0.3, 0.0], [0, 0, 0], [0, 0, 0])
    wk = K._work(km, 2)
    rng = np.random.default_rng(11)
    ref_pts = np.array([[-1.3, 0.1015, 0.0], [-1.75, 0.3, 0.0], [-2.0, 0.51, 0.0], [-1.9, 0.1015, 0.0],
                        [-3.24, 0.0, 0.1015], [-3.5, 0.0, -0.2], [-0.5, 0.07, 0.07], [-3.6, 0.0, 0.0]])
    n_moved = n_touch = 0
    for _ in range(3000):
        c0 = ref_pts[rng.integers(len(ref_pts))] + rng.normal(scale=0.02, size=3)
        u = rng.normal(size=3)
        half = 0.5 * rng.uniform(3e-3, 0.1) * u / np.linalg.norm(u)
        a, b = c0 - half, c0 + half
        c = K._clearance(km.bbox, R, wk.fin_pl, wk.fin_rh, km.nose_cones, a, b, K.CANDIDATE_SKIN)
        if _exact_touch(a, b, sh):
            n_touch += 1
            assert c <= 0.0
            continue
        if c <= 0.0:
            continue
        step = 0.999 * c
        mid = 0.5 * (a + b)
        towards = -np.array([0.0, mid[1], mid[2]]) / max(np.hypot(mid[1], mid[2]), 1e-12)
        for da, db in ((step * towards, step * towards), (step * _unit(rng), step * _unit(rng)),
                       (-step * half / np.linalg.norm(half), step * half / np.linalg.norm(half))):
            assert not _exact_touch(a + da, b + db, sh)
            n_moved += 1
    assert n_touch > 300 and n_moved > 1000  # the sample exercises both kinds


def _unit(rng):
    u = rng.normal(size=3)
    return u / np.linalg.norm(u)


@pytest.mark.parametrize("preset", ["radar", "infrared"])
def test_nose_cones_bound_the_body_distance(preset):
    # Reference: the exact body distance of ``missile.shapes.segment_body_closest`` (no broad phase).
    # The nose cones' gap (kernel._body_gap) must be a lower bound of (distance to the body − r)
    # for every capsule around the nose, and stay one after each end moved by 0.999 of it (the
    # candidate list's 1-Lipschitz proof); it must also be tighter than the bounding cylinder
    # alone where the cylinder is loose (around the radome / dome), or it does nothing.
    from flexnet_fe.missile.build import build_missile
    from flexnet_fe.missile.config import MissileConfig
    from flexnet_fe.missile.shapes import nose_cones

    missile = build_missile(MissileConfig(preset=preset))
    sh = pack_shapes(missile)
    cones = nose_cones(sh.prof_kind, sh.prof_data)
    r_body = float(sh.prof_data[1, 1])  # the cylinder's radius and first station (profile row 1)
    nose = float(sh.prof_data[1, 0])
    assert cones.shape == (4, 2)
    rng = np.random.default_rng(3)
    tighter = 0
    for _ in range(2000):
        x = -rng.uniform(-0.02, 1.1 * nose)
        c0 = np.array([x, *rng.normal(scale=0.08, size=2)])
        u = rng.normal(size=3)
        half = 0.5 * rng.uniform(3e-3, 0.05) * u / np.linalg.norm(u)
        a, b = c0 - half, c0 + half
        gap = K._body_gap(K._axis_distance(a, b), cones, R, a, b, r_body)
        d = segment_body_closest(a, b, sh.prof_kind, sh.prof_data, sh.prof_part)[0]
        assert gap <= max(d, 0.0) - R + 1e-12  # (inside the body, d < 0: the distance is 0)
        tighter += K._axis_distance(a, b) - r_body - R <= 0.0 < gap
        if gap > 0.0:
            da, db = 0.999 * gap * _unit(rng), 0.999 * gap * _unit(rng)
            assert segment_body_closest(a + da, b + db, sh.prof_kind, sh.prof_data, sh.prof_part)[0] > R
    assert tighter > 300
