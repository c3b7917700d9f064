"""The simplify study's pairs: which variant stands for "without the simplification"."""

from __future__ import annotations

import math

from flexnet_fe.study import simplify
from flexnet_fe.study.collide import shipped_rope_split


def _row(knob, value, dv, default=False):
    return {"stage": "collide", "knob": knob, "value": value, "is_default": default, "status": "ok",
            "cpu_s": 1.0, "err_dv_over_v": math.nan, "dv_over_v": dv}


def test_lumped_ropes_are_compared_with_finer_splits_only():
    # Reference: the meaning of the simplification — "lumped ropes near contact" is undone by
    # splitting them finer than the shipped case does; a coarser split is more of the
    # simplification, not its absence (the pair once compared the shipped 8 with 2 and 4).
    k = shipped_rope_split()
    rows = [_row("default", "as shipped", 1.0, default=True),
            _row("collide.rope_split", str(max(1, k // 2)), 0.9), _row("collide.rope_split", str(2 * k), 1.01)]
    out = [r for r in simplify.rows(rows, []) if r["simplification"] == "lumped ropes near contact"]
    assert [r["without"] for r in out] == [f"collide.rope_split = {2 * k}"]
    assert math.isclose(out[0]["difference_rel"], 0.01 / 1.01, rel_tol=1e-9)  # relative to the finer run
