"""One-way fin loading (issue 15 §3): how much can the fins' elasticity move the collision
headlines? A bound from the two stages' own results, without a coupled model.

The collision treats the fins as rigid; the shell stage then loads the elastic fins with the
collision's contact forces (one-way). One run of both stages on the default case gives three
measures (:func:`rows`, full study only):

1. the contact's compliance: the collision headlines with the contact stiffness K / s (s = 10,
   30: ``net.transverse_modulus`` / s; K_fin and K_body scale with it, Eq. (30)) against the
   shipped K. At a force F the Hertz contact gives way by δ = (F/K)^(1/m); the K / s contact by
   s^(1/m) δ, an extra (s^(1/m) − 1) δ. An elastic fin adds its displacement u to the contact's
   give (compliances in series). Where u is below that extra give at the fins' largest contact
   force, the softened run moves the rope–fin kinematics more than the fin does and its headline
   differences bound the fin's effect (if the headlines depend monotonically on the give);
   where u is larger, that run does not cover the fin, and the row says so (ratio > 1);
2. energy: the work of the contact loads on the moving fin surface (the shell history's
   ``external_work_j``) is energy a rigid fin does not take; over the energy the missile
   exchanges it is, to first order, the relative change of that exchange (and of Δv);
3. velocity: the fin's RMS velocity sqrt(2 KE_max / m_fin) (shell ``kinetic_energy_j``) over
   the impact speed: the order of the relative change of the rope–fin velocity the contact sees.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from flexnet_fe.study.common import HEADLINE_TOLERANCE, Context, measured, rel_error
from flexnet_fe.study.scenes import CASE, FULL_COLLIDE, case_with

LOG = logging.getLogger("flexnet.study.one_way")

SOFT_FACTORS = (10.0, 30.0)
"""The contact stiffness is divided by these (a decade, and the factor that covers the fins'
largest displacement on radar_traction: u / extra give = 1.56 at 10, 0.66 at 30)."""
SHELL_MESH = ("shell.local_mesh_size=0.005", "shell.peak_check=false", "shell.strike_envelope=false")
"""Fin element size at the loads for the bound: 5 mm (the shell study's coarsest point: the largest
displacement of its fin within 1.6 % of the 0.625 mm reference; stresses are not used here)."""
HEADLINES = ("dv_over_v", "fin_impulse_ns", "peak_accel_mps2")
LABEL = "rigid fins in the collision (one-way loading)"


def _collide(ctx: Context, extra: tuple[str, ...]):
    """(case, CollisionResult) of the default impact with ``extra`` overrides (deployed net of the
    study's deploy, shared: no override here changes the deployment)."""
    from flexnet_fe.study.collide import deploy_dir, simulate_case

    case = case_with(CASE, FULL_COLLIDE + extra)
    return case, simulate_case(case, deploy_dir(ctx))[2]


def _shell_fins(ctx: Context, case, res) -> dict:
    """Shell stage on every loaded fin under ``res``'s loads: {fin: (summary, history columns)}."""
    from flexnet_fe.collide.stage import write_outputs
    from flexnet_fe.io import read_history_csv
    from flexnet_fe.missile.build import build_missile
    from flexnet_fe.runs import FIN_CONTACTS, HISTORY
    from flexnet_fe.shell.stage import fin_specs, run_shell
    from flexnet_fe.study.shell import fin_mesh

    loads = ctx.scratch("one_way_loads")
    net = res.net
    missile = build_missile(case.missile)
    write_outputs(res, net.model.springs[res.alive], net.rest_length[res.alive], net.model.stiffness[res.alive],
                  missile, loads)
    scase = case_with(CASE, FULL_COLLIDE + SHELL_MESH)
    meshes = {f.name: fin_mesh(scase.missile, f.name, ctx.scratch("one_way_mesh")) for f in missile.fins}
    out = ctx.scratch("one_way_shell")
    s = run_shell(scase.shell, fin_specs(missile.fins, meshes), loads / FIN_CONTACTS, loads / HISTORY, out, LOG)
    return {f.name: (s[f.name], read_history_csv(out / f.name / HISTORY), f) for f in missile.fins if f.name in s}


def _row(without: str, headline: str, with_value, without_value, diff, cost, matters) -> dict:
    return {"simplification": LABEL, "without": without, "stage": "collide+shell", "headline": headline,
            "with_value": with_value, "without_value": without_value, "difference_rel": diff,
            "cost_with_s": cost[0], "cost_without_s": cost[1], "matters": matters}


def bound_measures(res, fins: dict, k_fin: float, exponent: float, speed: float, soft: float = 10.0) -> dict:
    """The three measures of the module docstring from the default collision ``res``, the shell
    results ``fins`` ({fin: (summary, history, fin)}), K_fin [N/m^m], exponent m and the impact
    speed [m/s]: largest fin displacement u [m], largest fin contact force F [N] (one rope segment
    on one fin, interval mean), its Hertz give δ [m] and the K/soft extra give [m], their ratio;
    Σ fin external work [J] and its fraction of the energy exchanged; largest RMS fin speed [m/s]
    and its fraction of the impact speed."""
    u = max(s["max_abs_u_m"] for s, _, _ in fins.values())
    f_max = float(np.linalg.norm(res.loads.force, axis=1).max(initial=0.0))
    delta = (f_max / k_fin) ** (1.0 / exponent)
    extra = (soft ** (1.0 / exponent) - 1.0) * delta
    work = sum(float(np.max(np.abs(h["external_work_j"]))) for _, h, _ in fins.values())
    v_rms = max(math.sqrt(2.0 * float(np.max(h["kinetic_energy_j"])) / (f.area * f.thickness * f.material.density))
                for _, h, f in fins.values())
    exchanged = res.summary["energy_exchanged_j"]
    return {"u_max_m": u, "f_max_n": f_max, "give_m": delta, "extra_give_m": extra, "u_over_extra": u / extra,
            "work_j": work, "work_rel": work / exchanged, "v_rms_mps": v_rms, "v_rel": v_rms / speed}


def _soft_rows(ctx: Context, case, s: dict, c_def: float, m: dict) -> tuple[list[dict], set]:
    """(headline rows of each softened contact (``SOFT_FACTORS``) and its u / extra-give row, the
    factors whose softened run stopped — a rope through a fin: that contact gives no bound)."""
    from flexnet_fe.errors import NumericalError

    e_t, out, stopped = case.net.transverse_modulus, [], set()
    for f in SOFT_FACTORS:
        without = f"contact stiffness K / {f:g} (net.transverse_modulus {e_t / f:g} Pa)"
        try:
            (_, soft), c_soft, _ = measured(lambda: _collide(ctx, (f"net.transverse_modulus={e_t / f:g}",)))
        except NumericalError as err:  # the softened rope passes through a fin: no bound from it
            out.append(_row(without, "run", None, f"stopped: {str(err).split(';')[0]}", math.nan, (c_def, math.nan),
                            None))
            stopped.add(f)
            continue
        t = soft.summary
        for h in HEADLINES:
            d = rel_error(s[h], t[h])
            out.append(_row(without, h, max(s[h].values()) if isinstance(s[h], dict) else s[h],
                            max(t[h].values()) if isinstance(t[h], dict) else t[h], d, (c_def, c_soft),
                            bool(d > HEADLINE_TOLERANCE)))
        mf = m[f]
        out.append(_row(f"elastic fins: largest fin displacement u against the K/{f:g} contact's extra give at "
                        "the largest fin contact force", f"u / extra give (≤ 1: the K/{f:g} rows bound the fins)",
                        mf["extra_give_m"], mf["u_max_m"], mf["u_over_extra"], (c_def, c_soft), None))
    return out, stopped


def rows(ctx: Context, notes: list[str]) -> list[dict]:
    """The one-way rows (full study only; the quick study notes that it skips them)."""
    if ctx.quick:
        notes.append("one-way fin loading bound (softened contact, fin work and speed): full study only")
        return []
    (case, res), c_def, _ = measured(lambda: _collide(ctx, ()))
    fins, c_shell, _ = measured(lambda: _shell_fins(ctx, case, res))
    s = res.summary
    m = {f: bound_measures(res, fins, s["contact_stiffness_fin"], case.collide.contact_exponent,
                           case.collide.impact_speed, f) for f in SOFT_FACTORS}
    out, stopped = _soft_rows(ctx, case, s, c_def, m)
    m0 = m[SOFT_FACTORS[0]]
    out.append(_row("elastic fins: work of the contact loads on the moving fins (shell, one-way)",
                    "Σ fin external work / energy exchanged", 0.0, m0["work_j"], m0["work_rel"], (c_def, c_shell),
                    bool(m0["work_rel"] > HEADLINE_TOLERANCE)))
    out.append(_row("elastic fins: largest RMS fin speed (shell kinetic energy)", "fin RMS speed / impact speed",
                    0.0, m0["v_rms_mps"], m0["v_rel"], (c_def, c_shell), bool(m0["v_rel"] > HEADLINE_TOLERANCE)))
    cover = [f"K/{f:g}: the softened run stopped (tunnelling), no bound" if f in stopped else
             f"K/{f:g}: {m[f]['u_over_extra']:.3g} ({'bounds' if m[f]['u_over_extra'] <= 1 else 'does NOT bound'})"
             for f in SOFT_FACTORS]
    notes.append(
        f"one-way fin loading (cases/radar_traction as shipped; shell at {SHELL_MESH[0].split('=')[1]} m at the loads, "
        f"all {len(fins)} loaded fins): largest fin displacement {1e3 * m0['u_max_m']:.3g} mm; largest fin contact "
        f"force {m0['f_max_n']:.4g} N, Hertz give {1e6 * m0['give_m']:.3g} µm; u / extra give of the softened "
        f"contact: {'; '.join(cover)}; the fins took {m0['work_j']:.3g} J ({m0['work_rel']:.2%} of the "
        f"{s['energy_exchanged_j']:.4g} J exchanged) and moved at ≤ {m0['v_rms_mps']:.3g} m/s RMS "
        f"({m0['v_rel']:.2%} of the impact speed)")
    return out
