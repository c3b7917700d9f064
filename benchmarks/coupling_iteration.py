"""The staggered fin coupling's second step: is one step enough? (``shell.coupling``; docs/validation.md,
"The staggered fin coupling").

    PYTHONPATH=. .venv/bin/python benchmarks/coupling_iteration.py RUN_DIR WORK_DIR OUT_JSON

RUN_DIR: a run whose collide stage used ``collide.fin_coupling = "staggered"`` (its ``resolved.json`` gives
the case, its ``collide/`` the loads of the impact with the fins moving: step 1). This takes the
iteration's second step the same way — the loaded fins' motion under step 1's loads (``shell.motion``,
the stage's mesh and sampling), then the impact again with the fins moving so — and writes the three
impacts' headlines (rigid = step 0, the stage's = step 1, this = step 2) and the moves between them. A
contraction (|step 2 − step 1| ≪ |step 1 − step 0|) says the stage's single step is converged to about
that difference."""
from __future__ import annotations

import json
import logging
import sys
import time
from pathlib import Path

logging.basicConfig(level=logging.WARNING)


def _moves(a: dict, b: dict) -> dict:
    """b / a − 1 of Δv/v, the CFC peak and each fin's impulse (None where a has none), as the stage's
    ``fin_coupling`` section computes them (``shell.coupling.coupling_section``)."""
    from flexnet_fe.shell.coupling import coupling_section

    c = coupling_section(a, b, 0.0, 0.0, {})
    return {"dv_over_v": c["dv_over_v_move_rel"], "peak_accel_mps2": c["peak_accel_move_rel"],
            "fin_impulse_ns": c["fin_impulse_move_rel"]}


def main(run_dir: str, work: str, out: str) -> None:
    import flexnet_fe.collide.scene  # noqa: F401  (before study.collide: import order)
    from flexnet_fe.config import Case
    from flexnet_fe.shell.coupling import MOTION_INTERVAL, MOTION_LOCAL_MESH, motion_shell
    from flexnet_fe.shell.motion import fin_motion
    from flexnet_fe.study.collide import simulate_case

    run = Path(run_dir)
    resolved = json.loads((run / "resolved.json").read_text())
    case = Case.model_validate(resolved["case"])
    step1 = json.loads((run / "summary.json").read_text())["collide"]
    step0 = step1["fin_coupling"]["rigid"]
    t0 = time.perf_counter()
    motion, fins = fin_motion(case.missile, motion_shell(case.shell, MOTION_LOCAL_MESH), run / "collide",
                              Path(work) / "shell", interval=MOTION_INTERVAL)
    t1 = time.perf_counter()
    step2 = simulate_case(case, run / "deploy", fin_motion=motion)[2].summary
    t2 = time.perf_counter()
    keep = ("dv_over_v", "peak_accel_mps2", "fin_impulse_ns")
    rec = {"run": str(run), "step0_rigid": step0, "step1_stage": {k: step1[k] for k in keep},
           "step2": {k: step2[k] for k in keep}, "moves_1_over_0": _moves(step0, step1),
           "moves_2_over_1": _moves(step1, step2), "max_abs_w_step2_m": float(abs(motion.w).max()),
           "moving_fins": sorted(fins), "wall_s": {"fin_motion": t1 - t0, "impact": t2 - t1}}
    Path(out).write_text(json.dumps(rec, indent=1))
    m1, m2 = rec["moves_1_over_0"]["fin_impulse_ns"], rec["moves_2_over_1"]["fin_impulse_ns"]
    print("fin impulse moves, step 1 / step 0 and step 2 / step 1:",
          {f: (m1[f], m2.get(f)) for f in m1 if m1[f] is not None}, f"→ {out}")


if __name__ == "__main__":
    main(*sys.argv[1:4])
