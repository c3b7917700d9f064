"""The damping map's two-body integration (flexnet_fe.contact.restitution.restitution_achieved)
against closed-form limits, so that the map's "achieved restitution" can be trusted."""

from __future__ import annotations

import pytest

from flexnet_fe.contact.law import DAMPING_CODE, DampingModel
from flexnet_fe.contact.restitution import restitution_achieved


@pytest.mark.parametrize("v", [0.3, 10.0, 500.0])
def test_undamped_hertz_contact_returns_all_energy(v):
    # χ = 0: a conservative Hertz contact; v_out = v_in exactly (energy conservation). RK4 with
    # 4000 steps over the contact time: error far below 1e-4.
    assert restitution_achieved(DAMPING_CODE[DampingModel.none], 0.5, v) == pytest.approx(1.0, abs=1e-4)


@pytest.mark.parametrize("model", [DampingModel.lankarani_nikravesh, DampingModel.hunt_crossley,
                                   DampingModel.flores])
def test_weak_damping_limit_recovers_requested_restitution(model):
    # All three χ laws are derived for e → 1 (Hunt & Crossley 1975, Lankarani & Nikravesh 1990,
    # Flores et al. 2011): at e = 0.99 the achieved value must be within 0.2 % of the request.
    e = restitution_achieved(DAMPING_CODE[model], 0.99, 100.0)
    assert e == pytest.approx(0.99, abs=2e-3)


def test_achieved_restitution_is_speed_independent_above_the_floor():
    # χ ∝ 1/v_k and Hertz scaling make e independent of v once v ≥ v_floor (self-similar impact).
    code = DAMPING_CODE[DampingModel.flores]
    assert restitution_achieved(code, 0.5, 10.0) == pytest.approx(restitution_achieved(code, 0.5, 500.0), rel=1e-6)


def test_collision_warns_when_the_damping_law_misses_the_requested_restitution():
    # Reference: the comparison of these laws by Flores et al. (2011, Nonlinear Dyn.) — for e = 0.5
    # Lankarani–Nikravesh returns
    # e ≈ 0.72 and Hunt–Crossley ≈ 0.66, while their own law stays within a few hundredths. The
    # guard must flag the first two and pass Flores (tolerance RESTITUTION_TOLERANCE = 0.05).
    from flexnet_fe.contact.restitution import restitution_warning

    for model, expected in ((DampingModel.lankarani_nikravesh, 0.725), (DampingModel.hunt_crossley, 0.663)):
        e = restitution_achieved(DAMPING_CODE[model], 0.5, 10.0)
        assert e == pytest.approx(expected, abs=0.01)
        line = restitution_warning(model.value, 0.5, e)
        assert line is not None and model.value in line and "flores" in line
    e = restitution_achieved(DAMPING_CODE[DampingModel.flores], 0.5, 10.0)
    assert abs(e - 0.5) <= 0.05 and restitution_warning("flores", 0.5, e) is None


def test_guard_flags_an_impact_below_the_approach_speed_floor():
    # Reference: restitution_achieved's RK4 integration of the two-body impact (tests above). Below
    # the floor v_floor χ is capped at c/v_floor, so every law's e rises above the requested one;
    # the guard made at the impact speed must say so (the stability map found these unflagged).
    from flexnet_fe.contact.restitution import RESTITUTION_TOLERANCE, restitution_check
    for model in (DampingModel.hunt_crossley, DampingModel.lankarani_nikravesh, DampingModel.flores):
        e, line = restitution_check(model.value, 0.5, 0.1, 1.0)
        assert e - 0.5 > RESTITUTION_TOLERANCE and line is not None and "below" in line
    e, line = restitution_check("flores", 0.5, 500.0, 1.0)  # above the floor Flores meets the request
    assert abs(e - 0.5) <= RESTITUTION_TOLERANCE and line is None
