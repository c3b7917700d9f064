"""The engagement map: grid → case overrides (run layer, ``flexnet_fe.engagement_map``), a run's
summary → outcome row (``flexnet_fe.flight.outcome``), CSV and picture. (Running the stages and
reusing a done run directory are the pipeline's and the sweep's, tested in tests/run and
tests/test_sweep.py; a real map is in docs/validation.md.)"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import pytest

from flexnet_fe.config import load_case
from flexnet_fe import engagement_map as EM
from flexnet_fe.flight.outcome import outcome

CASES = Path(__file__).resolve().parents[2] / "cases"


def test_grid_points_are_valid_case_overrides():
    pts = EM.grid([str(CASES / "engagement_map"), str(CASES / "engagement_map_rotary")], [-0.3, 0.3], [0.0], [0.0, 10.0])
    assert len(pts) == 2 * 2 * 1 * 2 and len({p.label for p in pts}) == len(pts)
    case, _ = load_case(Path(pts[1].case), pts[1].overrides())
    assert case.collide.aim_point == (-0.3, 0.0)
    assert case.collide.incidence_angle == pytest.approx(math.radians(10.0), rel=1e-15)
    assert [s.value for s in case.case.stages] == list(EM.STAGES)
    assert case.flight.damage_from_shell


def test_outcome_row_margins_from_the_shell_and_flight_summaries():
    summary = {"shell": {"wing_1": {"peak_von_mises_pa": 250e6, "allowable_pa": 500e6},
                         "rudder_2": {"peak_von_mises_pa": 1000e6}},           # no allowable: the flight's
               "flight": {"miss_distance_m": 12.0, "hit": False, "wing_damage": 0.1, "rudder_effectiveness": 0.75,
                          "damage_from_shell": {"allowable_pa": {"rudder_2": 500e6, "wing_1": 500e6}}}}
    row = outcome(summary)
    # margin = allowable/peak − 1: wing_1 +1.0, rudder_2 −0.5 (the critical fin)
    assert row["critical_fin"] == "rudder_2" and row["min_fin_margin"] == pytest.approx(-0.5)
    assert (row["miss_distance_m"], row["hit"]) == (12.0, False)


def test_map_csv_and_picture(tmp_path):
    rows = [dict(label=f"p{i}", case="engagement_map", aim_x_m=x, aim_y_m=0.0, incidence_deg=inc,
                 miss_distance_m=m, hit=m <= 5, min_fin_margin=-0.2, critical_fin="rudder_2",
                 wing_damage=0.0, rudder_effectiveness=1.0, error="")
            for i, (x, inc, m) in enumerate([(-0.3, 0, 0.3), (0.3, 0, 40.0), (0.3, 10, 2.0)])]
    rows.append(dict(rows[0], label="bad", miss_distance_m=None, error="collide: blow-up"))
    EM.write_csv(rows, tmp_path / "map.csv")
    EM.plot_map(rows, tmp_path / "map.png")
    with open(tmp_path / "map.csv") as f:
        back = list(csv.DictReader(f))
    assert [r["label"] for r in back] == ["p0", "p1", "p2", "bad"] and back[3]["error"] == "collide: blow-up"
    assert (tmp_path / "map.png").stat().st_size > 10_000
