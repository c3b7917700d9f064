"""The production deploy kernel against a second model of the same laws: ``study.net_numpy``
(whole-array numpy, written independently of the kernel's per-segment loop). Both evaluate
Eq. (1)–(4) + gravity (+ Eq. (5)–(10) with air) and step with symplectic Euler, so they must
agree to round-off: forces to ~1e-13 of the largest force, positions after 300 steps to
~1e-12 of the net's size (round-off grows slowly through the stiff springs)."""

import numpy as np
import pytest

from flexnet_fe.net.config import TractionNet
from flexnet_fe.net.kernels import net_forces
from flexnet_fe.net.state import Environment, initial_state, kernel_model, kernel_state, step_many
from flexnet_fe.net.timestep import spring_limit
from flexnet_fe.net.topology import build_traction
from flexnet_fe.study.net_numpy import NumpyNet, net_kernel_throughput

NET = TractionNet(edge_length=1.0, mesh_size=0.1, corner_mass=0.2, corner_speed=30.0, launch_elevation_deg=20.0,
                  slack_offset=-0.01)  # ropes 1 cm longer than the bars: some stay slack


def _env(air: bool) -> Environment:
    # rho = 0.5 kg/m³ at 20 m/s across the flight: drag of the same order as the tensions
    return Environment(np.array([0.0, -9.81, 0.0]), 0.5 if air else 0.0, np.array([3.0, 0.0, -1.0]), air)


@pytest.mark.parametrize("air", [False, True], ids=["air_off", "air_on"])
def test_forces_and_trajectory_match_numpy_model(air):
    model = build_traction(NET)
    env = _env(air)
    ref = NumpyNet(model, env.gravity, env.rho, env.wind, air)
    st = initial_state(model, (0.0, 0.0, 20.0))
    dt = 0.25 * spring_limit(model)
    step_many(model, st, env, dt, 40)  # a deformed, partly slack net with tensions and drag
    x, v = st.x.copy(), st.v.copy()
    # forces at one state
    f = np.empty_like(x)
    net_forces(kernel_model(model, env), kernel_state(st, st.wrap.copy()), f, np.zeros(len(x)))
    f_ref, t_ref = ref.forces(x, v)
    assert np.count_nonzero(t_ref == 0.0) > 0 and np.count_nonzero(t_ref > 0.0) > 0  # both branches of the law
    scale = np.abs(f_ref).max()
    assert np.abs(f - f_ref).max() <= 1e-13 * scale
    assert np.abs(st.tension - t_ref).max() <= 1e-13 * t_ref.max()
    # trajectories from the same state
    step_many(model, st, env, dt, 300)
    ref.step(x, v, dt, 300)
    assert np.abs(st.x - x).max() <= 1e-12 * np.ptp(x, axis=0).max()
    assert np.abs(st.v - v).max() <= 1e-10 * np.abs(v).max()


def test_numpy_model_refuses_a_hub():
    from flexnet_fe.net.config import RotaryNet
    from flexnet_fe.net.topology import build_rotary

    with pytest.raises(ValueError, match="hub"):
        NumpyNet(build_rotary(RotaryNet()), np.zeros(3), 0.0, np.zeros(3), False)


def test_throughput_keys_and_same_result():
    r = net_kernel_throughput(11, True, 20, repeats=1)
    assert {"ns_per_spring_step_kernel", "ns_per_spring_step_numpy", "ratio", "n_springs"} <= r.keys()
    assert r["n_springs"] == 2 * 11 * 10 and r["ratio"] > 0.0
    assert r["max_dx_m"] <= 1e-12  # the timed runs of both models end at the same state
