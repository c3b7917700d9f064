"""The flight case files validate and say what the docs say they do."""

from __future__ import annotations

from pathlib import Path

import pytest

from flexnet_fe.config import load_case

CASES = Path(__file__).resolve().parents[2] / "cases"


@pytest.mark.parametrize("name, wing, rudder, sweep", [
    ("flight_baseline", 0.0, 1.0, None),
    ("flight_wing_damage", 0.4, 1.0, "wing_damage"),
    ("flight_rudder_damage", 0.0, 0.2, "rudder_effectiveness"),
    ("flight_wing_sweep", 0.5, 1.0, "wing_damage"),
])
def test_flight_case_loads(name, wing, rudder, sweep):
    case, _ = load_case(CASES / name)
    f = case.flight
    assert [s.value for s in case.case.stages] == ["flight"]
    assert case.missile.preset.value == "radar" and f.damage.model.value == "geometry"
    assert (f.damage.wing_damage, f.damage.rudder_effectiveness) == (wing, rudder)
    assert (f.sweep.parameter.value if f.sweep else None) == sweep
    # paper §VI engagement
    assert f.target_position == (7000.0, 0.0, 0.0) and f.missile_position == (4000.0, 1000.0, 500.0)
    assert (f.target_speed, f.missile_speed, f.navigation_constant, f.target_load_factor) == (272.0, 1000.0, 6.0, 5.0)
    if f.sweep is not None:  # thresholds need values listed from undamaged to damaged
        vals = list(f.sweep.values)
        assert vals == sorted(vals, reverse=(sweep == "rudder_effectiveness"))


def test_radar_traction_takes_its_damage_from_the_shell_with_the_failure_strain_law():
    case, _ = load_case(CASES / "radar_traction")
    assert case.flight.damage_from_shell and case.flight.damage_law.law.value == "failure_strain"
