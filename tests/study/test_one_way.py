"""The one-way fin bound's measures (``study.one_way.bound_measures``) on a hand-made record, and its
softened runs when they stop."""

from __future__ import annotations

import math
import types

import numpy as np
import pytest

from flexnet_fe.errors import NumericalError
from flexnet_fe.study import one_way
from flexnet_fe.study.one_way import SOFT_FACTORS, bound_measures


def test_bound_measures_follow_the_hertz_law_and_the_fin_energies():
    # Reference: closed forms. A 500 N rope-on-fin force on a K = 1e9 N/m^1.5 Hertz contact
    # penetrates δ = (F/K)^(2/3) = (5e-7)^(2/3) m; the K/10 contact at that force 10^(2/3) δ, i.e.
    # 3.6416 δ more. A 1 kg fin (0.1 m² × 10 mm × 1000 kg/m³) with 1 J of kinetic energy moves at
    # sqrt(2) m/s RMS; its external work is the largest |W| of its history. Tolerance: round-off.
    res = types.SimpleNamespace(loads=types.SimpleNamespace(force=np.array([[300.0, 400.0, 0.0], [10.0, 0.0, 0.0]])),
                                summary={"energy_exchanged_j": 1000.0})
    fin = types.SimpleNamespace(area=0.1, thickness=0.01, material=types.SimpleNamespace(density=1000.0))
    hist = {"external_work_j": np.array([0.0, -2.5, 2.0]), "kinetic_energy_j": np.array([0.0, 1.0, 0.5])}
    m = bound_measures(res, {"wing_1": ({"max_abs_u_m": 1e-4}, hist, fin)}, 1e9, 1.5, 500.0)
    delta = 5e-7 ** (2.0 / 3.0)
    assert m["f_max_n"] == pytest.approx(500.0, rel=1e-14)
    assert m["give_m"] == pytest.approx(delta, rel=1e-12)
    assert m["extra_give_m"] == pytest.approx((10 ** (2 / 3) - 1) * delta, rel=1e-12)
    assert m["u_over_extra"] == pytest.approx(1e-4 / ((10 ** (2 / 3) - 1) * delta), rel=1e-12)
    assert m["work_j"] == 2.5 and m["work_rel"] == pytest.approx(2.5e-3, rel=1e-14)
    assert m["v_rms_mps"] == pytest.approx(math.sqrt(2.0), rel=1e-14)
    assert m["v_rel"] == pytest.approx(math.sqrt(2.0) / 500.0, rel=1e-14)


def test_a_softened_run_that_tunnels_is_recorded_as_no_bound(monkeypatch):
    # Reference: the study's contract (issue 15 §2: a method's failure is shown, not hidden). A
    # softened contact whose rope passes through a fin stops with NumericalError; the study must
    # keep going, write one "stopped" row per factor naming the reason (no headline difference, no
    # verdict) and report every factor as stopped, so no bound is claimed from it.
    def tunnels(ctx, extra):
        raise NumericalError("collide: tunnelling at t ≈ 0.0044 s: a rope centre line reached the core of wing_4; K …")

    monkeypatch.setattr(one_way, "_collide", tunnels)
    case = types.SimpleNamespace(net=types.SimpleNamespace(transverse_modulus=1e10))
    rows, stopped = one_way._soft_rows(None, case, {}, 30.0, {f: {} for f in SOFT_FACTORS})
    assert stopped == set(SOFT_FACTORS) and len(rows) == len(SOFT_FACTORS)
    for r in rows:
        assert r["headline"] == "run" and r["without_value"].startswith("stopped: collide: tunnelling")
        assert math.isnan(r["difference_rel"]) and r["matters"] is None
