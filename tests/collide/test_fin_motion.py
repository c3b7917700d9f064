"""A prescribed fin motion in the collision kernel (``model.FinMotion``, ``kernel._fin_motion``,
``kernel._point_depth``): the one-way check's second collision (``study.one_way``). Scenes next to
the radar missile's wing_1 (B frame: origin (−1.3, 0.1015, 0) m, e1 = +y (span u), e2 = −x (chord
v), normal n = +z, faces at z = ±3 mm). Each test states its reference."""

from __future__ import annotations

import numpy as np
import pytest

from flexnet_fe.collide import kernel as K
from flexnet_fe.collide import model as M
from flexnet_fe.contact.stiffness import crossed_cylinders_stiffness, line_stiffness

R = 2.25e-3  # rope radius [m]
H = 3.0e-3  # wing half-thickness [m]
K_LINE = line_stiffness(crossed_cylinders_stiffness(R, H, 1e10 / 0.91), R + H)  # the cases' k_l [N/m²]
H_LINE = R / 4  # the cases' point spacing [m]


def on_wing_1(u, v, z):
    """B coordinates [m] of wing_1's planform point (u, v) at height z above its mid-plane."""
    return np.array([-1.3 - v, 0.1015 + u, z])


def motion(radar, w_of_t, times, fin=0, nu=5, nv=5):
    """A FinMotion moving fin ``fin`` of ``radar`` uniformly by w(t) [m] (callable) sampled at ``times``
    (regular, from times[0]) on a nu × nv grid over its planform; every other fin rigid."""
    nf = len(radar.fins)
    nt = np.zeros(nf, np.int64)
    nt[fin] = len(times)
    offset = np.concatenate([[0], np.cumsum(nt)])
    grid = np.tile([-0.1, 0.6 / (nu - 1), -0.1, 1.0 / (nv - 1)], (nf, 1))
    w = np.repeat(np.array([w_of_t(t) for t in times])[:, None, None], nu, 1).repeat(nv, 2)
    t0 = np.full(nf, times[0])
    return M.FinMotion(t0=t0, dt=float(times[1] - times[0]), nt=nt, offset=offset, grid=grid, w=w)


def test_a_motion_of_zero_changes_nothing_to_the_bit(radar, scenes):
    # Reference: the rigid kernel. With w ≡ 0 (samples present) every contact point, force and
    # accumulator must be the same arithmetic: a rope segment striking wing_1's tip edge at 500 m/s.
    # (E_t = 100 GPa, as test_line_contact's strike: the cases' 10 GPa lets this bare segment through)
    kl = line_stiffness(crossed_cylinders_stiffness(R, H, 1e11 / 0.91), R + H)
    a = np.array([-2.0, 0.1015 + 0.4085 + H + R + 1e-4, -0.025])
    v0 = [0.0, -500.0, 0.0]
    rigid = scenes.segment_scene(radar, a, a + [0, 0, 0.05], v0, v0, mass=1.6e-3, k=318.0,
                                 damping="lankarani_nikravesh", line_h=H_LINE, k_line=kl)
    km, st = scenes.segment_scene(radar, a, a + [0, 0, 0.05], v0, v0, mass=1.6e-3, k=318.0,
                                  damping="lankarani_nikravesh", line_h=H_LINE, k_line=kl)
    km = M.with_fin_motion(km, motion(radar, lambda t: 0.0, np.linspace(0.0, 1e-5, 11)))
    for _ in range(400):
        assert K.advance(*rigid, 50, 1e-9) == M.OK
        assert K.advance(km, st, 50, 1e-9) == M.OK
    assert rigid[1].acc[M.A_FCONTACT] == 0.0 and rigid[1].v[0, 1] > 0.0  # struck and thrown back
    np.testing.assert_array_equal(st.x, rigid[1].x)
    np.testing.assert_array_equal(st.v, rigid[1].v)
    np.testing.assert_array_equal(st.mv, rigid[1].mv)
    assert st.acc[M.A_FIN_WORK] == 0.0


@pytest.mark.parametrize("shift", [0.3e-3, -0.2e-3])
def test_a_uniform_motion_is_the_fin_moved(radar, scenes, shift):
    # Reference: the rigid kernel with wing_1's origin moved by w n (a second geometry). A rope lying
    # across the face at 1.5 mm penetration, and one crossing the tip edge: the stored contact energy
    # (the line integral) must be the same to round-off.
    for a, b in ((on_wing_1(0.2, 0.30, H + R - 1.5e-3), on_wing_1(0.2, 0.33, H + R - 1.5e-3)),
                 (on_wing_1(0.4085 + H + R - 0.2e-3, 0.65, -0.02), on_wing_1(0.4085 + H + R - 0.2e-3, 0.65, 0.02))):
        a, b = a + [0, 0, shift], b + [0, 0, shift]
        km, st = scenes.segment_scene(radar, a, b, 0.0, 0.0, line_h=H_LINE, k_line=K_LINE)
        moved = km._replace(fin_origin=km.fin_origin + np.outer(np.eye(len(radar.fins))[0], [0.0, 0.0, shift]))
        km = M.with_fin_motion(km, motion(radar, lambda t: shift, np.linspace(0.0, 1e-5, 3)))
        st.acc[M.A_TIME] = 5e-6
        u_moved = K.energies(moved, st)[2]
        assert u_moved > 0.0
        assert K.energies(km, st)[2] == pytest.approx(u_moved, rel=1e-9)


def test_a_moving_face_throws_a_resting_rope_at_twice_its_speed(radar, scenes):
    # Reference: an elastic collision with a prescribed (infinitely heavy) wall moving at v_w: the
    # particle leaves at 2 v_w, having received the work 2 m v_w² (closed form; the missile takes the
    # reaction, 1e-5 of the rope's mass ratio). No damping, no friction. The energy balance closes
    # with the wall's work booked as external (conservation law): to the step error, O(dt) of the
    # work (dt = 1 ns against a contact of ≈ 20 µs).
    v_w, gap = 5.0, 0.1e-3
    a, b = on_wing_1(0.2, 0.30, H + R + gap), on_wing_1(0.2, 0.33, H + R + gap)
    km, st = scenes.segment_scene(radar, a, b, 0.0, 0.0, line_h=H_LINE, k_line=K_LINE)
    times = np.linspace(0.0, 300e-6, 301)
    km = M.with_fin_motion(km, motion(radar, lambda t: v_w * t, times))
    e0 = sum(K.energies(km, st)) + 0.5 * km.m_mass * float(st.mv @ st.mv)
    for _ in range(300):
        assert K.advance(km, st, 1000, 1e-9) == M.OK
    m = km.mass.sum()
    assert st.acc[M.A_FCONTACT] == 0.0  # the rope has left the face
    np.testing.assert_allclose(st.v[:, 2], 2.0 * v_w, rtol=1e-3)
    work = st.acc[M.A_FIN_WORK]
    assert work == pytest.approx(2.0 * m * v_w ** 2, rel=2e-3)
    e1 = sum(K.energies(km, st)) + 0.5 * km.m_mass * float(st.mv @ st.mv)
    assert abs(e1 - e0 - work) < 1e-3 * work


def test_a_motion_for_the_segment_law_or_the_wrong_fins_is_refused(radar, scenes):
    a = on_wing_1(0.2, 0.30, 0.01)
    km, _ = scenes.segment_scene(radar, a, a + [0.01, 0, 0], 0.0, 0.0)  # segment law
    with pytest.raises(ValueError, match="contact_law = 'line'"):
        M.with_fin_motion(km, motion(radar, lambda t: 0.0, np.linspace(0.0, 1e-5, 3)))
    km, _ = scenes.segment_scene(radar, a, a + [0.01, 0, 0], 0.0, 0.0, line_h=H_LINE, k_line=K_LINE)
    m = motion(radar, lambda t: 0.0, np.linspace(0.0, 1e-5, 3))
    with pytest.raises(ValueError, match="do not match"):
        M.with_fin_motion(km, m._replace(nt=m.nt[:3]))
