"""The production collision kernel (``collide.kernel.advance``) on single rope segments next to
the radar missile's wing_1 (B frame: fin plane z = 0, tip edge y = 0.51 m along x, faces z = ±3 mm).
Each test states its reference."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexnet_fe.collide import kernel as K
from flexnet_fe.collide import model as M
from flexnet_fe.contact.stiffness import crossed_cylinders_stiffness, line_stiffness
from flexnet_fe.missile.build import build_missile
from flexnet_fe.missile.config import MissileConfig

R = 2.25e-3  # rope radius [m]
H = 3.0e-3  # wing half-thickness [m]
TIP_Y = 0.1015 + 0.4085  # wing_1 tip edge, y_b [m]


def run(km, st, dt, t_end, chunk=1):
    """Advance to t_end in calls of ``chunk`` steps; returns (status, per-call contact impulse [N s])."""
    n = int(round(t_end / dt / chunk))
    imp = np.zeros(n)
    for k in range(n):
        status = K.advance(km, st, chunk, dt)
        imp[k] = st.acc[M.A_FCONTACT]
        if status != M.OK:
            return status, imp[:k + 1]
    return M.OK, imp


def test_hertz_impact_end_on(radar, scenes):
    # Reference: Hertz impact of a mass m on a rigid flat at speed v with F = K δ^1.5 (undamped):
    # δ_max = (5 m v²/(4K))^(2/5), contact time T = 2 δ_max/v · ∫₀¹ (1 − x^(5/2))^(−1/2) dx
    # = 2 δ_max/v · 0.4 Γ(0.4) Γ(0.5)/Γ(0.9). The capsule's end hemisphere hits the fin face end
    # on (the segment is perpendicular to the face, its far node held, no rope force), so the end
    # node is the mass. The 231 kg missile recoils: the reduced mass differs from m by < 1e-4.
    m, v, kc = 1.6e-3, 20.0, 1e9
    a = np.array([-1.8, 0.3, H + R + 1e-4])
    km, st = scenes.segment_scene(radar, a, a + [0, 0, 0.05], [0, 0, -v], [0, 0, 0], mass=m, k_contact=kc,
                                  free=(True, False))
    dmax = (5 * m * v * v / (4 * kc)) ** 0.4
    t_c = 2 * dmax / v * 0.4 * math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9)
    dt = t_c / 4000
    status, imp = run(km, st, dt, 1e-4 / v + 1.5 * t_c)
    assert status == M.OK
    assert st.acc[M.A_PEN] == pytest.approx(dmax, rel=2e-3)
    assert np.count_nonzero(imp) * dt == pytest.approx(t_c, rel=2e-3)
    assert st.v[0, 2] == pytest.approx(v, rel=2e-3)  # elastic: it leaves at the impact speed


def _energy_drift(km, st, radar, scenes, dt, n_us):
    """Advance ``st`` n_us µs in 1 µs calls of step dt [s]; returns (largest |E − E0|, final
    E − E0) / E0 of the total energy (kinetic + elastic + contact stored + dissipated)."""
    e0 = scenes.total_energy(km, st, radar)
    worst, final = 0.0, 0.0
    for _ in range(n_us):
        assert K.advance(km, st, int(round(1e-6 / dt)), dt) == M.OK
        final = scenes.total_energy(km, st, radar) - e0
        worst = max(worst, abs(final))
    return worst / e0, final / e0


@pytest.mark.parametrize("law", ["segment", "line"])
@pytest.mark.parametrize("where", ["face", "edge"])
def test_energy_closes_and_is_never_created(radar, scenes, where, law):
    # Reference: conservation of energy. A rope segment (rope springs on, the paper's rope
    # EA/l0) dropped flat on the fin face — tilted 2° so its ends land at different times — or
    # thrown broadside at the tip edge, at 50 m/s, with Lankarani–Nikravesh damping (e = 0.5)
    # and friction μ = 0.2. Kinetic + rope elastic + contact stored + dissipated must stay equal
    # to the initial kinetic energy: the error of symplectic Euler is O(dt) and bounded, so it
    # must shrink when dt is halved and never exceed 0.5 % of the energy; after the contact the
    # balance must not have grown (no energy created). Both contact laws (line: k_l from Eq. (30) for
    # this contact, points r/4 to r/2 apart; tests/collide/test_line_contact.py).
    v = 50.0
    if where == "face":
        a = np.array([-1.75, 0.3, H + R + 1e-4])
        b = a + 0.05 * np.array([-math.cos(0.035), 0.0, math.sin(0.035)])
        va = vb = [0.0, 0.0, -v]
    else:
        a = np.array([-2.0, TIP_Y + H + R + 1e-4, -0.025])
        b = a + [0.0, 0.0, 0.05]
        va = vb = [0.0, -v, 0.0]
    errs = []
    for dt in (2e-8, 1e-8):
        line = dict(line_h=R / 4, k_line=line_stiffness(6.7e8, R + H)) if law == "line" else {}
        km, st = scenes.segment_scene(radar, a, b, va, vb, k=318.0, c=0.01, k_contact=6.7e8,
                                      damping="lankarani_nikravesh", mu=0.2, **line)
        errs.append(_energy_drift(km, st, radar, scenes, dt, 200))
        assert st.acc[M.A_DISS_CONTACT] > 0 and st.acc[M.A_FCONTACT] == 0.0  # it hit, and it has left
    assert errs[0][0] < 5e-3 and errs[1][0] < 0.6 * errs[0][0]
    assert errs[1][1] < 1e-3 * errs[0][0] + 1e-12 or errs[1][1] < 0.6 * abs(errs[0][1])
    assert max(errs[0][1], errs[1][1]) < 5e-4  # after the contact: nothing created beyond the step error


def test_rope_in_the_fin_body_corner_conserves_energy(radar, scenes):
    # Reference: conservation of energy, as above. A rope segment (across the wing_1 plane, just
    # above the body) moving aft at 50 m/s and settling on the body slides into the corner of the
    # swept (55°) leading edge and the body. There its closest fin-core point lies inside the
    # body's radius (the core's root is extended into the body) until the capsule is ≈ 2 mm deep
    # in the rounded edge; the former rule dropped the fin pair there, so the fin potential
    # switched on at a finite penetration and the balance gained 22 × the initial kinetic energy
    # at every dt (2e-8, 1e-8, 5e-9 s). With both potentials acting, the error must be the
    # integrator's: below 0.5 %, halving with dt, nothing left created after the contact.
    a = np.array([-1.3 + 0.006, 0.1015 + R + 1e-4, -0.025])
    errs = []
    for dt in (2e-8, 1e-8):
        km, st = scenes.segment_scene(radar, a, a + [0.0, 0.0, 0.05], [-50.0, -2.0, 0.0], [-50.0, -2.0, 0.0],
                                      k=318.0, c=0.01, k_contact=6.7e8, damping="lankarani_nikravesh", mu=0.2)
        errs.append(_energy_drift(km, st, radar, scenes, dt, 300))
        assert st.fin_w[0] > 0.0 and st.acc[M.A_FCONTACT] == 0.0  # wing_1 was hit, and the rope has left
    assert errs[0][0] < 5e-3 and errs[1][0] < 0.6 * errs[0][0]
    assert max(errs[0][1], errs[1][1]) < 5e-4


TIP_V, TIP_M = 500.0, 1.6e-3  # approach speed [m/s] and node mass [kg] of the tip-edge impact


def _tip_edge_impact(radar, scenes, slide=0.0, mu=0.0):
    """A rope segment (two 1.6 g nodes) straddling wing_1's plane meets the tip edge at 500 m/s
    (sliding at ``slide`` [m/s] along x_b), the cases' contact (E_t = 100 GPa, Eq. (30)), LN
    damping, friction ``mu``; run for 20 µs. Returns (state, kernel status, per-call impulses)."""
    kc = crossed_cylinders_stiffness(R, H, 1e11 / 0.91)
    a = np.array([-2.0, TIP_Y + H + R + 1e-4, -0.025])
    v0 = [slide, -TIP_V, 0]
    km, st = scenes.segment_scene(radar, a, a + [0, 0, 0.05], v0, v0, mass=TIP_M, k=318.0, k_contact=kc,
                                  damping="lankarani_nikravesh", mu=mu)
    status, imp = run(km, st, 4e-9, 2e-5, chunk=50)
    return st, status, imp


def test_segment_swept_through_an_edge_at_500_mps_is_stopped(radar, scenes):
    # Reference: momentum and the kernel's tunnelling rule. A rope segment (two 1.6 g nodes)
    # straddling the fin plane meets the tip edge at 500 m/s. With the cases' contact (E_t =
    # 100 GPa, Eq. (30): K = 4/3 E/(1−ν²) sqrt(sqrt(r h/2))) it is stopped and thrown back: its
    # velocity reverses and the contact impulse is m_tot (v_in + v_out) to the step error.
    v, m = TIP_V, TIP_M
    st, status, imp = _tip_edge_impact(radar, scenes)
    assert status == M.OK
    v_out = st.v[:, 1].mean()
    assert v_out > 0.0  # moving away from the fin again
    assert imp.sum() == pytest.approx(2 * m * (v + v_out), rel=1e-3)
    assert st.acc[M.A_PEN_RATIO] < 1.0  # its centre line never reached the core


def test_per_part_impulse_sums_against_momentum_and_coulomb(radar, scenes):
    # References: (a) momentum — the 500 m/s tip-edge impact of the test above, μ = 0: the normal
    # keeps its direction (+y_b, the segment crosses the fin plane square to the rounded tip edge),
    # so wing_1's scalar sum Σ|F_n| dt is the segment's momentum change m_tot (v_in + v_out) to the
    # same 1e-3; nothing is booked on the body or as friction. (b) Eq. (32) at full slip — the same
    # impact while the segment slides at 400 m/s along the edge (x_b), μ = 0.2: friction takes at
    # most μ × 2 m_tot × 500 ≈ 200 m/s of the slide, so |v_t| stays ≫ v_reg = 0.1 m/s and
    # tanh(|v_t|/v_reg) = 1 in double precision: Σ|F_t| dt = μ Σ|F_n| dt to round-off (1e-12).
    v, m = TIP_V, TIP_M
    st, status, _ = _tip_edge_impact(radar, scenes)
    assert status == M.OK
    v_out = st.v[:, 1].mean()
    assert st.part_imp[1, 0] == pytest.approx(2 * m * (v + v_out), rel=1e-3)  # row 1 + 0: wing_1
    assert st.part_imp[0].sum() == 0.0 and st.part_imp[2:].sum() == 0.0 and st.part_imp[1, 1] == 0.0
    st, status, _ = _tip_edge_impact(radar, scenes, slide=-400.0, mu=0.2)
    assert status == M.OK
    assert st.v[:, 0].mean() < -150.0  # still sliding when the contact ended
    assert st.part_imp[1, 0] > 1.0
    assert st.part_imp[1, 1] == pytest.approx(0.2 * st.part_imp[1, 0], rel=1e-12)


def test_soft_contact_tunnels_and_stops_the_run(radar, scenes):
    # Reference: the tunnelling rule. With the paper's 1 MPa rope as its own transverse modulus
    # (K ≈ 6.7e4 N/m^1.5) the same segment's centre line reaches the fin core: the kernel stops
    # with TUNNEL; allowed, the run finishes and books the skipped impulse (m_eff × relative speed).
    v, m = 500.0, 1.6e-3
    kc = crossed_cylinders_stiffness(R, H, 1e6 / 0.91)
    a = np.array([-2.0, TIP_Y + H + R + 1e-4, -0.025])
    km, st = scenes.segment_scene(radar, a, a + [0, 0, 0.05], [0, -v, 0], [0, -v, 0], mass=m, k_contact=kc)
    status, _ = run(km, st, 4e-9, 4e-5, chunk=50)
    assert status == M.TUNNEL
    assert int(st.acc[M.A_TUN_PART]) == 2  # wing_1
    km, st = scenes.segment_scene(radar, a, a + [0, 0, 0.05], [0, -v, 0], [0, -v, 0], mass=m, k_contact=kc,
                                  allow_tunnel=True)
    status, _ = run(km, st, 4e-9, 4e-5, chunk=50)
    assert status == M.OK and st.acc[M.A_CROSS] > 0
    assert 0.5 * m * v < st.acc[M.A_SKIPPED] <= m * v  # m_eff = (1 − s) m + s m = m


def test_rope_breaks_at_its_breaking_load(radar, scenes):
    # Reference: the failure rule and energy. A segment far from the missile, one end held, the
    # other pulled away at 1 m/s: it must break when its elastic tension k·stretch reaches the
    # breaking load (here 10 N, stretch 10 mm), within one step's growth k v dt; the energy it
    # stored (½ k s²) is booked as released, and kinetic + elastic + released stays constant.
    k, s_b, v, dt = 1000.0, 0.01, 1.0, 1e-6
    a = np.array([1.0, 0.0, 0.0])
    # 1 kg end: it would stretch the rope to v/ω = 31.6 mm > 10 mm, so it must break
    km, st = scenes.segment_scene(radar, a, a + [0.05, 0, 0], [0, 0, 0], [v, 0, 0], mass=1.0, k=k,
                                  free=(False, True), break_stretch=s_b)
    e0 = scenes.total_energy(km, st, radar)
    stretch = 0.0
    for _ in range(20000):
        if not st.alive[0]:
            break
        stretch = float(np.linalg.norm(st.x[1] - st.x[0])) - 0.05
        assert K.advance(km, st, 1, dt) == M.OK
    assert k * stretch == pytest.approx(k * s_b, abs=k * v * dt)
    assert st.acc[M.A_NBROKEN] == 1
    assert st.acc[M.A_BROKEN] == pytest.approx(0.5 * k * stretch ** 2, rel=1e-3)
    assert scenes.total_energy(km, st, radar) == pytest.approx(e0, rel=1e-3)


def test_rope_that_cannot_push_books_its_spring_energy_as_damping(radar, scenes):
    # Reference: conservation of energy, far from the missile (no contact). A segment stretched by
    # 1 mm (K = 1000 N/m, ½ K s² = 0.5 mJ) whose free 1 g end moves towards the held end at 1 m/s
    # with a dashpot c = 10 N s/m: K s + c l̇ = −9 N < 0, so the rope (which cannot push) carries
    # no force and the end flies on at 1 m/s while the spring relaxes. The spring's 0.5 mJ is
    # taken by the dashpot (T − K s = −K s): kinetic + elastic + rope damping must stay at its
    # initial 1 mJ up to the step error: the booked dissipation is the left sum Σ K s_n |v| dt =
    # ½ K s0² + ½ K s0 |v| dt (s_n = s0 − n |v| dt), first order in dt. (A balance that dropped
    # the dashpot's share lost half the energy at any dt.)
    a = np.array([1.0, 0.0, 0.0])
    k, s0, v = 1000.0, 1e-3, 1.0
    for dt in (1e-6, 5e-7):
        km, st = scenes.segment_scene(radar, a, a + [0.05 + s0, 0, 0], [0, 0, 0], [-v, 0, 0], mass=1e-3, k=k,
                                      c=10.0, rest=0.05, free=(False, True))
        e0 = scenes.total_energy(km, st, radar)
        assert e0 == pytest.approx(1e-3, rel=1e-12)
        assert K.advance(km, st, int(round(2e-3 / dt)), dt) == M.OK
        step_error = 0.5 * k * s0 * v * dt
        assert st.v[1, 0] == -v and st.acc[M.A_DISS_ROPE] == pytest.approx(0.5 * k * s0 ** 2 + step_error, rel=1e-6)
        assert scenes.total_energy(km, st, radar) - e0 == pytest.approx(step_error, rel=1e-3)


def test_broad_phase_never_drops_a_touching_pair(radar, scenes):
    # Reference: the exact stored energy Σ U(δ) over ALL (segment, part) pairs, computed here with
    # no broad phase (every fin's core and the body, ``missile.shapes``). The kernel's culls
    # (bounding cylinder, body-axis distance, fin mid-plane and edge half-spaces) must only skip pairs that
    # cannot touch, or the stored energy jumps when a pair enters the cull: the kernel's contact
    # energy must equal the exact one for every segment. 4 000 random capsules (3–50 mm, any
    # direction) near the wing and rudder roots, edges and tips and the body.
    from flexnet_fe.contact.law import contact_potential
    from flexnet_fe.missile.shapes import pack_shapes, segment_body_closest, segment_core_closest
    sh = pack_shapes(radar)
    rng = np.random.default_rng(7)
    ref_pts = np.array([[-1.3, 0.1015, 0.0], [-1.75, 0.3, 0.0], [-2.0, TIP_Y, 0.0], [-1.9, 0.1015, 0.0],
                        [-3.24, 0.0, 0.1015], [-3.5, 0.0, -0.2], [-0.5, 0.07, 0.07]])
    km, st = scenes.segment_scene(radar, ref_pts[0], ref_pts[1], [0, 0, 0], [0, 0, 0], k_contact=6.7e8)
    wk = K._work(km, 2)
    n_touch = 0
    for _ in range(3000):
        c = ref_pts[rng.integers(len(ref_pts))] + rng.normal(scale=6e-3, size=3)
        u = rng.normal(size=3)
        half = 0.5 * rng.uniform(3e-3, 0.05) * u / np.linalg.norm(u)
        a, b = c - half, c + half
        st.x[0], st.x[1] = a, b  # B = W in this scene
        exact, crossing = 0.0, False
        d, *_ = segment_body_closest(a, b, sh.prof_kind, sh.prof_data, sh.prof_part)
        crossing |= d <= 0.0
        exact += contact_potential(R - d, km.k_body, km.exponent)
        for fi in range(len(sh.fin_half_thickness)):
            dist, _, _, _, crossed = segment_core_closest(a, b, sh.fin_origin[fi], sh.fin_axes[fi], sh.fin_poly[fi])
            crossing |= crossed
            exact += contact_potential(R + sh.fin_half_thickness[fi] - dist, km.k_fin, km.exponent)
        if crossing:
            continue
        n_touch += exact > 0.0
        assert K.energies(km, st)[2] == pytest.approx(exact, rel=1e-12, abs=1e-300)
        if exact > 0.0:  # the step's candidate list (``_clearance`` ≤ 0 ⇒ candidate) must keep every touching pair
            assert K._clearance(km.bbox, km.rope_radius, wk.fin_pl, wk.fin_rh, km.nose_cones, a, b, K.CANDIDATE_SKIN) <= 0.0
    assert n_touch > 300  # the sample does exercise touching pairs


def test_rounded_tip_corner_is_met_later_by_its_offset(radar, scenes):
    # Reference: geometry of a corner of interior angle θ rounded to radius ρ (missile.planform):
    # along the outward bisector the arc lies ρ/sin(θ/2) − ρ inside the sharp corner (the middle
    # chord vertex sits on the arc). A rope segment straddling wing_1's plane, moving at 50 m/s
    # along that bisector towards the tip leading-edge corner, must first touch later by
    # (ρ/sin(θ/2) − ρ)/v than at the sharp corner (first touch within the 0.1 µs sampling), and
    # both runs must close their energy to the step error, as above.
    rho, v, dt = 0.01, 50.0, 1e-8
    rounded = build_missile(MissileConfig(preset="radar", wings={"tip_corner_radius": rho}))
    fin = radar.fin("wing_1")
    uv = np.asarray(fin.uv)
    d1, d2 = uv[1] - uv[2], uv[3] - uv[2]
    d1, d2 = d1 / np.linalg.norm(d1), d2 / np.linalg.norm(d2)
    theta = math.acos(d1 @ d2)
    out = -(d1 + d2) / np.linalg.norm(d1 + d2)
    out_b = out[0] * fin.e1 + out[1] * fin.e2
    start = fin.corners[2] + (R + H + 2e-3) * out_b
    first = []
    for mis in (radar, rounded):
        km, st = scenes.segment_scene(mis, start - 0.025 * fin.n, start + 0.025 * fin.n, -v * out_b, -v * out_b,
                                      k=318.0, c=0.01, k_contact=6.7e8, damping="lankarani_nikravesh", mu=0.2)
        e0 = scenes.total_energy(km, st, mis)
        for call in range(3000):
            assert K.advance(km, st, 10, dt) == M.OK
            if st.acc[M.A_FCONTACT] > 0.0:
                first.append(call * 10 * dt)
                break
        for _ in range(3000):
            assert K.advance(km, st, 10, dt) == M.OK
        assert st.acc[M.A_FCONTACT] == 0.0 and st.fin_w[0] > 0.0  # it hit wing_1 and has left
        assert abs(scenes.total_energy(km, st, mis) - e0) < 5e-3 * e0
    expected = (rho / math.sin(theta / 2) - rho) / v
    assert first[1] - first[0] == pytest.approx(expected, abs=2 * 10 * dt)


def test_fin_slot_records_the_pressing_chord_not_the_rest_length(radar, scenes):
    # Reference: geometry. The edge-resolution guard (simulate.edge_resolution) must judge a rope
    # piece by the length it has while it presses — the paper's 1 MPa rope stretches its pieces
    # ~10× at the fins (docs/collide_convergence.md, thirteenth pass) — not by its rest length.
    # A segment whose two ends are held lies across wing_1's face, 0.1 mm deep, with a rest
    # length a fifth of its chord: the impulse-weighted chord of its fin slot must be the held
    # chord L to round-off, whatever the force history.
    from flexnet_fe.collide.simulate import _take_fin_events
    L = 0.03
    a = np.array([-1.8, 0.3, H + R - 1e-4])
    km, st = scenes.segment_scene(radar, a, a + [0.0, L, 0.0], [0, 0, 0], [0, 0, 0], free=(False, False),
                                  k=318.0, rest=L / 5, k_contact=1e9)
    assert K.advance(km, st, 20, 1e-8) == M.OK
    fin, _, imp, seg, chord = _take_fin_events(km, st)
    assert list(fin) == [0] and list(seg) == [0] and np.linalg.norm(imp) > 0.0
    assert chord[0] == pytest.approx(L, rel=1e-12)
    assert st.fin_len[0] == 0.0 and st.fin_w[0] == 0.0  # the slot is cleared for the next interval


def test_fin_gaps_bound_the_gap_to_the_nearest_fin(radar, scenes):
    # Reference: geometry. A segment 4 mm clear of wing_1's face, over its interior and parallel
    # to it: its distance to the core is H + R + 4 mm, so the gap is 4 mm, and the bound
    # (distance to the mid-plane) is exact there; moved 1 mm into the face the gap is −1 mm.
    # A broken segment has no gap (inf).
    for lift in (4e-3, -1e-3):
        a = np.array([-1.8, 0.3, H + R + lift])
        km, st = scenes.segment_scene(radar, a, a + [0.0, 0.03, 0.0], [0, 0, 0], [0, 0, 0])
        assert K.fin_gaps(km, st)[0] == pytest.approx(lift, abs=1e-12)
    st.alive[0] = False
    assert K.fin_gaps(km, st)[0] == np.inf


def test_fin_gaps_skip_rule_gives_the_minimum_over_every_fin(radar, scenes):
    # Reference: a second model, every fin's _fin_gap evaluated and the minimum taken. fin_gaps
    # skips a fin whose mid-plane term is not below the smallest gap so far; the minimum must be
    # the same to the last bit, for segments anywhere around the fins (both sides of their planes,
    # crossing them, near and far).
    rng = np.random.default_rng(7)
    lo, hi = np.array([-3.6, -0.45, -0.45]), np.array([-1.2, 0.45, 0.45])
    for _ in range(300):
        a = lo + (hi - lo) * rng.random(3)
        b = a + rng.normal(scale=0.02, size=3)
        km, st = scenes.segment_scene(radar, a, b, [0, 0, 0], [0, 0, 0])
        pl, rh = K._fin_half_spaces(km), km.fin_half + km.rope_radius
        ref = min(K._fin_gap(pl, fi, rh[fi], st.x[0] - st.mx + km.cg_b, st.x[1] - st.mx + km.cg_b)
                  for fi in range(km.fin_half.shape[0]))
        assert K.fin_gaps(km, st)[0] == ref
