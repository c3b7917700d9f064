"""The one-way check's rows (``study.one_way``) on hand-made records: the headline differences between
the rigid-fin collision and the one with the fins moving, and the fins' motion measures."""

from __future__ import annotations

import math
import types

import numpy as np
import pytest

from flexnet_fe.collide.model import FinMotion
from flexnet_fe.study.one_way import HEADLINES, difference_rows, motion_measures, scaled


def test_difference_rows_are_the_study_metric_and_flag_above_two_percent():
    # Reference: closed forms of study.common.rel_error. Δv 1.0e-4 → 1.01e-4 is 1 %; the per-fin
    # impulse's largest change 0.04 N s over the largest impulse 2.5 N s is 1.6 % (below 2 %); the
    # peak 100 → 97 is 3 % (matters); rudder_1's own impulse 1.0 → 1.04 N s is 4 % (matters).
    rigid = {"dv_over_v": 1.0e-4, "peak_accel_mps2": 100.0, "fin_impulse_ns": {"wing_1": 2.5, "rudder_1": 1.0}}
    moving = {"dv_over_v": 1.01e-4, "peak_accel_mps2": 97.0, "fin_impulse_ns": {"wing_1": 2.49, "rudder_1": 1.04}}
    rows = {r["headline"]: r for r in difference_rows(rigid, moving, 0.5, (10.0, 30.0))}
    assert set(rows) == set(HEADLINES) | {"fin_impulse_ns[wing_1]", "fin_impulse_ns[rudder_1]"}
    assert rows["dv_over_v"]["difference_rel"] == pytest.approx(0.01, rel=1e-12)
    assert rows["fin_impulse_ns"]["difference_rel"] == pytest.approx(0.016, rel=1e-12)
    assert rows["peak_accel_mps2"]["difference_rel"] == pytest.approx(0.03, rel=1e-12)
    assert rows["fin_impulse_ns[rudder_1]"]["difference_rel"] == pytest.approx(0.04, rel=1e-12)
    assert rows["fin_impulse_ns[wing_1]"]["difference_rel"] == pytest.approx(0.004, rel=1e-12)
    assert [rows[h]["matters"] for h in ("dv_over_v", "fin_impulse_ns", "peak_accel_mps2")] == [False, False, True]
    assert rows["fin_impulse_ns[rudder_1]"]["matters"] is True
    assert all("w × 0.5" in r["without"] and r["cost_without_s"] == 30.0 for r in rows.values())


def test_motion_measures_follow_the_fin_energies():
    # Reference: closed forms. A 1 kg fin (0.1 m² × 10 mm × 1000 kg/m³) with 1 J of kinetic energy
    # moves at sqrt(2) m/s RMS; −2.5 J of work on the rope is 0.25 % of 1 000 J exchanged.
    fin = types.SimpleNamespace(area=0.1, thickness=0.01, material=types.SimpleNamespace(density=1000.0))
    hist = {"kinetic_energy_j": np.array([0.0, 1.0, 0.5])}
    m = motion_measures(-2.5, 1000.0, {"wing_1": ({"max_abs_u_m": 1e-4}, hist, fin)}, 500.0)
    assert m["work_j"] == -2.5 and m["work_rel"] == pytest.approx(2.5e-3, rel=1e-14)
    assert m["u_max_m"] == 1e-4
    assert m["v_rms_mps"] == pytest.approx(math.sqrt(2.0), rel=1e-14)
    assert m["v_rel"] == pytest.approx(math.sqrt(2.0) / 500.0, rel=1e-14)


def test_scaled_scales_the_displacement_only():
    m = FinMotion(t0=np.array([1e-3]), dt=1e-6, nt=np.array([2]), offset=np.array([0, 2]),
                  grid=np.array([[0.0, 0.1, 0.0, 0.1]]), w=np.arange(8.0).reshape(2, 2, 2))
    s = scaled(m, 0.5)
    np.testing.assert_array_equal(s.w, 0.5 * m.w)
    assert s.t0 is m.t0 and s.dt == m.dt and s.grid is m.grid


def test_a_scale_whose_motion_reaches_the_rope_is_recorded_not_imposed(monkeypatch):
    # Reference: the check's contract (issue 15 §2: a method's limit is shown, not hidden).
    # model.with_fin_motion refuses a |w| that reaches a fin's rope radius + half-thickness (the
    # kernel's crossing test reads the undeformed core); the check must record that scale as not
    # imposed, with the reason, and still run the others.
    from flexnet_fe.study import one_way

    res = types.SimpleNamespace(summary={"dv_over_v": 1e-4}, history={"fin_motion_work_j": np.array([0.0, -0.5])})

    def collide(case_path, ddir, motion=None):
        if motion is not None and motion.w.max() > 1.5e-3:
            raise ValueError("fin motion: |w| up to 2 mm reaches rope radius + half-thickness")
        return "case", res

    monkeypatch.setattr(one_way, "_collide", collide)
    m = FinMotion(t0=np.zeros(1), dt=1e-6, nt=np.array([2]), offset=np.array([0, 2]), grid=np.zeros((1, 4)),
                  w=np.full((2, 2, 2), 1e-3))
    monkeypatch.setattr(one_way, "_shell_fins", lambda case_path, r, work: (m, {}))
    c = one_way.check("case_dir", "deploy", "work")
    scales = [s for s, *_ in c["moving"]]
    assert scales == list(one_way.SCALES)
    for scale, summary, work, _ in c["moving"]:
        if scale * 1e-3 > 1.5e-3:
            assert summary is None and "reaches rope radius" in work
        else:
            assert summary is res.summary and work == -0.5
