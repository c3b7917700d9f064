"""Rigid-body equations of motion against NASA's 6-DOF check case 2 and conservation laws."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from flexnet_fe.flight.eom import euler_rates, quat_rate
from flexnet_fe.frames import quat_to_matrix

# NASA/TM-2015-218675 check-case data, copied from ../shared/reference/nesc/ (see data/NESC_README.md)
NESC = Path(__file__).resolve().parent / "data" / "atmos02_tumbling_brick_sim02.csv"
SLUG_FT2 = 14.5939 * 0.3048 ** 2  # [kg m^2]
INERTIA = np.array([0.001894220, 0.006211019, 0.007194665]) * SLUG_FT2


def _torque_free(omega0_deg, t_end, dt):
    """RK4 on (q, ω) with the package's quat_rate / euler_rates; samples every 0.1 s."""
    y = np.concatenate([[1.0, 0, 0, 0], np.radians(omega0_deg)])
    zero = np.zeros(3)

    def f(y):
        return np.concatenate([quat_rate(y[:4], y[4:]), euler_rates(y[4:], INERTIA, zero)])

    every = int(round(0.1 / dt))
    out = [y.copy()]
    for k in range(1, int(round(t_end / dt)) + 1):
        k1 = f(y)
        k2 = f(y + 0.5 * dt * k1)
        k3 = f(y + 0.5 * dt * k2)
        k4 = f(y + dt * k3)
        y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if k % every == 0:
            out.append(y.copy())
    return np.array(out)


@pytest.fixture(scope="module")
def brick():
    ref = np.genfromtxt(NESC, delimiter=",", names=True)
    sim = _torque_free([10.0, 20.0, 30.0], 30.0, 1e-3)
    return ref, sim


def _nesc_rates(ref):
    return np.column_stack([ref["bodyAngularRateWrtEi_deg_s_Roll"], ref["bodyAngularRateWrtEi_deg_s_Pitch"],
                            ref["bodyAngularRateWrtEi_deg_s_Yaw"]])


def test_body_rates_match_converged_euler_equations(brick):
    ref, sim = brick
    # Second model: scipy's DOP853 (8th order, adaptive, rtol 1e-12) on Euler's equations.
    # RK4 at dt = 1 ms: global error ~ (Ω dt)^4 Ω T ≈ 3e-12 rad/s (Ω ≈ 0.65 rad/s, T = 30 s);
    # measured 3e-11 deg/s. Bound 1e-9 deg/s.
    f = lambda t, w: euler_rates(w, INERTIA, np.zeros(3))
    dop = solve_ivp(f, (0, 30), np.radians([10.0, 20.0, 30.0]), t_eval=ref["time"], method="DOP853",
                    rtol=1e-12, atol=1e-14)
    err = np.abs(np.degrees(sim[:, 4:]) - np.degrees(dop.y.T)).max()
    assert err < 1e-9, f"max body-rate difference to DOP853 {err:.3e} deg/s"


def test_body_rates_match_nesc_check_case_2(brick):
    ref, sim = brick
    err = np.abs(np.degrees(sim[:, 4:]) - _nesc_rates(ref)).max()
    # Reference: NASA/TM-2015-218675 check case 2, simulator 02. The issue asks for 1e-4 deg/s,
    # but the converged solution of Euler's equations for the documented inertia (the test
    # above, independent of our integrator) differs from these data by 1.24e-3 deg/s at most
    # (4e-5 of the 30 deg/s rates); we could not identify the cause (inertia refits do not
    # remove it). The data are not torque-free to that level: their rotational kinetic energy
    # ½ Σ I ω² drifts by 7.1e-6 and |I ω| by 3.4e-6 relative over the 30 s (both are exact
    # invariants of Euler's equations), and they already differ from the converged solution by
    # 1.38e-4 deg/s (pitch) at the first sample, t = 0.1 s. The bound below is that measured reference discrepancy plus 20 %, so the test
    # still catches any error in our equations larger than the reference's own deviation.
    assert err < 1.5e-3, f"max body-rate error {err:.3e} deg/s"


def test_torque_free_conserves_energy_momentum_and_quaternion_norm(brick):
    _, sim = brick
    q, w = sim[:, :4], sim[:, 4:]
    energy = 0.5 * np.sum(INERTIA * w * w, axis=1)
    h_inertial = np.array([quat_to_matrix(qi / np.linalg.norm(qi)) @ (INERTIA * wi) for qi, wi in zip(q, w)])
    de = np.abs(energy / energy[0] - 1).max()
    dh = np.abs(np.linalg.norm(h_inertial - h_inertial[0], axis=1) / np.linalg.norm(h_inertial[0])).max()
    dq = np.abs(np.linalg.norm(q, axis=1) - 1).max()
    # Exact invariants of torque-free motion (kinetic energy, inertial angular momentum, |q| = 1
    # of q̇ = ½ q ⊗ ω; no renormalisation anywhere). RK4 is not conservative: the drift is bounded
    # by its global error ~ (Ω dt)^4 Ω T ≈ 3e-12 (Ω ≈ 0.65 rad/s, dt = 1e-3 s, T = 30 s);
    # measured ~1e-14. Bound 1e-11.
    assert de < 1e-11, f"energy drift {de:.2e}"
    assert dh < 1e-11, f"angular momentum drift {dh:.2e}"
    assert dq < 1e-11, f"quaternion norm drift {dq:.2e}"
