"""The staggered fin coupling (``[collide] fin_coupling = "staggered"``, ``shell.coupling``): the
stage is the impact with the fins moving as the shell computes them under the rigid impact's loads;
its case checks and its input hash.

The physics of an impact on moving fins (the rope meets the fin where it moved, at its speed, and
the surfaces' work closes the energy balance) is tested against closed forms in
tests/collide/test_fin_motion.py, and the sampled motion against the shell stage's own field in
tests/shell/test_motion.py; here the stage's composition of the two is checked against the same
steps taken one by one."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest

from flexnet_fe.atmosphere import isa
from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.collide.scene import held_net
from flexnet_fe.collide.simulate import simulate
from flexnet_fe.collide.stage import run_collide
from flexnet_fe.config import load_case
from flexnet_fe.errors import CaseError
from flexnet_fe.io import read_history_csv
from flexnet_fe.missile.build import build_missile
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.net.config import TractionNet
from flexnet_fe.pipeline import stage_hashes
from flexnet_fe.shell.config import ShellConfig
from flexnet_fe.shell.coupling import MOTION_INTERVAL, motion_shell, run_staggered
from flexnet_fe.shell.motion import fin_motion
from flexnet_fe.stages import Stage

ROOT = Path(__file__).resolve().parents[2]
NET = TractionNet(edge_length=1.0, mesh_size=0.05, rope_diameter=4.5e-3, corner_mass=1e-3, transverse_modulus=1e11)
MISSILE = MissileConfig(preset="radar", mesh_size=0.04)
COARSE_MOTION = 0.02
"""[m] The fins' element size at the loads in these tests (the stage's 5 mm costs minutes)."""


def _collide(**kw) -> CollideConfig:
    """The wings struck within 8 ms by a flat 1 m net of 5 cm cells (tests/collide/test_stage.py's scene)."""
    return CollideConfig(net_source="flat_taut", duration=8e-3, aim_point=(0.025, 0.025), snapshots=2, **kw)


def test_the_stage_is_the_impact_with_the_fins_moving_as_the_shell_computed(tmp_path, caplog):
    # Reference: the three steps taken one by one (the rigid impact's files, shell.motion.fin_motion on
    # them, collide.simulate with that motion). The steps are deterministic, so every headline of the
    # stage's summary equals the third step's to the bit, and its fin_coupling section's rigid values
    # equal the first's; the moving-fin impact's energy balance closes from its history.csv with the fins'
    # work counted as external (<= 0.5 % of the energy exchanged, issue 9), and that work is not zero.
    log = logging.getLogger("test_coupling")
    air, shell = isa(8000.0), ShellConfig(end_margin=3e-4, workers=1)
    cfg = _collide(fin_coupling="staggered")
    with caplog.at_level(logging.INFO, logger="test_coupling"):
        s = run_staggered(NET, None, MISSILE, cfg, shell, air, None, tmp_path / "stage", log,
                          motion_mesh=COARSE_MOTION)
    assert "against rigid fins" in caplog.text
    assert not (tmp_path / "stage" / "coupling").exists()  # work files removed

    rigid = run_collide(NET, None, MISSILE, cfg, air, None, tmp_path / "rigid", log, plots=False)
    motion, fins = fin_motion(MISSILE, motion_shell(shell, COARSE_MOTION), tmp_path / "rigid", tmp_path / "shell",
                              interval=MOTION_INTERVAL)
    moved = simulate(held_net(NET, cfg.net_source, None), build_missile(MISSILE), cfg, air.gravity, log,
                     air_density=air.density, fin_motion=motion).summary
    for key in ("dv_over_v", "peak_accel_mps2", "fin_impulse_ns", "duration_s", "steps", "energy_error_rel"):
        assert s[key] == moved[key], key
    c = s["fin_coupling"]
    assert c["rigid"]["fin_impulse_ns"] == rigid["fin_impulse_ns"] and c["rigid"]["dv_over_v"] == rigid["dv_over_v"]
    assert c["dv_over_v_move_rel"] == moved["dv_over_v"] / rigid["dv_over_v"] - 1.0
    assert c["fin_impulse_move_rel"]["wing_1"] == moved["fin_impulse_ns"]["wing_1"] / rigid["fin_impulse_ns"]["wing_1"] - 1
    from flexnet_fe.report.units import unknown_units
    from flexnet_fe.report.rundir import flatten

    assert unknown_units(flatten(c)) == []  # every number of the section has a unit in the report
    assert c["moving_fins"] == sorted(fins) and {"wing_1", "wing_2"} <= set(fins)
    assert c["max_abs_w_m"] == float(np.abs(motion.w).max()) > 0

    h = read_history_csv(tmp_path / "stage" / "history.csv")
    assert h["fin_motion_work_j"][-1] == c["fin_motion_work_j"] != 0.0
    terms = [k for k in h if k.endswith("_j") and k != "energy_balance_j"]
    external = ("gravity_work_j", "crop_boundary_work_j", "fin_motion_work_j")
    total = sum(h[k] for k in terms if k not in external) - sum(h[k] for k in external)
    np.testing.assert_allclose(h["energy_balance_j"], total - total[0], atol=1e-9 * total[0])
    exchanged = h["missile_kinetic_j"][0] - h["missile_kinetic_j"].min()
    assert np.abs(h["energy_balance_j"]).max() <= 5e-3 * exchanged


def test_the_section_of_an_impact_without_contact_has_no_moves():
    # Reference: coupling_section's contract — a move is relative to the rigid value, so where the rigid
    # impact had none (no contact: Δv, peak and every impulse 0) the move is None, not a division by 0.
    from flexnet_fe.shell.coupling import coupling_section

    zero = {"dv_over_v": 0.0, "peak_accel_mps2": 0.0, "fin_impulse_ns": {"wing_1": 0.0, "rudder_1": 0.0}}
    c = coupling_section(zero, zero, 0.0, 0.0, {})
    assert c["dv_over_v_move_rel"] is None and c["peak_accel_move_rel"] is None
    assert c["fin_impulse_move_rel"] == {"wing_1": None, "rudder_1": None} and c["fin_impulse_largest_move_rel"] is None
    some = {"dv_over_v": 2e-4, "peak_accel_mps2": 50.0, "fin_impulse_ns": {"wing_1": 4.0, "rudder_1": 1.0}}
    moved = {"dv_over_v": 2e-4, "peak_accel_mps2": 50.0, "fin_impulse_ns": {"wing_1": 4.0, "rudder_1": 0.9}}
    c = coupling_section(some, moved, 1e-3, -1.0, {})
    assert c["fin_impulse_move_rel"]["rudder_1"] == pytest.approx(-0.1)
    assert c["fin_impulse_largest_move_rel"] == pytest.approx(0.1 / 4.0)  # largest |ΔJ| over the largest J


def test_the_coupling_needs_the_line_law_and_a_shell_table_without_a_given_load(tmp_path):
    # Reference: the case checks of CollideConfig and Case (one line naming the field).
    with pytest.raises(ValueError, match="needs contact_law = 'line'"):
        _collide(fin_coupling="staggered", contact_law="segment")
    case = ROOT / "cases" / "radar_traction"
    text = (case / "case.toml").read_text()
    start = text.index("\n[shell]")
    end = text.find("\n[", start + 1)
    (tmp_path / "case.toml").write_text(text[:start] + (text[end:] if end > 0 else "\n"))
    with pytest.raises(CaseError, match=r"needs a \[shell\] table"):
        load_case(tmp_path, ['collide.fin_coupling="staggered"', 'case.stages=["collide"]'])


def test_the_collide_stage_hashes_the_shell_table_only_under_the_coupling():
    # Reference: the stage registry's contract (a stage's hash covers every table that can change its
    # results): the shell table changes the collide stage's results only under the staggered coupling.
    case = ROOT / "cases" / "radar_traction"
    h = {(c, m): stage_hashes(load_case(case, [f'collide.fin_coupling="{c}"', f"shell.end_margin={m}"])[0])
         for c in ("one_way", "staggered") for m in (0.002, 0.001)}
    assert h["one_way", 0.002][Stage.collide] == h["one_way", 0.001][Stage.collide]
    assert h["staggered", 0.002][Stage.collide] != h["staggered", 0.001][Stage.collide]
    assert h["one_way", 0.002][Stage.collide] != h["staggered", 0.002][Stage.collide]
