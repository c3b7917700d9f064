"""The collide stage with the fins' elasticity fed back (``[collide] fin_coupling = "staggered"``;
issue 15 §3; docs/validation.md, "The staggered fin coupling").

The collision treats the fins as rigid and the shell stage loads them afterwards (one-way). On
radar × rotary that overstates rudder_4's impulse by ≈ 3 %: the rudder gives way under the rope
(``study.one_way``). The staggered coupling takes one step of the Gauss–Seidel iteration of the
coupled problem:

1. the impact with rigid fins (``collide.stage.run_collide``, no resolution check, no plots);
2. every loaded fin's normal displacement w(u, v, t) under those loads, by the shell stage's own
   functions on a mesh of ``MOTION_LOCAL_MESH`` at the loads, sampled every ``MOTION_INTERVAL``
   (``shell.motion``);
3. the impact again with each fin's mid-surface displaced by w and moving at ẇ
   (``collide.model.FinMotion``), with the case's resolution check: the stage's result and files.

One step suffices when the fins' effect on the loads is small: the loads of step 3 differ from
those of step 1 by a fraction ε (≈ 3 % on rudder_4, < 0.5 % elsewhere), w by as much, so a second
step would move the loads by ≈ ε² (≈ 0.1 %). Measured on radar × rotary
(``benchmarks/coupling_iteration.py``): the second step moves rudder_4's impulse +0.04 % after the
first's −3.13 %, every other headline ≤ 0.06 % but a 0.03 N s graze. The summary's
``fin_coupling`` section records the rigid impact's headlines and each one's move, so ε is read
from every run.
"""

from __future__ import annotations

import logging
import shutil
import time
from pathlib import Path

import numpy as np

from flexnet_fe.collide.stage import run_collide
from flexnet_fe.io import read_history_csv
from flexnet_fe.runs import HISTORY
from flexnet_fe.shell.motion import fin_motion

MOTION_LOCAL_MESH = 0.005
"""[m] Fin element size at the loads for the fins' motion: the largest displacement of a paper fin at
5 mm is within 1.6 % of its 0.625 mm value (docs/study, the shell study's coarsest point); the motion
moves the headlines by a few per cent at most, so its own error enters them as a few hundredths of a
per cent. Stresses are not taken from this run."""
MOTION_INTERVAL = 1e-6
"""[s] The motion's sample interval (the strikes last 1–4 µs; linear in time between samples)."""
HEADLINES = ("dv_over_v", "peak_accel_mps2")


def run_staggered(net_cfg, deploy_cfg, missile_cfg, collide_cfg, shell_cfg, air, deploy_dir: Path | None,
                  stage_dir: Path, log: logging.Logger, *, motion_mesh: float = MOTION_LOCAL_MESH) -> dict:
    """The collide stage under the staggered coupling (module docstring): the files of the moving-fin
    impact in ``stage_dir`` and its summary, with ``fin_coupling`` (``coupling_section``). Work files
    (the rigid impact's, the fins' shell runs) in ``stage_dir/coupling``, removed at the end.
    ``motion_mesh`` [m]: the fins' element size at the loads for the motion (tests use coarser)."""
    stage_dir = Path(stage_dir)
    work = stage_dir / "coupling"
    t0 = time.perf_counter()
    log.info("collide (fin coupling): 1 of 3, the impact with rigid fins")
    rigid = run_collide(net_cfg, deploy_cfg, missile_cfg, collide_cfg.model_copy(update={"resolution_check": False}),
                        air, deploy_dir, work / "rigid", log, plots=False)
    t1 = time.perf_counter()
    log.info("collide (fin coupling): 2 of 3, the loaded fins' motion (shell at %.3g mm at the loads, sampled "
             "every %.3g µs)", 1e3 * motion_mesh, 1e6 * MOTION_INTERVAL)
    motion, fins = fin_motion(missile_cfg, motion_shell(shell_cfg, motion_mesh), work / "rigid", work / "shell",
                              interval=MOTION_INTERVAL, log=log)
    t2 = time.perf_counter()
    w_max = float(np.abs(motion.w).max(initial=0.0))
    log.info("collide (fin coupling): 3 of 3, the impact with the fins moving (%d loaded fins, largest |w| %.3g mm)",
             len(fins), 1e3 * w_max)
    s = run_collide(net_cfg, deploy_cfg, missile_cfg, collide_cfg, air, deploy_dir, stage_dir, log, fin_motion=motion)
    work_j = float(read_history_csv(stage_dir / HISTORY)["fin_motion_work_j"][-1])
    s["fin_coupling"] = coupling_section(rigid, s, w_max, work_j,
                                         {"rigid_impact": t1 - t0, "fin_motion": t2 - t1,
                                          "moving_impact": time.perf_counter() - t2})
    s["fin_coupling"].update(motion_mesh_m=motion_mesh, motion_interval_s=MOTION_INTERVAL,
                             moving_fins=sorted(fins))
    shutil.rmtree(work)
    c = s["fin_coupling"]
    log.info("collide (fin coupling): against rigid fins Δv/v %s, the CFC peak %s, fin impulses %s; the fins' work "
             "on the rope %.3g J", _pct(c["dv_over_v_move_rel"]), _pct(c["peak_accel_move_rel"]),
             ", ".join(f"{f} {_pct(m)}" for f, m in c["fin_impulse_move_rel"].items() if m is not None) or "none",
             work_j)
    return s


def motion_shell(shell_cfg, motion_mesh: float):
    """The shell table for the fins' motion: the case's (material model, step, mass scaling, supports)
    on every loaded fin (whatever fins the shell stage reports), over the whole collision (no
    end_time), at ``motion_mesh`` [m] at the loads."""
    from flexnet_fe.shell.config import FinSelection

    return shell_cfg.model_copy(update={"local_mesh_size": motion_mesh, "fins": FinSelection.LOADED, "fin_names": (),
                                        "end_time": None})


def coupling_section(rigid: dict, coupled: dict, w_max: float, work_j: float, wall_s: dict) -> dict:
    """The summary's ``fin_coupling`` section from the rigid and the moving-fin impacts' summaries:
    the rigid headlines (Δv/v, CFC peak [m/s²], per-fin impulse [N s]); each one's relative move
    coupled/rigid − 1 (``*_move_rel``, named as the resolution check's; per fin over its own rigid
    impulse, None for a fin with none); the fin impulses' move as the study measures it
    (``fin_impulse_largest_move_rel``: largest |ΔJ_f| over the largest J_f — a graze's own relative
    move, 0.03 N s scattering by ×6, says little); the largest |w| [m]; the fins' work on the rope
    [J]; the three parts' wall times [s]."""
    jr, jc = rigid["fin_impulse_ns"], coupled["fin_impulse_ns"]
    fins = sorted(set(jr) | set(jc))
    largest = max(jr.values(), default=0.0)
    return {"scheme": "staggered, one step (rigid impact, fins' motion, impact with the fins moving)",
            "rigid": {**{h: rigid[h] for h in HEADLINES}, "fin_impulse_ns": dict(jr)},
            "dv_over_v_move_rel": _move(coupled["dv_over_v"], rigid["dv_over_v"]),
            "peak_accel_move_rel": _move(coupled["peak_accel_mps2"], rigid["peak_accel_mps2"]),
            "fin_impulse_move_rel": {f: _move(jc.get(f, 0.0), j) for f, j in jr.items()},
            "fin_impulse_largest_move_rel": (max(abs(jc.get(f, 0.0) - jr.get(f, 0.0)) for f in fins) / largest
                                             if largest > 0 else None),
            "max_abs_w_m": w_max, "fin_motion_work_j": work_j, "wall_s": wall_s}


def _move(new: float, old: float) -> float | None:
    """new / old − 1, or None when there is nothing to compare with (old = 0: no contact there)."""
    return new / old - 1.0 if old > 0 else None


def _pct(m: float | None) -> str:
    return "—" if m is None else f"{100 * m:+.3f} %"
