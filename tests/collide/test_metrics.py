"""SAE J211-1 CFC filter and window-free collision metrics (issue 9 §5).

References: SAE J211-1 (2007) Appendix C (filter equations, 3 dB frequencies 100/300/1000/1650 Hz
for CFC 60/180/600/1000, sampling ≥ 10 × CFC) and its response corridor (±0.5 dB in the pass
band up to F_H = CFC, +0.5/−1 dB at F_H, +0.5/−4 dB at F_N, at most −9 dB/octave from F_N on);
scipy's Butterworth design as a second implementation; closed forms (bilinear transform of the
2-pole Butterworth, the fourth-derivative expansion of the filtered peak); conservation of
momentum (Δv = impulse / m).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import signal

from flexnet_fe.collide.metrics import (CFC_CLASSES, DESIGN_FACTOR, FinContacts, MetricsInputError, MissileHistory,
                                        cfc_coefficients, cfc_filter, cfc_gain, collision_metrics, contact_window,
                                        filtered_peak, fin_impulses, settle_samples)

DT = 1e-5                     # the collide stage's output interval [s] (100 kHz)
F_3DB = {60: 100.0, 180: 300.0, 600: 1000.0, 1000: 1650.0}   # J211-1 "3 dB limit frequency" [Hz]


def _roundoff(cfc, dt=DT):
    """Round-off level of the direct-form recursion: its DC gain Σb/Σa divides by Σa ≈ 4 ω_a²
    (ω_a = tan(π f_d T) ≈ 4e-3 for CFC 60 at 100 kHz), so relative errors of ~10 ε / ω_a²."""
    return 10 * np.finfo(float).eps / math.tan(math.pi * DESIGN_FACTOR * cfc * dt) ** 2


def _db(g):
    return 20.0 * np.log10(g)


def _sine_response(cfc, f, dt=DT):
    """(gain, phase [rad]) of cfc_filter on a sine of f [Hz], fitted over the steady middle."""
    n_set = settle_samples(cfc, dt)
    n = int(max(6.0 / (f * dt), 4 * n_set))          # ≥ 6 periods, ≥ 2 settling lengths each side
    t = np.arange(n) * dt
    y = cfc_filter(t, np.sin(2 * np.pi * f * t), cfc)
    mid = slice(n_set, n - n_set)                      # past the end transients of the sine's ends
    basis = np.column_stack([np.sin(2 * np.pi * f * t[mid]), np.cos(2 * np.pi * f * t[mid])])
    (s, c), *_ = np.linalg.lstsq(basis, y[mid], rcond=None)
    return math.hypot(s, c), math.atan2(c, s)


@pytest.mark.parametrize("cfc", CFC_CLASSES)
def test_coefficients_are_the_bilinear_butterworth(cfc):
    # Second implementation: scipy's 2-pole Butterworth (bilinear, pre-warped) at 2.0775·CFC.
    b, a = cfc_coefficients(cfc, DT)
    b_ref, a_ref = signal.butter(2, DESIGN_FACTOR * cfc, fs=1.0 / DT)
    assert np.allclose(b, b_ref, rtol=1e-12, atol=0) and np.allclose(a, a_ref, rtol=1e-12, atol=1e-15)
    # 2.0775 = (5/3) / (√2 − 1)^(1/4): the design factor that puts the 4-pole −3 dB at 5/3 CFC.
    assert abs(DESIGN_FACTOR - (5 / 3) / (math.sqrt(2) - 1) ** 0.25) < 1e-5


@pytest.mark.parametrize("cfc", CFC_CLASSES)
def test_frequency_response_j211_points_and_zero_phase(cfc):
    # Measured gain and phase of the implementation (padding, forward-backward) against the
    # closed form 1/(1 + (tan(πfT)/tan(πf_dT))⁴); a steady-state fit is exact to round-off.
    f_h, f_n = float(cfc), F_3DB[cfc]
    for f in (0.1 * f_h, f_h, f_n, 2 * f_n):
        g, phase = _sine_response(cfc, f)
        assert abs(_db(g) - _db(cfc_gain(f, cfc, DT))) < 1e-6, f
        assert abs(phase) < 1e-7, (f, phase)           # zero phase: forward-backward cancels the lag
        if f == f_n:                                    # J211-1: −3 dB at the class's stated frequency
            assert abs(_db(g) + 3.0) < 0.5, _db(g)
        if f == f_h:                                    # corridor at F_H: +0.5 / −1 dB (and ±0.5 dB)
            assert -0.5 <= _db(g) <= 0.5, _db(g)
    # Dense check of the corridor on the closed form just verified against the implementation.
    f = np.geomspace(0.1, f_h, 400)
    assert np.all(np.abs(_db(cfc_gain(f, cfc, DT))) <= 0.5)                      # pass band ±0.5 dB
    assert -4.0 <= _db(cfc_gain(f_n, cfc, DT)) <= 0.5                            # at F_N: +0.5/−4 dB
    f = np.geomspace(f_n, 8 * f_n, 200)
    assert np.all(_db(cfc_gain(f, cfc, DT)) <= 0.5 - 9.0 * np.log2(f / f_n))     # ≤ −9 dB/octave line


def test_dc_gain_is_one():
    t = np.arange(3000) * DT
    for cfc in CFC_CLASSES:
        y = cfc_filter(t, np.full((t.size, 2), [3.0, -7.5]), cfc)
        assert np.max(np.abs(y - [3.0, -7.5])) < _roundoff(cfc) * 7.5


def test_symmetric_pulse_stays_centred():
    # Zero phase: a pulse symmetric about t_c, in a record symmetric about t_c, stays symmetric
    # (to round-off) and keeps its centroid at t_c; a one-way 2-pole pass would delay it.
    n = 4001
    t = np.arange(n) * DT
    tc = t[n // 2]
    x = np.exp(-0.5 * ((t - tc) / 1e-3) ** 2) + np.where(np.abs(t - tc) < 2e-4, 1.0, 0.0)
    x = 0.5 * (x + x[::-1])                            # symmetric to the bit (t − tc rounds unevenly)
    for cfc in CFC_CLASSES:
        y = cfc_filter(t, x, cfc)
        assert np.max(np.abs(y - y[::-1])) < 1e-12
        assert abs(np.sum(t * y) / np.sum(y) - tc) < 1e-12
        assert int(np.argmax(y)) == n // 2
    b, a = cfc_coefficients(180, DT)
    y1 = signal.lfilter(b, a, x)                        # the one-way pass: visibly late
    assert np.sum(t * y1) / np.sum(y1) - tc > 1e-4


@pytest.mark.parametrize("cfc", [600, 1000])
def test_half_sine_much_longer_than_the_filter_keeps_its_peak(cfc):
    # A half-sine A sin(πt/T) of T = 10 ms. Near its crest the filter acts on it as the gain at
    # f = 1/(2T): 1/(1 + r⁴) = 1 − ρ + ρ² …, ρ = r⁴ = (tan(π T_s/(2T)) / tan(π f_d T_s))⁴ (closed
    # form, T_s the sampling interval). Neglected: ρ² and the ringing from the pulse's end kinks,
    # exp(−ζ ω_d T/2) ≤ e^−27, plus round-off — so |loss − ρ| ≤ 10 ρ² + round-off.
    tau = 10e-3
    t = np.arange(int(0.03 / DT) + 1) * DT
    x = np.where((t > 0.01) & (t < 0.01 + tau), np.sin(np.pi * (t - 0.01) / tau), 0.0)
    loss = 1.0 - cfc_filter(t, x, cfc).max()
    rho = (math.tan(math.pi * DT / (2 * tau)) / math.tan(math.pi * DESIGN_FACTOR * cfc * DT)) ** 4
    assert loss < 3e-6
    assert abs(loss - rho) < 10 * rho ** 2 + _roundoff(cfc), (loss, rho)


def _history(t, v, a_body, force, g=(0.0, 0.0, 0.0), mass=100.0):
    return MissileHistory(t, v, a_body, force, np.asarray(g, dtype=float), mass)


def _rigid_body_run(force_fine, dt_fine, k_out, mass, g, omega):
    """Reference rigid-body integration at dt_fine: v += (F/m + g) dt (world), body axes rotating
    at a constant rate omega [rad/s] about z; outputs every k_out steps in the collide layout."""
    n = force_fine.shape[0]
    ang = omega * dt_fine * np.arange(n)
    c, s = np.cos(ang), np.sin(ang)
    f_body = np.column_stack([c * force_fine[:, 0] + s * force_fine[:, 1],
                              -s * force_fine[:, 0] + c * force_fine[:, 1], force_fine[:, 2]])  # Rᵀ F
    v = np.array([3.0, -2.0, 500.0]) + np.cumsum(force_fine / mass + g, axis=0) * dt_fine
    v = np.vstack([[3.0, -2.0, 500.0], v])[::k_out]
    delta = k_out * dt_fine
    a_body = np.vstack([np.zeros(3), f_body.reshape(-1, k_out, 3).sum(axis=1) * dt_fine / (mass * delta)])
    f_mag = np.concatenate([[0.0], np.linalg.norm(force_fine, axis=1).reshape(-1, k_out).mean(axis=1)])
    t = np.arange(v.shape[0]) * delta
    return _history(t, v, a_body, f_mag, g, mass), f_body


def _strike_force(dt_fine, seed=1, pre=0.011, post=0.011, strike_ns=2e-2):
    """(contact force [N] at dt_fine, shape (n, 3); Σ|J| of the strikes [N s]): ``pre`` [s] at rest,
    an 8 ms half-sine (peak 1 kN along −z, 0.3 kN along x) with 10 smooth bumps (Gaussians of
    σ = 0.2 ms, ~300 N, random directions) and 40 rope strikes of 1 µs each (impulse ``strike_ns``
    per component, random directions; 0 for a smooth pulse), then ``post`` [s] at rest."""
    rng = np.random.default_rng(seed)
    n = int(round((pre + 0.008 + post) / dt_fine / 10)) * 10
    t = np.arange(n) * dt_fine
    half = np.where((t > pre) & (t < pre + 0.008), np.sin(np.pi * (t - pre) / 0.008), 0.0)
    force = np.outer(half, [300.0, 0.0, -1000.0])
    for tc in rng.uniform(pre + 0.001, pre + 0.007, 10):
        force += np.outer(np.exp(-0.5 * ((t - tc) / 2e-4) ** 2), rng.normal(size=3) * 300.0)
    strikes = rng.normal(size=(40, 3)) * strike_ns
    for k, j in zip(rng.integers(int((pre + 0.0005) / dt_fine), int((pre + 0.0075) / dt_fine), 40), strikes):
        force[k] += j / dt_fine
    return force, float(np.linalg.norm(strikes, axis=1).sum())


def test_delta_v_is_impulse_over_mass_and_filtered_integral_keeps_it():
    # Momentum: Δv (velocities, gravity removed) = Σ F dt / m; body-axis Δv = Σ Rᵀ F dt / m; both
    # to round-off. The filter (DC gain 1) keeps ∫ a_f dt = Δv to round-off when the record has
    # ≥ settle_samples of rest before and after the contact (25 ms each side; CFC 180 needs 24.4).
    dt_fine, mass, g = 1e-6, 120.0, np.array([0.0, -9.81, 0.0])
    force, _ = _strike_force(dt_fine, pre=0.025, post=0.025)
    h, f_body = _rigid_body_run(force, dt_fine, 10, mass, g, omega=20.0)
    fins = FinContacts(["a"], np.zeros(0, int), np.zeros((0, 3)), 1e-5)
    m = collision_metrics(h, fins, cfc=180)
    j = force.sum(axis=0) * dt_fine
    assert np.allclose(m["delta_v_world_mps"], j / mass, rtol=0, atol=1e-12 * np.linalg.norm(h.vel_world_mps[0]))
    assert np.allclose(m["delta_v_axis_mps"], f_body.sum(axis=0) * dt_fine / mass, rtol=1e-12, atol=1e-15)
    assert abs(m["impulse_ns"] - np.linalg.norm(j)) < 1e-9 * np.linalg.norm(j)
    assert abs(m["dv_over_v"] - np.linalg.norm(j) / mass / np.linalg.norm(h.vel_world_mps[0])) < 1e-12
    assert settle_samples(180, 1e-5) * 1e-5 < 0.025
    assert m["filter_dv_loss_rel"] < _roundoff(180)
    assert m["warnings"] == []


@pytest.mark.parametrize("strike_ns", [0.0, 2e-2])
def test_filtered_peak_does_not_depend_on_the_output_interval(strike_ns):
    # One fine-step run (1 µs) written at Δ = 10 µs and at Δ = 5 µs.
    # Smooth pulse: the filtered peak moves only by (a) the bilinear warping, ≤ (1/3)(2π F_N Δ)² in
    # the pass band, (b) the box average over Δ, (2π f Δ)²/24, (c) the peak falling between samples,
    # ≤ (2π F_N Δ/2)²/2: in all ≲ 0.5 (2π F_N Δ)² at each Δ; bound e2 = (2π F_N Δ)² at Δ = 10 µs.
    # Rope strikes shorter than Δ: each enters as its impulse J_i but placed at its interval's
    # midpoint, up to Δ/2 (resp. Δ/4) away: the peak moves by at most (3Δ/4) max|h'| Σ|J_i| / m with
    # max|h'| ≤ ∫ 2π|f| |H(f)| df = π² f_d² (f_d = 2.0775 CFC): bound e1 = (3Δ/4) π² f_d² Σ|J_i| / (m peak).
    # The raw one-interval peak of a strike reads J/(mΔ): it roughly doubles.
    dt_fine, mass, g, delta = 1e-6, 120.0, np.zeros(3), 1e-5
    force, sum_j = _strike_force(dt_fine, seed=2, strike_ns=strike_ns)
    fins = FinContacts(["a"], np.zeros(0, int), np.zeros((0, 3)), 1e-5)
    for cfc in CFC_CLASSES:
        coarse = collision_metrics(_rigid_body_run(force, dt_fine, 10, mass, g, 0.0)[0], fins, cfc=cfc)
        fine = collision_metrics(_rigid_body_run(force, dt_fine, 5, mass, g, 0.0)[0], fins, cfc=cfc)
        e2 = (2 * math.pi * F_3DB[cfc] * delta) ** 2
        e1 = 0.75 * delta * (math.pi * DESIGN_FACTOR * cfc) ** 2 * sum_j / (mass * coarse["peak_accel_mps2"])
        rel = abs(fine["peak_accel_mps2"] / coarse["peak_accel_mps2"] - 1.0)
        assert rel < e2 + e1, (cfc, rel, e2, e1)
        assert abs(fine["peak_accel_time_s"] - coarse["peak_accel_time_s"]) < 1e-4
        raw_ratio = fine["peak_accel_raw_mps2"] / coarse["peak_accel_raw_mps2"]
        assert raw_ratio > 1.5 if strike_ns else abs(raw_ratio - 1.0) < 0.01


def test_step_in_velocity_keeps_delta_v_after_filtering():
    # A velocity step (all the impulse in one interval) mid-record, with settle_samples of rest on
    # each side (73 ms for CFC 60): ∫ a_f dt = Δv to round-off (the filter's DC gain is 1).
    n_set = settle_samples(60, DT)
    t = np.arange(2 * n_set + 3) * DT
    a = np.zeros((t.size - 1, 3))
    a[n_set + 1] = [0.0, 50.0, -400.0]
    out = filtered_peak(t[1:] - DT / 2, a, 60)
    assert out["filter_dv_loss_rel"] < _roundoff(60)
    # near the end the filter spreads Δv beyond the record and the loss says so
    a[:] = 0.0
    a[-3] = [0.0, 0.0, 1.0]
    assert filtered_peak(t[1:] - DT / 2, a, 60)["filter_dv_loss_rel"] > 0.1


def test_contact_window_fin_impulses_and_end_warning():
    t = np.arange(11) * DT
    force = np.zeros(11)
    force[3:8] = 5.0                                   # intervals (t2, t3] … (t7, t8]
    assert contact_window(t, force) == pytest.approx((t[2], t[7], t[7] - t[2]), abs=1e-18)
    assert contact_window(t, np.zeros(11)) == (0.0, 0.0, 0.0)
    fins = FinContacts(["w1", "w2", "r1"], np.array([0, 2, 0]),
                       np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 3.0, 4.0]]), 1e-5)
    imp = fin_impulses(fins)
    assert np.allclose(imp["w1"], [1e-5, 3e-5, 4e-5]) and np.allclose(imp["w2"], 0) and np.allclose(imp["r1"], [0, 2e-5, 0])
    # contact still on in the last interval: one warning line
    v = np.tile([0.0, 0.0, 500.0], (11, 1))
    a_b = np.zeros((11, 3))
    v[10, 2] -= 1e-3
    a_b[10, 0] = -100.0
    force[10] = 1.0
    m = collision_metrics(_history(t, v, a_b, force), fins)
    assert len(m["warnings"]) == 1 and "last output interval" in m["warnings"][0]
    assert m["fin_impulse_ns"]["w1"] == pytest.approx(np.linalg.norm([1e-5, 3e-5, 4e-5]))


def test_bad_input_is_one_clear_line():
    t = np.arange(100) * 1e-3                          # 1 kHz: below 10 × CFC 180
    with pytest.raises(MetricsInputError, match="needs a sampling rate") as e:
        cfc_filter(t, np.zeros(100), 180)
    assert "\n" not in str(e.value)
    t2 = np.arange(100) * DT
    t2[50:] += 0.3 * DT
    with pytest.raises(MetricsInputError, match="not uniform"):
        cfc_filter(t2, np.zeros(100), 180)
    with pytest.raises(MetricsInputError, match="positive class"):
        cfc_filter(np.arange(100) * DT, np.zeros(100), -60)
    # gravity in the velocity but not declared: the body and world accelerations disagree
    dt_fine = 1e-6
    h, _ = _rigid_body_run(_strike_force(dt_fine)[0], dt_fine, 10, 120.0, np.array([0.0, -9.81, 0.0]), 0.0)
    fins = FinContacts(["a"], np.zeros(0, int), np.zeros((0, 3)), 1e-5)
    with pytest.raises(MetricsInputError, match="disagree"):
        collision_metrics(h._replace(gravity_mps2=np.zeros(3)), fins)


def test_load_alternation_runs_flags_a_step_instability_not_a_strike():
    # Reference: by construction. Fin 0: a strike, a half-sine of 4 µs (13 samples of 0.3125 µs)
    # over a steady 900 N — it never alternates for more than a sample or two. Fin 1: 900 N with
    # ±300 N flipping every sample for 100 samples (the explicit dashpot's period-2 mode seen on
    # infrared × traction's rudders before the damping cap): one run of ~100 samples. Fin 2: no
    # rows.
    from flexnet_fe.collide.metrics import ALTERNATION_RUN_LIMIT, load_alternation_runs

    nt = 300
    k = np.arange(nt)
    strike = 900.0 + 2000.0 * np.where((k >= 100) & (k < 113), np.sin(np.pi * (k - 100) / 13), 0.0)
    chatter = 900.0 + np.where((k >= 50) & (k < 150), 300.0 * (-1.0) ** k, 0.0)
    rows = np.stack([strike, chatter], axis=1)  # (nt, 2): one row per fin per sample
    force = np.zeros((2 * nt, 3))
    force[:, 0] = rows.ravel()
    row_start = np.arange(0, 2 * nt + 1, 2)
    fin = np.tile([0, 1], nt)
    runs = load_alternation_runs(row_start, fin, force, 3)
    assert runs[0] <= 2 and runs[2] == 0
    assert 96 <= runs[1] <= 100 and runs[1] > ALTERNATION_RUN_LIMIT
