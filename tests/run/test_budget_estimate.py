"""The budget's step estimates against the stages' own step counts (flexnet_fe/budget.py)."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from flexnet_fe.atmosphere import isa
from flexnet_fe.budget import collide_cost
from flexnet_fe.collide.stage import run_collide
from flexnet_fe.config import load_case

CASES = Path(__file__).resolve().parents[2] / "cases"


@pytest.mark.parametrize("split", [1, 4])
def test_collide_steps_match_the_stage(tmp_path, split):
    # Reference: the collide stage's own step count (summary "steps") on the default case's rope,
    # missile and contact, on a 1.5 m flat taut net (edges beyond the missile's reach; the budget
    # knows only the undeployed net, whose rest lengths the flat net has), 0.2 ms. The estimate follows the stage's step rule at the split
    # piece's node mass; the stage then shortens dt so that an output interval is a whole number of
    # steps n, which changes the count by less than 1/n. (The cut at the fins is off here: its
    # pieces' lengths depend on the held geometry, which the estimate does not know — budget.py;
    # no max_duration: the estimate counts up to the cap, the stage stops when the contact is over.)
    case, file = load_case(CASES / "radar_traction")
    net = type(case.net).model_validate({**case.net.model_dump(), "edge_length": 1.5, "corner_mass": 1e-3})
    cfg = type(case.collide).model_validate({**case.collide.model_dump(), "net_source": "flat_taut",
                                             "duration": 2e-4, "snapshots": 2, "rope_split": split,
                                             "aim_point": (0.025, 0.025), "fin_piece_length": None,
                                             "max_duration": None, "resolution_check": False})
    case = case.model_copy(update={"net": net, "collide": cfg})
    estimated = collide_cost(case, file).steps
    summary = run_collide(net, None, case.missile, cfg, isa(case.atmosphere.altitude), None, tmp_path,
                          logging.getLogger("test_budget"))
    per_interval = cfg.output_interval * estimated / cfg.duration
    assert estimated == pytest.approx(summary["steps"], rel=1.0 / per_interval + 1e-9)



def test_shell_steps_count_the_peak_check_and_the_strike_envelope():
    # Reference: shell.stage.check_peaks reruns each fin from its start to its peak + 0.1 ms on the
    # mesh at half the local size, whose step is at most half (the CFL limit of the halved cells):
    # at most twice the run's steps more, so the upper bound is 3x the run's (budget.shell_cost).
    from flexnet_fe.budget import shell_cost
    case, file = load_case(CASES / "radar_traction")
    assert case.shell.peak_check and case.shell.local_mesh_size
    # shell.strike_envelope reruns each fin at the same size up to its peak once per move: at most
    # the run's steps again per move (shell.strikes.STRIKE_OFFSETS, four).
    bare = case.model_copy(update={"shell": case.shell.model_copy(update={"peak_check": False,
                                                                           "strike_envelope": False})})
    check = bare.model_copy(update={"shell": bare.shell.model_copy(update={"peak_check": True})})
    envelope = bare.model_copy(update={"shell": bare.shell.model_copy(update={"strike_envelope": True})})
    n = shell_cost(bare, file).steps
    assert shell_cost(check, file).steps == pytest.approx(3 * n, rel=1e-12)
    assert shell_cost(envelope, file).steps == pytest.approx(5 * n, rel=1e-12)
    assert "peak check" in shell_cost(check, file).detail and "strike envelope" in shell_cost(envelope, file).detail
