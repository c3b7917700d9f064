"""Time integration: damped oscillator, stability limit, terminal speed (closed forms)."""

import math

import numpy as np
import pytest

from flexnet_fe.errors import NumericalError
from flexnet_fe.net.config import TractionNet
from flexnet_fe.net.state import Environment, initial_state, step_many
from flexnet_fe.net.timestep import choose_time_step, dt_critical_damped, spring_limit
from flexnet_fe.net.topology import build_traction, segment_damping

NO_LOADS = Environment(gravity=np.zeros(3), rho=0.0, wind=np.zeros(3), air=False)


M, K, L0 = 0.2, 500.0, 0.1  # node mass [kg], segment stiffness [N/m], rest length [m]
OMEGA = math.sqrt(2 * K / M)  # axial mode of two equal masses: ω² = K (1/m + 1/m)


def spinning_pair(make_chain, zeta, spin_ratio=0.05, delta=0.1):
    """Two equal masses on one rope, spinning about their centre at Ω = spin_ratio·ω so that the
    centrifugal load keeps the tension-only rope taut (without an external load a rope cannot
    oscillate about a taut state). Radial perturbation = delta × static stretch.

    Linearised radial motion of each mass (r = half length, h = r²θ̇ conserved):
    δr̈ + (2c/m) δṙ + (2K/m + 3Ω²) δr = 0 -> ω_r = √(ω² + 3Ω²), ζ_r = ζ ω / ω_r.
    Returns (model, ω_r, ζ_r)."""
    c = segment_damping(np.array([K]), np.array([M]), np.array([M]), zeta)[0]
    spin = spin_ratio * OMEGA
    r_e = K * L0 / (2 * K - M * spin**2)  # m r Ω² = K (2r - l0)
    r0 = r_e + delta * (2 * r_e - L0) / 2
    h = spin * r_e**2
    x0 = [[-r0, 0, 0], [r0, 0, 0]]
    v0 = [[0, -h / r0, 0], [0, h / r0, 0]]
    model = make_chain(x0, v0, [M, M], [[0, 1]], L0, K * L0, damping=c)
    w_r = math.sqrt(OMEGA**2 + 3 * spin**2)
    return model, w_r, zeta * OMEGA / w_r


def test_damped_two_mass_oscillator_log_decrement(make_chain):
    zeta = 0.05
    # reference: amplitude ratio per damped period exp(-2πζ/√(1-ζ²)) = 0.730 (log decrement 0.3146)
    assert math.exp(-2 * math.pi * zeta / math.sqrt(1 - zeta**2)) == pytest.approx(0.730, abs=5e-4)
    model, w_r, z_r = spinning_pair(make_chain, zeta)
    expected = math.exp(-2 * math.pi * z_r / math.sqrt(1 - z_r**2))  # 0.7309 with the spin's 3Ω²
    dt = 2 * math.pi / w_r / 2000
    st = initial_state(model)
    n = 6000  # 3 periods
    r = np.empty(n)
    for k in range(n):
        step_many(model, st, NO_LOADS, dt, 1)
        r[k] = np.linalg.norm(st.x[1] - st.x[0])
    u = r - r[-2000:].mean()
    peaks = [u[i] for i in range(1, n - 1) if u[i] > u[i - 1] and u[i] >= u[i + 1]]
    assert min(r) > L0  # the rope stayed taut: the law is linear over the whole run
    ratio = peaks[1] / peaks[0]
    # tolerance: lagged-velocity damping errs on ζ by O(ω dt) = 0.3 %; the 10 %-of-stretch
    # amplitude adds an O(δ/r) = 1e-3 nonlinearity; peak sampling at 2000 steps/period < 1e-5
    assert math.log(ratio) == pytest.approx(math.log(expected), rel=5e-3)


def clamped_mass(make_chain, zeta, stretch=1e-2, delta=1e-6):
    """A mass m between two ropes whose far ends are masses of 1e12 kg (fixed for all purposes),
    the ropes pre-stretched by ``stretch`` [m] and the mass displaced axially by ``delta`` [m]:
    m ẍ = -2K x - 2c ẋ, ω² = 2K/m, ζ_eff = c/(m ω) (taut throughout while |x| < stretch).
    Returns (model, ω, ζ_eff)."""
    big = 1e12
    c = segment_damping(np.array([K]), np.array([M]), np.array([big]), zeta)[0]
    d = L0 + stretch
    model = make_chain([[-d, 0, 0], [delta, 0, 0], [d, 0, 0]], np.zeros((3, 3)), [big, M, big],
                       [[0, 1], [1, 2]], L0, K * L0, damping=c)
    w = math.sqrt(2 * K / M)
    return model, w, c / (M * w)


@pytest.mark.parametrize("zeta", [0.0, 0.3, 0.9])
def test_damped_spring_stability_limit(make_chain, zeta):
    """ω dt_crit = 2(√(1+ζ²) − ζ) (Belytschko, Liu & Moran §6.2, central differences with the
    damping at the lagged velocity): just below the limit the motion decays or stays bounded,
    just above it grows."""
    model, w, z = clamped_mass(make_chain, zeta)
    dtc = 2 * (math.sqrt(1 + z**2) - z) / w
    assert dt_critical_damped(w, z) == pytest.approx(dtc, rel=1e-15)

    def max_excursion(dt, n=3000):
        st = initial_state(model)
        top = 0.0
        for _ in range(n):
            step_many(model, st, NO_LOADS, dt, 1, dtc)
            top = max(top, abs(st.x[1, 0]))
        return top

    # below the limit: bounded by the undamped scheme's amplification of the initial
    # displacement, δ √(1 + Ω²/(4 - Ω²)) with Ω = ω dt (= 5.0 δ at Ω = 1.96; damping only lowers it)
    om = 0.98 * dtc * w
    assert max_excursion(0.98 * dtc) <= 1e-6 * math.sqrt(1 + om**2 / (4 - om**2)) * (1 + 1e-9)
    # above the limit (1.1 dt_crit: the dominant root has |λ| >= 1.05 per step for these ζ) the
    # displacement grows past 100 δ (3000 steps could grow it by 1.3^3000; it saturates when
    # the ropes go slack at |x| ~ stretch = 1e4 δ: a tension-only rope does not overflow)
    assert max_excursion(1.1 * dtc) > 100 * 1e-6


def test_non_finite_state_is_reported(make_chain):
    model, w_r, _ = spinning_pair(make_chain, 0.0)
    st = initial_state(model)
    st.v[0, 0] = np.nan
    with pytest.raises(NumericalError, match=r"dt = .* dt_crit = "):
        step_many(model, st, NO_LOADS, 1e-4, 10, 2 / w_r)


def test_net_time_step_below_true_limit_and_forced_step_refused():
    cfg = TractionNet(edge_length=0.5, mesh_size=0.1, damping_ratio=0.2)
    model = build_traction(cfg)
    # true highest frequency of the taut net (axial stiffness of every segment): eigenvalues of
    # M^-1/2 K M^-1/2 assembled from the segments' 3×3 blocks K n nᵀ
    n = model.n_nodes
    Kg = np.zeros((3 * n, 3 * n))
    for (i, j), k in zip(model.springs, model.stiffness):
        e = model.x0[j] - model.x0[i]; e /= np.linalg.norm(e)
        b = k * np.outer(e, e)
        for a, bb, sgn in ((i, i, 1), (j, j, 1), (i, j, -1), (j, i, -1)):
            Kg[3 * a:3 * a + 3, 3 * bb:3 * bb + 3] += sgn * b
    minv = np.repeat(1 / np.sqrt(model.mass), 3)
    wmax = math.sqrt(np.linalg.eigvalsh(minv[:, None] * Kg * minv[None, :]).max())
    # ζ of that mode is at most the largest segment ζ (damping ∝ stiffness per element)
    zmax = float(np.max(model.damping * wmax / (2 * model.stiffness)))
    true_limit = 2 * (math.sqrt(1 + zmax**2) - zmax) / wmax
    lim = spring_limit(model)
    assert lim <= true_limit  # Irons' bound is conservative
    assert lim > 0.5 * true_limit  # ... but not absurdly so (it is 1/√2 for a square grid)
    ts = choose_time_step(model, model.x0, model.v0, 0.0, 0.5)
    assert ts.dt == pytest.approx(0.5 * lim) and ts.dt < true_limit
    with pytest.raises(NumericalError, match="exceeds"):
        choose_time_step(model, model.x0, model.v0, 0.0, 0.5, forced=1.01 * lim)


def test_falling_broadside_segment_terminal_speed(make_chain):
    """Two nodes on a horizontal segment falling in still air: drag ½ ρ 1.122 d l v² = m g
    gives v_t = √(2 m g / (ρ 1.122 d l)) (Eq. (5), (7) at α = 90°)."""
    m, g, rho, d, l = 1e-3, 9.81, 1.2, 4e-3, 0.1
    model = make_chain([[0, 0, 0], [l, 0, 0]], np.zeros((2, 3)), [m / 2, m / 2], [[0, 1]], l, 10.0,
                       diameter=d)
    env = Environment(gravity=np.array([0.0, -g, 0.0]), rho=rho, wind=np.zeros(3), air=True)
    vt = math.sqrt(2 * m * g / (rho * 1.122 * d * l))
    tau = vt / g  # time scale of the approach; after 8 τ the speed is within e^-16 of v_t
    st = initial_state(model)
    dt = tau / 2000
    step_many(model, st, env, dt, 16000)
    # the explicit update reaches the discrete fixed point of the same balance: exact up to round-off
    np.testing.assert_allclose(st.v[:, 1], -vt, rtol=1e-6)
    np.testing.assert_allclose(st.v[:, [0, 2]], 0.0, atol=1e-9)


@pytest.mark.parametrize("law", ["segment", "material"])
def test_subdivided_rope_dashpots_follow_the_damping_law(law):
    # Reference: Eq. (4) written out, c = 2 ζ √(μ K) with μ = m_i m_j/(m_i + m_j) of the segment's
    # end nodes and K = EA/l0 (independent of segment_damping). "segment": every segment of a bar
    # split into k = 3 has its own Eq. (4); "material": k times the Eq. (4) of its own values, the
    # k dashpots in series then give the viscosity of the whole bar. Unsplit (k = 1): both laws equal.
    zeta, k = 0.1, 3
    cfg = dict(edge_length=0.5, mesh_size=0.1, damping_ratio=zeta, damping_law=law)
    fine, whole = build_traction(TractionNet(subdivisions=k, **cfg)), build_traction(TractionNet(**cfg))
    i, j = fine.springs[:, 0], fine.springs[:, 1]
    eq4 = 2 * zeta * np.sqrt(fine.mass[i] * fine.mass[j] / (fine.mass[i] + fine.mass[j]) * fine.stiffness)
    np.testing.assert_allclose(fine.damping, eq4 * (k if law == "material" else 1), rtol=1e-13)
    other = build_traction(TractionNet(**{**cfg, "damping_law": "material" if law == "segment" else "segment"}))
    np.testing.assert_array_equal(whole.damping, other.damping)
