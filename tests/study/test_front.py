"""The studies' Pareto front and verdict (``study.common.pareto_mask``, ``verdict``) on hand-made rows."""

from __future__ import annotations

from flexnet_fe.study.common import verdict


def _row(knob, cpu, err, default=False, reference=False, excluded=""):
    return {"knob": knob, "value": knob, "cpu_s": cpu, "is_default": default, "is_reference": reference,
            "err_q": err, "excluded": excluded}


def test_an_excluded_point_does_not_push_the_default_off_the_front():
    # Reference: the rule of pareto_mask. A point 50 % cheaper (beyond the 15 % noise) and more
    # accurate dominates the default — unless it is excluded (a cost its stage cannot see, stated).
    rows = [_row("reference", 100.0, 0.0, reference=True), _row("default", 10.0, 0.015, default=True),
            _row("coarse", 5.0, 0.01)]
    v = verdict(rows)
    assert v["default_on_front"] is False and v["cheapest_within"] == "coarse = coarse"
    rows[2]["excluded"] = "moves a downstream quantity"
    v = verdict(rows)
    assert v["default_on_front"] is True and v["default_within"] is True
    assert rows[2]["on_front"] is False and v["cheapest_within"] == "default = default"


def test_an_excluded_default_keeps_its_own_error():
    # The default's verdict reads its own worst error even if it were marked excluded.
    rows = [_row("reference", 100.0, 0.0, reference=True), _row("default", 10.0, 0.03, default=True, excluded="x")]
    v = verdict(rows)
    assert v["default_worst_error"] == 0.03 and v["default_within"] is False and v["default_on_front"] is False


def test_each_fins_own_error_is_reported_beside_the_verdicts():
    # Reference: closed form. A 1.0 N s rudder off by 0.04 N s beside a 2.5 N s wing off by 0.01 is 4 %
    # off on its own (the verdict's error over the largest impulse reads 0.04 / 2.5 = 1.6 %).
    from flexnet_fe.study.collide import own_fin_errors

    ref = {"is_reference": True, "fin_impulse_ns.wing_1": 2.5, "fin_impulse_ns.rudder_1": 1.0}
    row = {"is_reference": False, "fin_impulse_ns.wing_1": 2.49, "fin_impulse_ns.rudder_1": 1.04}
    stopped = {"is_reference": False}
    own_fin_errors([ref, row, stopped])
    assert abs(row["fin_impulse_own_err"] - 0.04) < 1e-12 and ref["fin_impulse_own_err"] == 0.0
    assert stopped["fin_impulse_own_err"] != stopped["fin_impulse_own_err"]  # NaN: no impulses to compare


def test_the_collide_study_excludes_pieces_coarser_than_measured():
    # The rule of study.collide.excluded: pieces coarser than FIN_PIECE_MEASURED are not candidates
    # (their cost is on the fin stresses: docs/validation.md, "Ensembles at three rope resolutions").
    from flexnet_fe.study.collide import FIN_PIECE_MEASURED, FIN_PIECE_REASON, excluded

    assert excluded("collide.fin_piece_length", 2.0 * FIN_PIECE_MEASURED) == FIN_PIECE_REASON
    assert excluded("collide.fin_piece_length", FIN_PIECE_MEASURED) == ""
    assert excluded("collide.fin_piece_length", 0.5 * FIN_PIECE_MEASURED) == ""
    assert excluded("collide.fin_piece_chord", 2.0 * FIN_PIECE_MEASURED) == ""
