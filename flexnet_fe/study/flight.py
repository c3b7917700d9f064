"""Flight study: error in the miss distance (undamaged and damaged missile), the time of
closest approach and the largest lateral acceleration against CPU time over the RK4 step
(``flight.simulate_flight``, the stage's own engagement, cases/flight_baseline)."""

from __future__ import annotations

import numpy as np

from flexnet_fe.study.common import Context, Point, run_points
from flexnet_fe.study.scenes import FLIGHT_CASE, case_with

DAMAGED = ("flight.damage.model='geometry'", "flight.damage.wing_damage=0.4")
"""The damaged scene: the same engagement with 40 % of the wing area lost (cases/flight_wing_damage)."""

STEPS = (2e-3, 1e-3, 8e-4, 5e-4, 4e-4, 2e-4, 5e-5)
"""RK4 steps [s] around the default (reference: 1.25e-5 s, quick 2.5e-5 s)."""


def points(quick: bool) -> list[Point]:
    ref = 2.5e-5 if quick else 1.25e-5
    out = [Point("reference", ref, (f"flight.dt={ref}", "flight.output_dt=1e-3"), is_reference=True),
           Point("default", "as shipped", (), is_default=True)]
    out += [Point("flight.dt", v, (f"flight.dt={v}", f"flight.output_dt={max(v, 1e-3)}")) for v in STEPS]
    return out


def run_point(p: Point, ctx: Context) -> tuple[dict, dict]:
    from flexnet_fe.flight.stage import simulate_flight

    out = {}
    for label, extra in (("", ()), ("_damaged", DAMAGED)):
        case = case_with(FLIGHT_CASE, p.overrides + extra)
        r = simulate_flight(case.flight, case.atmosphere.altitude, missile=case.missile)
        out[f"miss_distance{label}_m"] = r.miss_distance_m
        if not label:
            out["time_of_closest_approach_s"] = r.time_of_closest_approach_s
            out["max_accel_mps2"] = float(np.hypot(r.diag["accel_y_mps2"], r.diag["accel_z_mps2"]).max())
            extra_cols = {"size": r.steps, "steps": r.steps, "dt_s": r.dt_s, "dt_crit_s": r.dt_crit_s}
    return out, extra_cols


def rows(ctx: Context, bar=None) -> list[dict]:
    ctx.note("flight", "scene: cases/flight_baseline (paper §VI engagement), undamaged and with 40 % of the "
                       "wing area lost (flight.damage.wing_damage = 0.4), both modes")
    ctx.note("flight", "integrator: RK4 only in this branch (no knob); dt is the only resolution knob")
    ctx.note("flight", "max_accel_mps2 is the largest sampled |a_lateral| of the history (output_dt = "
                       "max(dt, 1 ms)): its error includes the sampling")
    return run_points("flight", points(ctx.quick), lambda p: run_point(p, ctx), ctx, bar)
