"""Flight study: error in the miss distance against CPU time over the RK4 step
(``flight.simulate_flight``, the stage's own engagement, cases/flight_baseline)."""

from __future__ import annotations

from flexnet_fe.study.common import Context, Point, run_points
from flexnet_fe.study.scenes import FLIGHT_CASE, case_with



def points(quick: bool) -> list[Point]:
    ref = 2.5e-5 if quick else 1.25e-5
    out = [Point("reference", ref, (f"flight.dt={ref}",), is_reference=True),
           Point("default", "as shipped", (), is_default=True)]
    out += [Point("flight.dt", v, (f"flight.dt={v}", f"flight.output_dt={max(v, 1e-3)}"))
            for v in (8e-4, 4e-4, 2e-4, 5e-5)]
    return out


def run_point(p: Point, ctx: Context) -> tuple[dict, dict]:
    from flexnet_fe.flight.stage import simulate_flight

    case = case_with(FLIGHT_CASE, p.overrides)
    r = simulate_flight(case.flight, case.atmosphere.altitude, missile=case.missile)
    return ({"miss_distance_m": r.miss_distance_m},
            {"size": r.steps, "steps": r.steps, "dt_s": r.dt_s, "dt_crit_s": r.dt_crit_s})


def rows(ctx: Context, bar=None) -> list[dict]:
    ctx.note("flight", "scene: cases/flight_baseline (paper §VI engagement, undamaged missile), both modes")
    ctx.note("flight", "integrator: RK4 only in this branch (no knob); dt is the only resolution knob")
    return run_points("flight", points(ctx.quick), lambda p: run_point(p, ctx), ctx, bar)
