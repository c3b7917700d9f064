"""Simplifications table (issue 15 §3): the same headline numbers with and without each
simplification the code can switch, their difference and cost, flagged above 2 %.

Built from the accuracy rows of the stage studies on the page and measurements of its own: air
off vs on during the collision (:func:`air_rows`, the collide study's scene run side by side) and,
in the full study, the one-way fin loading against the collision run again with the fins moving as
the shell computed (``study.one_way``)."""

from __future__ import annotations

import math

from flexnet_fe.study.common import HEADLINE_TOLERANCE, Context, measured, rel_error
from flexnet_fe.study.scenes import CASE, FULL_COLLIDE, QUICK_COLLIDE, case_with

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


AIR_HEADLINES = ("dv_over_v", "fin_impulse_ns", "peak_accel_mps2", "contact_end_s")
"""The collide headlines compared with air off and on (``contact_end_s``: end of the contact
force, ``collide.metrics``; the run's end time when the force still acts there)."""


def _air_case(ctx: Context, air: bool, extra: tuple[str, ...] = ()):
    """(case, deploy dir or None) of the collide study's scene with ``collide.air`` set."""
    base = QUICK_COLLIDE if ctx.quick else FULL_COLLIDE
    case = case_with(CASE, base + (f"collide.air={'true' if air else 'false'}",) + extra)
    if case.collide.net_source.value != "deploy_max_area":
        return case, None
    from flexnet_fe.study.collide import deploy_dir

    return case, deploy_dir(ctx)


def _air_pair(label: str, without: str, headline: str, off, on, cost: tuple[float, float]) -> dict:
    """One row; a per-fin dict is compared as the study's errors are (``rel_error``: max-normalised
    over the fins) and shown by its largest entry, as the stage rows show it."""
    diff = rel_error(off, on)
    if isinstance(on, dict):
        off, on = max(off.values(), default=0.0), max(on.values(), default=0.0)
    return {"simplification": label, "without": without, "stage": "collide", "headline": headline,
            "with_value": off, "without_value": on, "difference_rel": diff, "cost_with_s": cost[0],
            "cost_without_s": cost[1], "matters": bool(diff > HEADLINE_TOLERANCE)}


def air_rows(ctx: Context, notes: list[str]) -> list[dict]:
    """Air off (the paper's assumption 2) vs on (``collide.air``, Eq. (5)–(8) on every active
    rope segment) during the collision of the collide study's scene, run side by side after an
    untimed warm-up (both runs use the same compiled kernel). Rows per headline (the per-fin
    impulse as the study's max-normalised error and per fin) with CPU seconds of each run."""
    from flexnet_fe.study.collide import simulate_case

    case, ddir = _air_case(ctx, True, ("collide.duration=1e-4",))
    simulate_case(case, ddir)  # warm-up: JIT / cache load, not timed
    res = {}
    for air in (False, True):
        case, ddir = _air_case(ctx, air)
        (_, _, r), cpu, wall = measured(lambda: simulate_case(case, ddir))
        res[air] = (r.summary, cpu, wall)
    (off, c_off, _), (on, c_on, _) = res[False], res[True]
    cost = (c_off, c_on)
    label, without = "no air on the rope during the collision", "collide.air = true"
    out = [_air_pair(label, without, h, off[h], on[h], cost) for h in AIR_HEADLINES]
    out += [_air_pair(label, without, f"fin_impulse_ns[{f}]", off["fin_impulse_ns"][f], on["fin_impulse_ns"][f], cost)
            for f in sorted(on["fin_impulse_ns"])]
    notes.append(f"air off vs on during the collision ({'quick scene' if ctx.quick else 'cases/radar_traction'}, "
                 f"ISA density {on['air_density_kgpm3']:.4g} kg/m³): the air took {on['dissipated_air_j']:.4g} J "
                 f"({on['dissipated_air_j'] / on['energy_exchanged_j']:.1%} of the energy exchanged) and "
                 f"{math.hypot(*on['air_impulse_ns']):.4g} N s from the net; CPU {c_on:.3g} s with air against "
                 f"{c_off:.3g} s without (ratio {c_on / c_off:.3g}); contact end {off['contact_end_s']:.4g} / "
                 f"{on['contact_end_s']:.4g} s, stop reason {off['stop_reason']} / {on['stop_reason']}, energy "
                 f"error {off['energy_error_rel']:.2%} / {on['energy_error_rel']:.2%} (off / on)")
    return out


def _finer_splits(stage_rows: list[dict]) -> list[int]:
    """The collide record's ``collide.rope_split`` values finer than the shipped one: less lumped
    ropes near the contact, the simplification's "without" (a coarser split is more of it)."""
    from flexnet_fe.study.collide import shipped_rope_split

    k = shipped_rope_split()
    return sorted({int(float(r["value"])) for r in stage_rows
                   if r["stage"] == "collide" and r["knob"] == "collide.rope_split" and int(float(r["value"])) > k})


def rows(stage_rows: list[dict], notes: list[str], ctx: Context | None = None) -> list[dict]:
    """The table; ``notes`` receives a line per simplification that cannot be switched. With
    ``ctx`` the air pair is measured (:func:`air_rows`); without, it is noted as not measured."""
    out = []
    out += _pair(stage_rows, "collide", "collide.crop", "false", "cropped net (collide.crop)", "full net")
    for v in _finer_splits(stage_rows):
        out += _pair(stage_rows, "collide", "collide.rope_split", v, "lumped ropes near contact",
                     f"collide.rope_split = {v}")
    out += _pair(stage_rows, "collide", "net.subdivisions", 2, "lumped ropes (one segment per bar)",
                 "net.subdivisions = 2")
    for v in (2, 3):
        out += _pair(stage_rows, "deploy", "net.subdivisions", v, "lumped ropes (one segment per bar)",
                     f"net.subdivisions = {v}")
    if not any(r["simplification"].startswith("lumped ropes near") for r in out):
        notes.append("lumped vs split ropes near contact: the collide record on this page has no "
                     "collide.rope_split rows (measured before the knob existed) — re-run `flexnet study "
                     "collide` to measure it")
    if ctx is not None:
        from flexnet_fe.study import one_way

        out += air_rows(ctx, notes)
        out += one_way.rows(ctx, notes)
    else:
        notes.append("air off vs on during the collision: not measured in this call (no study context)")
    notes.append("rigid missile body in the collision: no elastic-body model exists — not measured (the "
                 "fins' elasticity is: the one-way rows)")
    return out
