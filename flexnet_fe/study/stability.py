"""Stability maps (issue 15 §2): where each method fails and whether the solver's guard stops
the run (or flags it) before a wrong number is reported.

Each map row has ``status``: ``ok`` (finished, no flag), ``flagged`` (finished with a warning in
its summary), ``stopped`` (the solver raised NumericalError: the guard stopped it) — and
``wrong`` (its headline differs from the map's fine reference by more than
:data:`WRONG_TOLERANCE`, or its physics check failed: energy grew, rope past the core) and
``escaped`` = wrong and not flagged and not stopped: a bug, listed on the page.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from flexnet_fe import runs
from flexnet_fe.atmosphere import isa
from flexnet_fe.config import load_case
from flexnet_fe.errors import NumericalError
from flexnet_fe.study.common import Context, measured, rel_error
from flexnet_fe.study.scenes import CASE, NO_FIN_CUT, QUICK_COLLIDE, QUICK_DEPLOY, case_with

LOG = logging.getLogger("flexnet.study.stability")

WRONG_TOLERANCE = 0.02
"""A finished point whose headline is off its map's fine reference by more than this (the
issue's 2 % bar) counts as a wrong number."""


def _row(map_name: str, **kw) -> dict:
    row = {"map": map_name, "status": "ok", "wrong": False, "escaped": False}
    row.update(kw)
    row["escaped"] = bool(row["wrong"] and row["status"] == "ok")
    return row


# -- net: forced dt / spring limit against energy growth ---------------------------------------

def net_map(ctx: Context) -> list[dict]:
    """Deploy the quick net with ``deploy.time_step`` forced to r × the spring stability limit.
    Energy growth = max over outputs of (kinetic about the CoM + elastic) / its value at the
    first output (≤ ~1 for this damped, unforced net when stable)."""
    from flexnet_fe.io import read_history_csv
    from flexnet_fe.study.deploy import deploy_summary

    d = ctx.scratch("stab_net")
    base = QUICK_DEPLOY + ("deploy.duration=0.1",)
    ratios = (0.25, 0.5, 1.0, 1.05, 2.0) if ctx.quick else (0.125, 0.25, 0.5, 0.9, 1.0, 1.05, 1.5, 2.0)
    case = case_with(CASE, base)
    s0 = deploy_summary(case, d)
    lim = s0["dt_spring_limit_s"]
    ref = None
    rows = []
    for r in ratios:
        case = case_with(CASE, base + (f"deploy.time_step={r * lim!r}",))
        try:
            s = deploy_summary(case, d)
        except NumericalError as err:
            rows.append(_row("net", dt_over_dt_crit=r, energy_growth=math.nan, status="stopped",
                             message=str(err)[:200]))
            continue
        h = read_history_csv(d / runs.HISTORY)
        e = h["kinetic_energy_rel_j"] + h["elastic_energy_j"]
        growth = float(np.nanmax(e) / e[1]) if e[1] > 0 else math.nan
        ref = s["max_area_m2"] if ref is None else ref
        err = rel_error(s["max_area_m2"], ref)
        rows.append(_row("net", dt_over_dt_crit=r, energy_growth=growth, err_headline=err,
                         wrong=bool(err > WRONG_TOLERANCE or not growth < 2.0 or not np.isfinite(growth)),
                         status="flagged" if s.get("warnings") else "ok"))
    return rows


# -- collision: dt / dt_crit against the energy balance -----------------------------------------

def collide_map(ctx: Context) -> list[dict]:
    """The quick impact with the chosen dt multiplied by r (``simulate(dt_scale=r)``), output
    interval 0.1 ms so that dt may grow; dt_crit = min(spring, contact) stability limits.
    Energy growth = the run's own ``energy_error_rel`` (balance error / energy exchanged)."""
    from flexnet_fe.collide.scene import held_net
    from flexnet_fe.collide.simulate import simulate
    from flexnet_fe.missile.build import build_missile

    case = case_with(CASE, QUICK_COLLIDE + ("collide.output_interval=1e-4", "collide.load_interval=1e-4"))
    net = held_net(case.net, case.collide.net_source, None)
    missile = build_missile(case.missile)
    g, rho = isa(case.atmosphere.altitude).gravity, isa(case.atmosphere.altitude).density
    ref, rows = None, []
    for r in ((1.0, 4.0, 16.0, 64.0, 256.0) if ctx.quick else (0.25, 1.0, 4.0, 16.0, 64.0, 256.0)):
        try:
            res = simulate(net, missile, case.collide, g, LOG, air_density=rho, n_snapshots=2, dt_scale=r)
        except NumericalError as err:
            rows.append(_row("collide", dt_scale=r, dt_over_dt_crit=math.nan, energy_growth=math.nan,
                             status="stopped", message=str(err)[:200]))
            continue
        s = res.summary
        lim = min(s["dt_limits_s"]["rope_springs"], s["dt_limits_s"]["contact"])
        q = {"dv": s["dv_over_v"], "fin": dict(s["fin_impulse_ns"])}
        ref = q if ref is None else ref
        err = max(rel_error(q["dv"], ref["dv"]), rel_error(q["fin"], ref["fin"]))
        rows.append(_row("collide", dt_scale=r, dt_over_dt_crit=s["dt_s"] / lim,
                         energy_growth=s["energy_error_rel"], err_headline=err,
                         max_penetration_ratio=s["max_penetration_ratio"], wrong=bool(err > WRONG_TOLERANCE),
                         status="flagged" if s["warnings"] else "ok",
                         message="; ".join(s["warnings"])[:200]))
    return rows


# -- shell: dt / dt_crit against energy growth -----------------------------------------------

def shell_map(ctx: Context) -> list[dict]:
    """A clamped 0.2 m × 0.1 m, 2 mm Al plate (16 × 8 elements) under a 0.1 ms pressure pulse,
    run at dt = r × dt_crit (Lanczos λ_max). Energy growth = max(kinetic + strain) /
    max |external work|; the solver's guard is ``growth_limit`` (RunResult.failed_at)."""
    from flexnet_fe.shell import api
    from flexnet_fe.shell.forms import ShellMaterial, Support

    mat = ShellMaterial(thickness=2e-3, youngs_modulus=71.7e9, poisson_ratio=0.33, density=2810.0)
    model = api.plate(16, 8, 0.2, 0.1, mat, supports={"root": Support.CLAMPED})
    loads = api.pressure(model, [0.0, 5e-5, 1e-4], [0.0, 1e5, 0.0])
    probe = api.solve(model, loads, 1e-6)
    ref, rows = None, []
    for r in (0.25, 0.5, 0.9, 1.0, 1.01, 1.05, 1.2, 2.0):
        res = api.solve(model, loads, 1e-3, dt=r * probe.dt_crit)
        run = res.run
        work = float(np.max(np.abs(run.work))) if len(run.work) else 0.0
        growth = float(np.max(run.ke + run.se)) / work if work > 0 else math.nan
        stopped = bool(run.failed_at)
        peak = float(np.max(run.vm)) if len(run.vm) else math.nan
        ref = peak if ref is None else ref
        err = rel_error(peak, ref)
        rows.append(_row("shell", dt_over_dt_crit=r, energy_growth=growth, err_headline=err,
                         wrong=bool(not np.isfinite(err) or err > WRONG_TOLERANCE or growth > 2.0),
                         status="stopped" if stopped else "ok",
                         message=f"energy guard tripped at step {run.failed_at}" if stopped else ""))
    return rows


# -- contact: stiffness × dt × impact speed against penetration / tunnelling ------------------

CONTACT_SCENE = ("collide.net_source='flat_taut'", "net.edge_length=0.6", "net.mesh_size=0.1",
                 "collide.stiffness_rule='given'", "collide.snapshots=2", "collide.output_interval=1e-4",
                 "collide.load_interval=1e-4",
                 "collide.rope_split=1", *NO_FIN_CUT)
"""A 0.6 m flat patch of the rope (49 nodes) centred on the missile's path: the nose, body and
the four wings and rudders pass through it (the wings reach beyond the body's radius). Ropes not
split (rope_split 1) nor cut at the fins (``scenes.NO_FIN_CUT``): the map is about the contact law and its guard at a given stiffness, not
the rope's resolution (the split would multiply its cost ≈ 10×, measured)."""


def contact_map(ctx: Context) -> list[dict]:
    """Given contact stiffness K × travel per step (``pass_through_fraction`` f, dt = f ×
    min(rope radius, fin half-thickness) / v) × impact speed v: the largest penetration as a
    fraction of (rope radius + half-thickness) and whether the rope passed a part's core.
    A finished run with penetration ratio ≥ 1 that says nothing is a wrong number escaped."""
    from flexnet_fe.collide.scene import held_net
    from flexnet_fe.collide.simulate import simulate
    from flexnet_fe.missile.build import build_missile

    ks = (1e6, 1e8, 1e10) if ctx.quick else (1e5, 1e6, 1e7, 1e8, 1e9, 1e10)
    fs = (0.1, 1.0) if ctx.quick else (0.1, 0.5, 1.0)
    vs = (300.0, 1000.0) if ctx.quick else (100.0, 300.0, 500.0, 1000.0)
    rows = []
    for k in ks:
        for f in fs:
            for v in vs:
                case = case_with(CASE, CONTACT_SCENE + (f"collide.contact_stiffness={k}",
                                                        f"collide.pass_through_fraction={f}",
                                                        f"collide.impact_speed={v}",
                                                        f"collide.duration={4.0 / v:.6g}",
                                                        f"collide.max_duration={4.0 / v:.6g}"))  # (4 m of travel:
                # the case's own cap, 30 ms, is shorter at 100 m/s)
                net = held_net(case.net, case.collide.net_source, None)
                missile = build_missile(case.missile)
                try:
                    s = simulate(net, missile, case.collide, 9.81, LOG, n_snapshots=2,
                                 air_density=isa(case.atmosphere.altitude).density).summary
                except NumericalError as err:
                    rows.append(_row("contact", stiffness=k, pass_through_fraction=f, impact_speed_mps=v,
                                     penetration_ratio=math.nan, status="stopped",
                                     message=str(err)[:160]))
                    continue
                pen = s["max_penetration_ratio"]
                rows.append(_row("contact", stiffness=k, pass_through_fraction=f, impact_speed_mps=v,
                                 penetration_ratio=pen, energy_growth=s["energy_error_rel"],
                                 wrong=bool(pen >= 1.0 or s["tunnelling"]),
                                 status="flagged" if s["warnings"] else "ok",
                                 message="; ".join(s["warnings"])[:160]))
    return rows


# -- damping: restitution achieved against requested -----------------------------------------

def damping_map(ctx: Context) -> list[dict]:
    """Restitution achieved by Hunt–Crossley, Lankarani–Nikravesh and Flores across impact
    speeds and requested e, against the collision's guard (``contact.restitution``: the summary
    warns when the law misses the requested e by more than RESTITUTION_TOLERANCE above the
    approach-speed floor). Below the floor (``collide.damping_min_approach_speed``, 1 m/s in the
    cases) χ is capped and e is higher: the guard (``restitution_check``, made at the case's impact
    speed) says so for an impact below the floor; slow secondary contacts inside a fast impact
    are the floor's documented regularisation (docs/validation.md, "Damping law")."""
    from flexnet_fe.contact.law import DampingModel
    from flexnet_fe.contact.restitution import RESTITUTION_TOLERANCE, restitution_check

    rows = []
    speeds = (0.3, 10.0, 500.0) if ctx.quick else (0.1, 0.3, 1.0, 10.0, 100.0, 500.0, 1000.0)
    v_floor = load_case(CASE)[0].collide.damping_min_approach_speed  # the shipped cases' floor
    for model in (DampingModel.hunt_crossley, DampingModel.lankarani_nikravesh, DampingModel.flores):
        for e in (0.2, 0.5, 0.8, 0.95):
            for v in speeds:
                ea, guard = restitution_check(model.value, e, v, v_floor)
                rows.append(_row("damping", model=model.value, restitution_requested=e, impact_speed_mps=v,
                                 restitution_achieved=ea, status="flagged" if guard else "ok",
                                 message=guard or "", wrong=bool(not abs(ea - e) <= RESTITUTION_TOLERANCE)))
    return rows


MAPS = {"net": net_map, "collide": collide_map, "shell": shell_map, "contact": contact_map,
        "damping": damping_map}


def rows(ctx: Context, bar=None) -> list[dict]:
    ctx.note("stability", "escaped = finished without a flag (no warning, no stop) and wrong (headline "
                          f"> {WRONG_TOLERANCE:.0%} off the map's finest point, energy grown > 2×, or rope "
                          "centre line at/past a part's core)")
    out = []
    for name, fn in MAPS.items():
        r, cpu, wall = measured(lambda: fn(ctx))
        LOG.info("stability map %s: %d points, %.1f s CPU", name, len(r), cpu)
        out += r
        if bar is not None:
            bar.update(1)
    return out
