"""Simplifications table (issue 15 §3): the same headline numbers with and without each
simplification the code can switch, their difference and cost, flagged above 2 %.

Built from the accuracy rows of the stage studies in the same run (no extra runs), plus the
one-way (rigid-fin) check from the shell study's largest fin displacement."""

from __future__ import annotations

import math

from flexnet_fe.study.common import HEADLINE_TOLERANCE, rel_error

ROPE_RADIUS_M = 4.5e-3 / 2
"""cases/radar_traction's rope radius [m] (net.rope_diameter / 2)."""


def _pair(rows, stage, knob, value, label, without) -> list[dict]:
    """Rows comparing the default (with the simplification) with the variant ``knob = value``."""
    d = next((r for r in rows if r["stage"] == stage and r["is_default"]), None)
    v = next((r for r in rows if r["stage"] == stage and r["knob"] == knob and str(r["value"]) == str(value)
              and r["status"] == "ok"), None)
    if d is None or v is None:
        return []
    out = []
    for col in [k[4:] for k in d if k.startswith("err_")]:
        diff = rel_error(d[col], v[col])
        out.append({"simplification": label, "without": without, "stage": stage, "headline": col,
                    "with_value": d[col], "without_value": v[col], "difference_rel": diff,
                    "cost_with_s": d["cpu_s"], "cost_without_s": v["cpu_s"],
                    "matters": bool(diff > HEADLINE_TOLERANCE)})
    return out


def rows(stage_rows: list[dict], notes: list[str]) -> list[dict]:
    """The table; ``notes`` receives a line per simplification that cannot be switched."""
    out = []
    out += _pair(stage_rows, "collide", "collide.crop", "false", "cropped net (collide.crop)", "full net")
    for v in (2, 4):
        out += _pair(stage_rows, "collide", "collide.rope_split", v, "lumped ropes near contact",
                     f"collide.rope_split = {v}")
    out += _pair(stage_rows, "collide", "net.subdivisions", 2, "lumped ropes (one segment per bar)",
                 "net.subdivisions = 2")
    for v in (2, 3):
        out += _pair(stage_rows, "deploy", "net.subdivisions", v, "lumped ropes (one segment per bar)",
                     f"net.subdivisions = {v}")
    shell_d = next((r for r in stage_rows if r["stage"] == "shell" and r["is_default"]), None)
    if shell_d is not None and math.isfinite(shell_d.get("max_abs_u_m", math.nan)):
        u = shell_d["max_abs_u_m"]
        ratio = u / ROPE_RADIUS_M
        out.append({"simplification": "rigid fins in the collision (one-way loading)",
                    "without": "elastic fins (not coupled in the code)", "stage": "shell",
                    "headline": "max fin displacement / rope radius", "with_value": 0.0,
                    "without_value": u, "difference_rel": ratio, "cost_with_s": math.nan,
                    "cost_without_s": math.nan, "matters": bool(ratio > HEADLINE_TOLERANCE)})
    if not any(r["simplification"].startswith("lumped ropes near") for r in out):
        notes.append("lumped vs split ropes near contact: the collide record on this page has no "
                     "collide.rope_split rows (measured before the knob existed) — re-run `flexnet study "
                     "collide` to measure it")
    notes.append("air off vs on during the collision: the [collide] table has no air knob — not measured")
    notes.append("rigid missile in the collision: no elastic-missile model exists — not measured; the "
                 "one-way check compares the shell stage's largest fin displacement with the rope "
                 "radius (a fin that moves by a good part of the rope radius would change the contact)")
    return out
