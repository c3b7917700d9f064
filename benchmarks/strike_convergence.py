"""Does one rope strike's peak fin stress converge as the rope is cut finer? (issue 10 §2, issue 9 §6)

The default case's rudder peaks come from the first strike of the rope on each leading edge, 5–9 µs
after the fin's load starts, and they moved −31 … +21 % when the rope's pieces at the fins went from
0.7 to 1.4 mm while the fin impulses agreed within 0.42 % (docs/validation.md, "Line contact as the
default"). That case's rope arrives at the rudders after 8 ms of dragging over the nose and the
wings, so two runs that differ in round-off already give peaks 2–16 % apart. This benchmark takes
the rope's history out: one strike, nothing before it.

Scene (tests/collide/test_collide.py's fin-edge scene, the case's rope contact): a 0.1 m square of
the paper's rope (E = 1 MPa, ρ = 1000 kg/m³, d = 4.5 mm, E_t = 10 GPa as in cases/radar_traction)
0.3 m off the path; its two x-ropes cross wing_1's plane at their midpoints; the radar missile at
500 m/s, no air, the case's [collide] contact settings (line law, Lankarani–Nikravesh e = 0.5,
μ = 0.2, load_interval 0.3125 µs), the rope cut to ``fin_piece_length = fin_piece_chord = ℓ`` at the
fins. The rope strikes wing_1's leading edge (≈ 3 ms) and, having slid off it, rudder_1 (≈ 7 ms).
Then the case's [shell] stage (clamped root, 1.25 mm at the loads, structural peak outside the
St-Venant zones, ZZ estimate) on the loads of each ℓ, run through the production pipeline
(``pipeline.run_case`` with this collision in place of the collide stage).

    PYTHONPATH=.:tests/collide .venv/bin/python benchmarks/strike_convergence.py OUT.jsonl RUNS_DIR \
        [--pieces 1.4 0.7 0.35 0.175] [--until 8e-3]

Data: docs/data/strike_convergence.jsonl (key ``line_law``: the rows of 2026-11-28 03:59–04:04 UTC
ran the line law per metre of current length, the others per metre of rest length, as shipped);
docs/validation.md, "The line law per metre of rest length".

Each row (one per ℓ): the collision's fin impulses [N s], largest resultant fin force [N] at the
load sampling and its time, energy balance, CPU [s]; the shell's per-fin peaks [Pa], their times,
ZZ estimates; load, machine, date."""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import time
from pathlib import Path

import numpy as np

from flexnet_fe.config import load_case
from flexnet_fe.io import write_history_csv
from flexnet_fe.pipeline import run_case
from flexnet_fe.stages import Stage

CASE = Path(__file__).resolve().parent.parent / "cases" / "radar_traction"
LOG = logging.getLogger("strike_convergence")
LOG.setLevel(logging.ERROR)


def scene_net():
    """The fin-edge scene with the case's transverse modulus (10 GPa)."""
    import conftest as C  # tests/collide/conftest.py (on PYTHONPATH)

    net = C.flat_net(0.1, 0.1, transverse_modulus=1.0e10)
    x = np.array(net.x)
    x[:, 1] += 0.3
    return C.moved(net, x)


def peak_force(loads, fin: int) -> tuple[float, float]:
    """Largest resultant force [N] on fin ``fin`` over the load samples, and its time [s]."""
    rows = np.repeat(np.arange(len(loads.t)), np.diff(loads.row_start))
    sel = loads.fin == fin
    f = np.zeros((len(loads.t), 3))
    np.add.at(f, rows[sel], loads.force[sel])
    mag = np.linalg.norm(f, axis=1)
    k = int(np.argmax(mag))
    return float(mag[k]), float(loads.t[k])


def collide_stage(piece: float, until: float, record: dict):
    """A collide-stage function for ``run_case``: the scene's collision, written as the stage's files."""

    def run(ctx):
        from flexnet_fe.collide.simulate import simulate
        from flexnet_fe.missile.build import build_missile

        missile = build_missile(ctx.case.missile)
        cfg = ctx.case.collide.model_copy(update={
            "net_source": "flat_taut", "duration": until, "max_duration": until, "crop": False,
            "aim_point": (0.0, 0.0), "air": False, "resolution_check": False, "fin_split_margin": 0.03,
            "fin_piece_length": piece, "fin_piece_chord": piece})
        c0 = time.process_time()
        res = simulate(scene_net(), missile, cfg, 9.81, LOG)
        cpu = time.process_time() - c0
        ld, s = res.loads, res.summary
        np.savez(ctx.stage_dir / "fin_contacts.npz", fin_names=ld.fin_names.astype(str), t=ld.t,
                 row_start=ld.row_start.astype(np.int64), fin=ld.fin.astype(np.int32), point=ld.point,
                 force=ld.force, width=ld.width)
        h = res.history
        np.savez(ctx.stage_dir / "accel_body.npz", t=h["t_s"],
                 accel_body=np.column_stack([h[f"accel_body_{c}_mps2"] for c in "xyz"]))
        write_history_csv(ctx.stage_dir / "history.csv", h)
        names = [str(n) for n in ld.fin_names]
        record.update(collide_cpu_s=cpu, steps=s["steps"], dt_s=s["dt_s"], energy_error_rel=s["energy_error_rel"],
                      end_s=float(h["t_s"][-1]), cut_segments=s.get("cut_segments"),
                      fin_impulse_ns={k: v for k, v in s["fin_impulse_ns"].items() if v > 0.0})
        record["peak_force_n"] = {}
        for i, n in enumerate(names):
            if np.any(ld.fin == i):
                record["peak_force_n"][n] = peak_force(ld, i)
        return {"fin_impulse_ns": record["fin_impulse_ns"]}

    return run


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("runs")
    ap.add_argument("--pieces", type=float, nargs="+", default=[1.4, 0.7, 0.35, 0.175], help="piece length ℓ [mm]")
    ap.add_argument("--until", type=float, default=8e-3, help="collision end [s]")
    ap.add_argument("--sets", nargs="*", default=[], help="extra case overrides (shell.*)")
    args = ap.parse_args()
    for mm in args.pieces:
        piece = mm * 1e-3
        case, case_dir = load_case(CASE, [f"shell.end_time={args.until}", 'collide.net_source="flat_taut"', *args.sets])
        run_dir = Path(args.runs) / f"piece_{mm:g}mm"
        rec = {"piece_mm": mm, "until_s": args.until, "sets": args.sets}
        run_case(case, case_dir, run_dir, [Stage.collide],
                 stage_funcs={Stage.collide: collide_stage(piece, args.until, rec)}, force=True)
        c0 = time.perf_counter()
        summ = run_case(case, case_dir, run_dir, [Stage.shell], force=True)
        rec["shell_wall_s"] = time.perf_counter() - c0
        rec["shell"] = {k: {f: v[f] for f in ("peak_von_mises_pa", "peak_time_s", "peak_nodal_von_mises_pa",
                                              "peak_error_estimate_rel", "start_time_s", "peak_bearing_force_n",
                                              "peak_bearing_pa", "dofs", "steps")}
                        for k, v in summ["shell"].items() if isinstance(v, dict) and "peak_von_mises_pa" in v}
        rec.update(load=os.getloadavg()[0], machine=platform.processor() or platform.machine(),
                   date=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()))
        with open(args.out, "a") as f:
            f.write(json.dumps(rec) + "\n")
        print(json.dumps(rec), flush=True)


if __name__ == "__main__":
    main()
