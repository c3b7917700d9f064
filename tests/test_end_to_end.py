"""The README's main job, end to end: `flexnet run cases/radar_traction --report` through the
real CLI. Checks the run-directory contract (DESIGN.md §3) and the invariants a correct chain
must hold; the physics of each stage is verified against theory in its own test folder."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from flexnet_fe.io import read_history_csv

ROOT = Path(__file__).resolve().parents[1]

SUMMARY_KEYS = {
    "deploy": ["max_area_m2", "time_to_max_area_s", "initial_area_m2", "period_s", "max_tension_n", "steps",
               "dt_s", "wall_s"],
    "collide": ["peak_accel_mps2", "peak_accel_axis_mps2", "duration_s", "dv_over_v", "max_attitude_change_rad",
                "passed_through", "momentum_error_rel", "energy_error_rel", "max_penetration_m", "steps", "dt_s",
                "wall_s"],
    "shell": ["dt_s", "dt_crit_s", "dofs", "steps", "wall_s"],
    "flight": ["miss_distance_m", "hit", "lethal_radius_m", "time_of_closest_approach_s", "max_achieved_accel_g",
               "wall_s"],
}
FIN_KEYS = ["peak_von_mises_pa", "peak_time_s", "peak_location_m", "peak_max_principal_pa"]


@pytest.mark.slow
def test_default_case_whole_chain(tmp_path):
    out = tmp_path / "run"
    env = dict(os.environ, FLEXNET_NO_PROGRESS="1")
    r = subprocess.run([sys.executable, "-m", "flexnet_fe.cli", "run", str(ROOT / "cases/radar_traction"),
                        "--out", str(out), "--report"], capture_output=True, text=True, env=env, timeout=1200)
    assert r.returncode == 0, r.stderr[-3000:]
    status = json.loads((out / "status.json").read_text())
    assert {s: v["state"] for s, v in status["stages"].items()} == {s: "done" for s in SUMMARY_KEYS}
    summary = json.loads((out / "summary.json").read_text())
    for stage, keys in SUMMARY_KEYS.items():
        missing = [k for k in keys if k not in summary[stage]]
        assert not missing, f"{stage}: missing {missing}"
    fins = {k: v for k, v in summary["shell"].items() if isinstance(v, dict)}
    assert fins, "no fin was loaded"
    for name, sec in fins.items():
        assert all(k in sec for k in FIN_KEYS), name
        # XDMF + HDF5 per fin, readable history with the peak in it
        assert (out / "shell" / name / "fields.xdmf").is_file() and (out / "shell" / name / "fields.h5").is_file()
        hist = read_history_csv(out / "shell" / name / "history.csv")
        assert np.isclose(hist["max_von_mises_pa"].max(), sec["peak_von_mises_pa"], rtol=1e-12)
    # The stress fields open in PyVista's XDMF reader: one output time per field write, the
    # von Mises fields as cell data on the fin's quadrilaterals.
    import pyvista as pv

    name = next(iter(fins))
    reader = pv.XdmfReader(str(out / "shell" / name / "fields.xdmf"))
    assert reader.number_time_points > 1
    reader.set_active_time_value(reader.time_values[-1])
    blocks = reader.read()
    names = {k for b in blocks for k in b.cell_data.keys()}
    assert {"von_mises_top_pa", "von_mises_mid_pa", "von_mises_bottom_pa"} <= names
    # Newton's third law holds through the whole impact (gravity off in the collision):
    # momentum error at round-off (see tests/collide for the controlled version).
    assert summary["collide"]["momentum_error_rel"] < 1e-8
    # The explicit shell step respects its own stability limit.
    assert summary["shell"]["dt_s"] < summary["shell"]["dt_crit_s"]
    # The flight stage used the shell stage's damage (≥ 0) and the report was written.
    assert 0.0 <= summary["flight"]["wing_damage"] <= 1.0
    assert (out / "report.html").stat().st_size > 1000
