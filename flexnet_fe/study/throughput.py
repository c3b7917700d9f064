"""Throughput and scaling (issue 15 §4): net kernel against plain numpy (helper E's
``flexnet_fe.study.net_numpy``, when present), shell ns per DOF-step, log-log slope of cost
against size per stage, and the default case's end-to-end time by stage from a run directory."""

from __future__ import annotations

import importlib
import logging
import math
from pathlib import Path

from flexnet_fe.study.common import Context, loglog_slope

LOG = logging.getLogger("flexnet.study.throughput")

SIZE_KNOBS = {"deploy": ("net.subdivisions",),
              "collide": ("net.subdivisions", "collide.crop", "collide.crop_wave_speed_factor"),
              "shell": ("missile.mesh_size",), "flight": ("flight.dt",)}
"""The knobs whose variants change each stage's problem size (deploy nodes, collide active
segments, shell DOFs, flight steps)."""


def net_kernel(ctx: Context) -> list[dict]:
    try:
        mod = importlib.import_module("flexnet_fe.study.net_numpy")
    except ImportError as err:
        ctx.note("throughput", f"net kernel vs numpy: flexnet_fe.study.net_numpy not on this branch ({err}) "
                               "— skipped")
        return []
    n_side, steps = (41, 50) if ctx.quick else (101, 400)
    out = []
    for air in (False, True):
        r = mod.net_kernel_throughput(n_side, air, steps)
        out.append({"kind": "net_kernel", "air": air, "n_side": n_side, **r})
    return out


def shell_rate(stage_rows: list[dict]) -> list[dict]:
    out = []
    for r in stage_rows:
        if r["stage"] == "shell" and r["status"] == "ok" and r.get("steps"):
            out.append({"kind": "shell_dof_step", "knob": r["knob"], "value": r["value"], "dofs": r["size"],
                        "steps": r["steps"], "ns_per_dof_step": 1e9 * r["cpu_s"] / (r["size"] * r["steps"])})
    return out


def slopes(stage_rows: list[dict]) -> list[dict]:
    """Per stage: slope of log(CPU) and of log(CPU per step) against log(size) over the default
    and its size-knob variants (size: deploy nodes, collide active segments, shell DOFs, flight steps)."""
    out = []
    for stage, knobs in SIZE_KNOBS.items():
        pts = [r for r in stage_rows if r["stage"] == stage and r["status"] == "ok"
               and (r["is_default"] or r["knob"] in knobs) and r.get("size")]
        if len(pts) < 2:
            continue
        size = [r["size"] for r in pts]
        used = sorted({r["knob"] for r in pts if not r["is_default"]})
        out.append({"kind": "scaling", "stage": stage, "size_knob": ", ".join(used), "points": len(pts),
                    "size_min": min(size), "size_max": max(size),
                    "slope_cpu": loglog_slope(size, [r["cpu_s"] for r in pts]),
                    "slope_cpu_per_step": loglog_slope(size, [r["cpu_s"] / r["steps"] for r in pts])})
    return out


def end_to_end(ctx: Context, run_dir: Path | None) -> list[dict]:
    """Per stage wall time of a run of the default case, from its status.json (the pipeline's
    own timing). Full study: the case is run into the scratch folder first."""
    from flexnet_fe.io import read_json
    from flexnet_fe.runs import STATUS

    if run_dir is None:
        if ctx.quick:
            ctx.note("throughput", "end-to-end time by stage: full study only (or --run-dir DIR)")
            return []
        from flexnet_fe.config import load_case
        from flexnet_fe.pipeline import run_case
        from flexnet_fe.study.scenes import CASE

        case, case_dir = load_case(CASE, [])
        run_dir = ctx.scratch("end_to_end")
        run_case(case, case_dir, run_dir, force=True)
    status = read_json(Path(run_dir) / STATUS)["stages"]
    out = []
    for name, rec in status.items():
        if rec.get("state") == "done":
            out.append({"kind": "end_to_end", "stage": name, "wall_s": rec.get("wall_s", math.nan)})
    if out:
        out.append({"kind": "end_to_end", "stage": "total", "wall_s": sum(r["wall_s"] for r in out)})
    return out


def rows(ctx: Context, stage_rows: list[dict], run_dir: Path | None = None) -> list[dict]:
    ctx.note("throughput", "not measured in this branch: shell step against a STREAM triad, 1 vs 2 MPI "
                           "ranks, time outside kernels per stage")
    return net_kernel(ctx) + shell_rate(stage_rows) + slopes(stage_rows) + end_to_end(ctx, run_dir)
