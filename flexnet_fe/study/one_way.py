"""One-way fin loading (issue 15 §3): what the fins' elasticity does to the collision headlines,
measured with a second model — the collision run again with the fins moving as the shell stage
says they do.

The collision treats the fins as rigid; the shell stage then loads the elastic fins with the
collision's contact forces (one-way). The check (:func:`rows`, full study only) takes one step of
the staggered (Gauss–Seidel) iteration of the coupled problem:

1. the default impact with rigid fins (``study.collide.simulate_case``);
2. the shell stage on every loaded fin under those loads (5 mm at the loads), each fin's normal
   displacement w(u, v, t) sampled on a grid every 1 µs (``shell.motion``, as ``shell.coupling`` does);
3. the same impact with each fin's mid-surface displaced by w and moving at ẇ
   (``collide.model.FinMotion``: the rope meets the fin where the shell put it and at its speed;
   the missile still takes every contact force; the moving surfaces' work on the rope is booked,
   so the energy balance still closes), and again with w doubled and halved (``SCALES``).

The headline differences 3 − 1 are the first correction of the iteration: the coupled solution
differs from the one-way one by that correction to first order in the fins' compliance. Run at 2w,
w and w/2, a correction that scales with w is the fins' effect; one that does not is the
collision's sensitivity to any small change (the noise floor of these headlines, ≈ 1 % on a
rudder's impulse between aim points 1 mm apart: docs/validation.md, "Where the rope strikes").
The fins' work on the rope over the energy exchanged and their largest RMS speed over the impact
speed are recorded beside them (the measures the check had before it: they bound nothing alone).
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np

from flexnet_fe.study.collide import SHIPPED
from flexnet_fe.study.common import HEADLINE_TOLERANCE, Context, measured, rel_error
from flexnet_fe.study.scenes import CASE, case_with

LOG = logging.getLogger("flexnet.study.one_way")

# The motion is the staggered coupling's (``shell.coupling``: 5 mm at the loads, ``MOTION_LOCAL_MESH``;
# sampled every 1 µs, ``MOTION_INTERVAL``): this check is that coupling's step, run as a study.
SCALES = (2.0, 1.0, 0.5)
"""The second collision with w × each of these (module docstring: the fins' effect must scale with w).
2: the sampled motion may read low — its largest surface speed grows 7 % from 1 to 0.5 µs samples
(rudder_3, 16.2 → 17.3 m/s), and a 41 × 41 grid (9–22 mm) smooths the dent under a 4.5 mm rope —
so the check also imposes twice what was sampled."""
HEADLINES = ("dv_over_v", "fin_impulse_ns", "peak_accel_mps2")
LABEL = "rigid fins in the collision (one-way loading)"


def _collide(case_path: Path, ddir: Path, motion=None):
    """(case, CollisionResult) of the case's impact as shipped (``study.collide.SHIPPED``: its fin loads at
    the case's own sampling — the shell's motion under the strikes is what the second collision sees) on
    the deployed net in ``ddir``, the fins moving as ``motion`` if given."""
    from flexnet_fe.study.collide import simulate_case

    case = case_with(case_path, SHIPPED)
    return case, simulate_case(case, ddir, fin_motion=motion)[2]


def _shell_fins(case_path: Path, res, work: Path):
    """(FinMotion of every loaded fin under ``res``'s loads, {fin: (summary, history columns, fin)})."""
    from flexnet_fe.collide.stage import write_outputs
    from flexnet_fe.missile.build import build_missile
    from flexnet_fe.shell.coupling import MOTION_INTERVAL, MOTION_LOCAL_MESH, motion_shell
    from flexnet_fe.shell.motion import fin_motion

    scase = case_with(case_path, SHIPPED)
    loads = work / "loads"
    loads.mkdir(parents=True, exist_ok=True)
    net = res.net
    write_outputs(res, net.model.springs[res.alive], net.rest_length[res.alive], net.model.stiffness[res.alive],
                  build_missile(scase.missile), loads)
    return fin_motion(scase.missile, motion_shell(scase.shell, MOTION_LOCAL_MESH), loads, work / "shell",
                      interval=MOTION_INTERVAL, log=LOG)


def check(case_path: Path, ddir: Path, work: Path) -> dict:
    """The check of the module docstring on one case (its impact on the deployed net in ``ddir``; work
    files in ``work``): {"case", "rigid" (summary), "moving" [(scale, summary, fins' work on the rope
    [J], CPU [s])] (summary None and the reason in place of the work when w × scale reaches a fin's
    rope radius + half-thickness), "fins" ({fin: (shell summary, history, fin)}), "cpu_rigid_s",
    "cpu_shell_s"}."""
    (case, res), c_rigid, _ = measured(lambda: _collide(case_path, ddir))
    (motion, fins), c_shell, _ = measured(lambda: _shell_fins(case_path, res, Path(work)))
    moving = []
    for scale in SCALES:
        try:
            (_, moved), c_moved, _ = measured(lambda: _collide(case_path, ddir, scaled(motion, scale)))
        except ValueError as err:  # w × scale reaches a fin's r + h/2 (model.with_fin_motion): not imposed
            moving.append((scale, None, str(err), 0.0))
            continue
        moving.append((scale, moved.summary, float(moved.history["fin_motion_work_j"][-1]), c_moved))
    return {"case": case, "rigid": res.summary, "moving": moving, "fins": fins, "cpu_rigid_s": c_rigid,
            "cpu_shell_s": c_shell}


def scaled(motion, scale: float):
    """``motion`` with w × scale."""
    return motion._replace(w=motion.w * scale)


def _row(without: str, headline: str, with_value, without_value, diff, cost, matters) -> dict:
    return {"simplification": LABEL, "without": without, "stage": "collide+shell", "headline": headline,
            "with_value": with_value, "without_value": without_value, "difference_rel": diff,
            "cost_with_s": cost[0], "cost_without_s": cost[1], "matters": matters}


def _value(v):
    return max(v.values()) if isinstance(v, dict) else v


def difference_rows(rigid: dict, moving: dict, scale: float, cost: tuple[float, float]) -> list[dict]:
    """Rows of the headline differences between the rigid-fin summary and a moving-fin one (w × scale):
    the study's three headlines (per-fin impulse: max over fins / the largest, ``rel_error``) and each
    fin's impulse over its own value; a difference above 2 % matters."""
    without = f"elastic fins: the collision again with the fins moving as the shell computed (w × {scale:g})"
    out = []
    for h in HEADLINES:
        d = rel_error(moving[h], rigid[h])
        out.append(_row(without, h, _value(rigid[h]), _value(moving[h]), d, cost, bool(d > HEADLINE_TOLERANCE)))
    for fin, ref in sorted(rigid["fin_impulse_ns"].items()):
        d = rel_error(moving["fin_impulse_ns"].get(fin, 0.0), ref)
        out.append(_row(without, f"fin_impulse_ns[{fin}]", ref, moving["fin_impulse_ns"].get(fin, 0.0), d, cost,
                        bool(d > HEADLINE_TOLERANCE)))
    return out


def motion_measures(work: float, exchanged: float, fins: dict, speed: float) -> dict:
    """From a moving-fin collision's work of the fins on the rope ``work`` [J] (history
    ``fin_motion_work_j`` at its end), the energy exchanged [J] and the shell results ``fins`` ({fin:
    (summary, history, fin)}): that work and its fraction of the energy exchanged; the largest fin
    displacement [m]; the largest RMS fin speed sqrt(2 KE_max / m_fin) [m/s] (shell
    ``kinetic_energy_j``) and its fraction of the impact speed ``speed`` [m/s]."""
    v_rms = max(math.sqrt(2.0 * float(np.max(h["kinetic_energy_j"])) / (f.area * f.thickness * f.material.density))
                for _, h, f in fins.values())
    return {"work_j": work, "work_rel": abs(work) / exchanged,
            "u_max_m": max(s["max_abs_u_m"] for s, _, _ in fins.values()), "v_rms_mps": v_rms,
            "v_rel": v_rms / speed}


def rows(ctx: Context, notes: list[str]) -> list[dict]:
    """The one-way rows (full study only; the quick study notes that it skips them)."""
    if ctx.quick:
        notes.append("one-way fin loading (the collision again with the fins moving as the shell computed): "
                     "full study only")
        return []
    from flexnet_fe.shell.coupling import MOTION_INTERVAL, MOTION_LOCAL_MESH
    from flexnet_fe.study.collide import deploy_dir

    c = check(CASE, deploy_dir(ctx), ctx.scratch("one_way"))
    rigid, fins, case = c["rigid"], c["fins"], c["case"]
    out, lines = [], []
    for scale, moved, work, c_moved in c["moving"]:
        if moved is None:
            lines.append(f"w × {scale:g}: not imposed ({work})")
            continue
        new = difference_rows(rigid, moved, scale, (c["cpu_rigid_s"], c["cpu_shell_s"] + c_moved))
        out += new
        m = motion_measures(work, moved["energy_exchanged_j"], fins, case.collide.impact_speed)
        lines.append(f"w × {scale:g}: largest headline difference {max(r['difference_rel'] for r in new):.3%}, the "
                     f"fins' work on the rope {m['work_j']:.3g} J ({m['work_rel']:.3%} of the energy exchanged), "
                     f"energy error {moved['energy_error_rel']:.3%}")
    notes.append(
        f"one-way fin loading (cases/radar_traction as shipped; shell at {MOTION_LOCAL_MESH:g} m at the loads, "
        f"{len(fins)} loaded fins, motion sampled every {MOTION_INTERVAL * 1e6:g} µs): largest fin displacement "
        f"{1e3 * m['u_max_m']:.3g} mm, largest RMS fin speed {m['v_rms_mps']:.3g} m/s ({m['v_rel']:.2%} of the "
        f"impact speed); the collision again with the fins moving so: {'; '.join(lines)}")
    return out
