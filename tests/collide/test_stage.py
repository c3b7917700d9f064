"""The collide stage's files: the fin_contacts.npz contract with the shell stage, history, snapshots."""

from __future__ import annotations

import json
import logging

import numpy as np
import pytest
from pydantic import ValidationError

from flexnet_fe.atmosphere import isa
from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.collide.stage import run_collide
from flexnet_fe.io import read_history_csv
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.net.config import TractionNet

DESIGN_KEYS = {"peak_accel_mps2", "peak_accel_axis_mps2", "duration_s", "dv_over_v", "max_attitude_change_rad",
               "passed_through", "momentum_error_rel", "energy_error_rel", "max_penetration_m", "steps", "dt_s",
               "wall_s"}


def test_stage_writes_its_files(tmp_path):
    net = TractionNet(edge_length=1.0, mesh_size=0.05, rope_diameter=4.5e-3, corner_mass=1e-3, transverse_modulus=1e11)
    cfg = CollideConfig(net_source="flat_taut", duration=4e-3, aim_point=(0.025, 0.025), snapshots=3)
    summary = run_collide(net, None, MissileConfig(preset="radar"), cfg, isa(8000.0), None, tmp_path,
                          logging.getLogger("test_collide_stage"))
    assert DESIGN_KEYS <= set(summary)
    json.dumps(summary)  # JSON-able as summary.json needs
    with np.load(tmp_path / "fin_contacts.npz", allow_pickle=False) as z:
        assert set(z.files) == {"fin_names", "t", "row_start", "fin", "point", "force", "width"}
        nt, ne = z["t"].size, z["fin"].size
        assert z["fin_names"].dtype.kind == "U" and z["fin_names"].shape == (8,)
        assert z["row_start"].dtype == np.int64 and z["row_start"].shape == (nt + 1,)
        assert z["fin"].dtype == np.int32
        assert z["point"].shape == (ne, 3) and z["force"].shape == (ne, 3) and z["width"].shape == (ne,)
        assert z["row_start"][-1] == ne and ne > 0  # the wings were hit within 4 ms
        assert np.all((z["fin"] >= 0) & (z["fin"] < 8))
        np.testing.assert_allclose(z["width"], 4.5e-3)  # rope diameter
    h = read_history_csv(tmp_path / "history.csv")
    for c in ("t_s", "accel_body_x_mps2", "accel_body_y_mps2", "accel_body_z_mps2", "accel_mag_mps2",
              "omega_body_x_rps", "alpha_body_z_rps2", "speed_change_rel", "roll_change_rad",
              "max_penetration_m"):
        assert c in h
    # headline: the CFC-filtered peak is below the raw one-interval peak, which is kept as raw
    assert 0 < summary["peak_accel_mps2"] <= summary["peak_accel_raw_mps2"]
    assert h["accel_mag_mps2"].max() == pytest.approx(summary["peak_accel_raw_mps2"], rel=1e-12)
    # momentum closes from the file: missile + free net + held-node impulse is constant (gravity off)
    p = sum(np.column_stack([h[f"{w}_{a}_ns"] for a in "xyz"]) for w in ("missile_momentum", "net_momentum",
                                                                          "held_impulse"))
    assert np.abs(p - p[0]).max() < 1e-9 * np.abs(h["missile_momentum_z_ns"][0] - h["missile_momentum_z_ns"][-1])
    # energy closes from the file: energy_balance_j is the sum of its terms minus its initial value
    terms = [c for c in h if c.endswith("_j") and c != "energy_balance_j"]
    external = ("gravity_work_j", "crop_boundary_work_j", "fin_motion_work_j")  # work done on the system
    total = sum(h[c] for c in terms if c not in external) - sum(h[c] for c in external)
    np.testing.assert_allclose(h["energy_balance_j"], total - total[0], atol=1e-9 * total[0])
    exchanged = h["missile_kinetic_j"][0] - h["missile_kinetic_j"].min()
    assert np.abs(h["energy_balance_j"]).max() <= 5e-3 * exchanged  # issue 9: 0.5 % of the energy exchanged
    assert (tmp_path / "net.pvd").is_file() and (tmp_path / "missile.pvd").is_file()
    assert len(list((tmp_path / "snapshots").glob("net_*.vtu"))) == 3
    for name in ("accel", "velocity", "attitude", "snapshots", "fin_loads"):
        assert (tmp_path / f"collide_{name}.png").is_file()


def test_config_refuses_unknown_and_inconsistent_values():
    with pytest.raises(ValidationError):
        CollideConfig(damping_model="kelvin_voigt")
    with pytest.raises(ValidationError):
        CollideConfig(stiffness_rule="given")  # needs contact_stiffness
    with pytest.raises(ValidationError):
        CollideConfig(contact_stiffness=1e9)  # only with the 'given' rule
    with pytest.raises(ValidationError):
        CollideConfig(bogus=1.0)


@pytest.mark.parametrize("case", ["radar_traction", "radar_rotary", "infrared_traction"])
def test_paper_case_closes_momentum_and_energy_from_its_files(tmp_path, case):
    # Reference: conservation laws, read back from history.csv. Each paper case's own [net] and
    # [collide] tables (rope, contact, step), on its flat net (no deployment: fast) for 3 ms —
    # the nose and the wings' leading edges meet the net — must run without tunnelling, and
    # its history must close momentum to round-off and energy to 0.5 % of the energy exchanged.
    from pathlib import Path

    from flexnet_fe.config import load_case

    root = Path(__file__).resolve().parents[2]
    # The cases' max_duration (30 ms) is set to the 3 ms here: a longer cap would widen the crop and
    # run on while the rope touches. radar_rotary's cut at the fins (0.175 mm) is set to 1.4 mm to
    # keep this test cheap: momentum and energy close at any rope resolution (the kernel's balance
    # does not depend on it; the 1.4 mm pieces are the other cases' and as light).
    extra = ["collide.fin_piece_length=1.4e-3"] if case == "radar_rotary" else []
    # (The cases' resolution check, a second impact at half the pieces, is off: conservation only.)
    c, _ = load_case(root / "cases" / case, ["collide.net_source=flat_taut", "collide.duration=3e-3",
                                             "collide.max_duration=3e-3", "collide.resolution_check=false"] + extra)
    summary = run_collide(c.net, None, c.missile, c.collide, isa(8000.0), None, tmp_path,
                          logging.getLogger("test_collide_stage"))
    assert not summary["tunnelling"]
    h = read_history_csv(tmp_path / "history.csv")
    # (with collide.air the air's impulse on the net is external: it is taken out)
    p = sum(np.column_stack([h[f"{w}_{a}_ns"] for a in "xyz"]) for w in ("missile_momentum", "net_momentum",
                                                                          "held_impulse")) \
        - np.column_stack([h[f"air_impulse_{a}_ns"] for a in "xyz"])
    dp = np.linalg.norm([h[f"missile_momentum_{a}_ns"][0] - h[f"missile_momentum_{a}_ns"][-1] for a in "xyz"])
    assert np.abs(p - p[0]).max() < 1e-9 * dp
    exchanged = h["missile_kinetic_j"][0] - h["missile_kinetic_j"].min()
    assert exchanged > 0 and np.abs(h["energy_balance_j"]).max() <= 5e-3 * exchanged
