"""The coupled impact under the rope's resolution at the fins, the fins' motion held fixed (issue 9 §6,
``collide.fin_coupling = "staggered"``; docs/validation.md, "The staggered fin coupling").

    PYTHONPATH=. .venv/bin/python benchmarks/coupled_resolution.py RUN_DIR WORK_DIR OUT.jsonl \
        PIECE:CHORD [PIECE:CHORD ...] [--rigid]

RUN_DIR: a run whose collide stage used the staggered coupling (its ``resolved.json`` gives the case, its
``collide/`` the loads of the impact with the fins moving). The fins' motion under those loads is
computed once, as the stage computes it (``shell.motion.fin_motion``, ``shell.coupling``'s mesh and
sampling: the coupling's second step, which moves the headlines by ≤ 0.06 %,
docs/data/coupling_iteration_radar_rotary.json), and the impact is run with that motion at each
``collide.fin_piece_length`` : ``collide.fin_piece_chord`` pair [m] given. One JSON row per pair is
appended to OUT.jsonl: Δv/v, the CFC peak, the per-fin impulses, the energy error, steps, wall and CPU
times. The stage's resolution check is one such pair (pieces and chords halved, the same motion); this
gives the series its observed order needs. ``--rigid``: the same impacts with rigid fins (no motion), the
one-way model's series beside it.
"""
from __future__ import annotations

import json
import logging
import os
import sys
import time
from pathlib import Path

logging.basicConfig(level=logging.WARNING)


def main(run_dir: str, work: str, out: str, *pairs: str) -> None:
    rigid = "--rigid" in pairs
    pairs = tuple(p for p in pairs if p != "--rigid")
    import flexnet_fe.collide.scene  # noqa: F401  (before study.collide: import order)
    from flexnet_fe.config import Case
    from flexnet_fe.shell.coupling import MOTION_INTERVAL, MOTION_LOCAL_MESH, motion_shell
    from flexnet_fe.shell.motion import fin_motion
    from flexnet_fe.study.collide import simulate_case

    run = Path(run_dir)
    case = Case.model_validate(json.loads((run / "resolved.json").read_text())["case"])
    t0 = time.perf_counter()
    motion = None
    if not rigid:
        motion, fins = fin_motion(case.missile, motion_shell(case.shell, MOTION_LOCAL_MESH), run / "collide",
                                  Path(work) / "shell", interval=MOTION_INTERVAL)
        print(f"motion of {sorted(fins)} in {time.perf_counter() - t0:.0f} s; largest |w| "
              f"{1e3 * float(abs(motion.w).max()):.3f} mm", flush=True)
    for pair in pairs:
        piece, chord = (float(v) for v in pair.split(":"))
        c = case.model_copy(update={"collide": case.collide.model_copy(
            update={"fin_piece_length": piece, "fin_piece_chord": chord})})
        w0, c0 = time.perf_counter(), time.process_time()
        s = simulate_case(c, run / "deploy", fin_motion=motion)[2].summary
        row = {"run": str(run), "fins": "rigid" if rigid else "moving", "fin_piece_length_m": piece, "fin_piece_chord_m": chord,
               "dv_over_v": s["dv_over_v"], "peak_accel_mps2": s["peak_accel_mps2"],
               "fin_impulse_ns": s["fin_impulse_ns"], "energy_error_rel": s.get("energy_error_rel"),
               "steps": s.get("steps"), "wall_s": time.perf_counter() - w0, "cpu_s": time.process_time() - c0,
               "load": os.getloadavg()}
        with open(out, "a") as f:
            f.write(json.dumps(row) + "\n")
        print(json.dumps({k: row[k] for k in ("fin_piece_length_m", "fin_piece_chord_m", "dv_over_v",
                                              "fin_impulse_ns", "wall_s")}), flush=True)


if __name__ == "__main__":
    main(*sys.argv[1:])
