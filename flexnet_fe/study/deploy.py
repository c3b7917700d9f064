"""Deploy study: error in the maximum net area and its time against CPU time, over the net's
rope subdivisions, the time-step safety factor and the area pixel (``run_deploy``, the stage
function itself)."""

from __future__ import annotations

import logging

from flexnet_fe.atmosphere import isa
from flexnet_fe.study.common import Context, Point, run_points
from flexnet_fe.study.scenes import CASE, FULL_DEPLOY, QUICK_DEPLOY, case_with

LOG = logging.getLogger("flexnet.study.deploy")

"""The shipped values of the case (cases/radar_traction, schema defaults)."""


def points(quick: bool) -> list[Point]:
    """One-at-a-time variants around the default; the reference sets every knob to its finest."""
    grid = {"net.subdivisions": [2, 3],
            "deploy.safety_factor": [1.0, 0.25],
            "deploy.area_pixel": [0.04, 0.03, 0.02, 0.005]}
    if quick:
        grid = {"net.subdivisions": [2], "deploy.safety_factor": [1.0], "deploy.area_pixel": [0.02]}
    ref = {"net.subdivisions": 4, "deploy.safety_factor": 0.125,
           "deploy.area_pixel": 0.0025}
    out = [Point("reference", "all finest", tuple(f"{k}={v}" for k, v in ref.items()), is_reference=True),
           Point("default", "as shipped", (), is_default=True)]
    for knob, values in grid.items():
        out += [Point(knob, v, (f"{knob}={v}",)) for v in values]
    return out


def deploy_summary(case, stage_dir) -> dict:
    """``run_deploy``'s summary for ``case``, without the stage's figure (the study measures the
    simulation — kernel, time-step control, area, history, snapshots — not matplotlib)."""
    from flexnet_fe.net.deploy import run_deploy

    return run_deploy(case.net, case.deploy, isa(case.atmosphere.altitude), stage_dir, LOG, plots=False)


def run_point(p: Point, ctx: Context) -> tuple[dict, dict]:
    base = QUICK_DEPLOY if ctx.quick else FULL_DEPLOY
    case = case_with(CASE, base + p.overrides)
    s = deploy_summary(case, ctx.scratch("deploy_point"))
    return ({"max_area_m2": s["max_area_m2"], "time_to_max_area_s": s["time_to_max_area_s"]},
            {"size": s["nodes"], "steps": s["steps"], "dt_s": s["dt_s"]})


def rows(ctx: Context, bar=None) -> list[dict]:
    if ctx.quick:
        ctx.note("deploy", "scene: reduced traction net (2 m, 10 cm mesh, 441 nodes, 0.2 kg corners), "
                           "0.2 s, air off, as cases/radar_traction otherwise")
    else:
        ctx.note("deploy", "scene: cases/radar_traction deploy (5 m traction net, 5 cm mesh, 10 201 nodes, "
                           "0.4 s, air off)")
    ctx.note("deploy", "CPU time: run_deploy without its figure (deploy.png: ≈ 0.7 s of CPU per run, 8–9× "
                       "the default case's kernel, docs/performance.md); with it the figure is most of a "
                       "small net's stage time")
    ctx.note("deploy", "time_to_max_area_s is sampled at deploy.output_interval (5 ms): its error is "
                       "quantised to that interval")
    pts = points(ctx.quick)
    return run_points("deploy", pts, lambda p: run_point(p, ctx), ctx, bar)
