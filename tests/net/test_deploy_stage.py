"""The deploy stage end to end on small nets: outputs, summary keys, refusal of a forced step."""

import logging

import numpy as np
import pytest

from flexnet_fe.atmosphere import isa
from flexnet_fe.errors import NumericalError
from flexnet_fe.io import atomic_write_json, read_history_csv
from flexnet_fe.net.config import DeployConfig, RotaryNet, TractionNet
from flexnet_fe.net.deploy import find_period, run_deploy

LOG = logging.getLogger("flexnet.test.net")
KEYS = {"max_area_m2", "time_to_max_area_s", "initial_area_m2", "period_s", "max_tension_n", "steps",
        "dt_s", "wall_s"}
SMALL_TRACTION = TractionNet(edge_length=1.0, mesh_size=0.1, corner_mass=0.2, corner_speed=30.0)
SMALL_ROTARY = RotaryNet(warps=6, warp_length=0.6, mesh_size=0.1, tip_mass=0.1, hub_mass=0.5, tip_speed=6.0)


@pytest.mark.parametrize("net", [SMALL_TRACTION, SMALL_ROTARY], ids=["traction", "rotary"])
@pytest.mark.parametrize("air", [False, True], ids=["air_off", "air_on"])
def test_run_deploy_writes_outputs(tmp_path, net, air):
    dep = DeployConfig(duration=0.1, output_interval=0.005, snapshot_interval=0.05, air=air, mach=1.0)
    summary = run_deploy(net, dep, isa(8000.0), tmp_path, LOG)
    assert KEYS <= summary.keys()
    atomic_write_json(tmp_path / "summary.json", summary)  # JSON-clean (no NaN/inf)
    hist = read_history_csv(tmp_path / "history.csv")
    assert len(hist["t_s"]) == 21 and hist["t_s"][-1] == pytest.approx(0.1)
    assert {"area_m2", "mass_speed_rel_mps", "max_tension_n", "hub_spin_radps"} <= hist.keys()
    assert summary["max_area_m2"] == pytest.approx(hist["area_m2"].max())
    assert summary["initial_area_m2"] == pytest.approx(hist["area_m2"][0])
    assert summary["dt_s"] <= 0.5 * summary["dt_spring_limit_s"] * (1 + 1e-12)
    state = np.load(tmp_path / "net_state.npz", allow_pickle=False)
    assert state["x"].shape == (summary["nodes"], 3) and float(state["t"]) == summary["time_to_max_area_s"]
    assert (tmp_path / "deploy.png").stat().st_size > 10_000
    import pyvista as pv
    series = pv.get_reader(str(tmp_path / "net.pvd"))
    assert len(series.time_values) == 3
    series.set_active_time_value(series.time_values[-1])
    mesh = series.read()[0]
    assert mesh.n_points == summary["nodes"] and mesh.n_cells == summary["segments"]


def test_forced_step_above_limit_is_refused(tmp_path):
    dep = DeployConfig(duration=0.01, time_step=1.0, air=False)
    with pytest.raises(NumericalError, match="exceeds"):
        run_deploy(SMALL_TRACTION, dep, isa(8000.0), tmp_path, LOG)


def test_find_period():
    t = np.linspace(0, 1, 1001)
    # two maxima of a sine of period 0.4 s within 1 s -> 0.4 s at the sampling's resolution
    assert find_period(t, 50 + 20 * np.sin(2 * np.pi * t / 0.4)) == pytest.approx(0.4, abs=1e-3)
    assert find_period(t, t) is None
