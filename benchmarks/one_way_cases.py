"""The one-way check (``study.one_way.check``: the impact again with the fins moving as the shell stage
computed them, at 2w, w and w/2) on any case, for the paper cases the study does not run.

    PYTHONPATH=. .venv/bin/python benchmarks/one_way_cases.py CASE_DIR DEPLOY_DIR WORK_DIR OUT_JSON

DEPLOY_DIR: the ``deploy/`` folder of a run of that case (``flexnet run CASE_DIR --stages deploy``).
Writes one JSON object: the rigid and moving-fin headlines, their differences (``one_way.difference_rows``),
the fins' work on the rope, the motion's size, CPU times. Results: docs/validation.md, "One-way fin loading:
the collision again with the fins moving"; data docs/data/one_way_<case>.json."""
from __future__ import annotations

import json
import logging
import sys
import time
from pathlib import Path

import numpy as np

logging.basicConfig(level=logging.WARNING)


def main(case_dir: str, deploy_dir: str, work: str, out: str) -> None:
    import flexnet_fe.collide.scene  # noqa: F401  (before study.collide: import order)
    from flexnet_fe.study.one_way import check, difference_rows, motion_measures

    t0 = time.perf_counter()
    c = check(Path(case_dir), Path(deploy_dir), Path(work))
    case, rigid = c["case"], c["rigid"]
    keep = ("dv_over_v", "peak_accel_mps2", "fin_impulse_ns", "energy_error_rel", "passed_through")
    moving = []
    for scale, summary, work_j, cpu in c["moving"]:
        if summary is None:
            moving.append({"scale": scale, "not_imposed": work_j})
            continue
        m = motion_measures(work_j, summary["energy_exchanged_j"], c["fins"], case.collide.impact_speed)
        rows = difference_rows(rigid, summary, scale, (c["cpu_rigid_s"], cpu))
        moving.append({"scale": scale, "cpu_s": cpu, **{k: summary[k] for k in keep}, **m,
                       "differences": {r["headline"]: r["difference_rel"] for r in rows}})
    fins = {name: {"max_abs_u_m": s["max_abs_u_m"], "window_s": [float(h["t_s"][0]), float(h["t_s"][-1])]}
            for name, (s, h, _) in c["fins"].items()}
    rec = {"case": str(case_dir), "rigid": {k: rigid[k] for k in keep}, "cpu_rigid_s": c["cpu_rigid_s"],
           "cpu_shell_s": c["cpu_shell_s"], "moving": moving, "fins": fins, "wall_s": time.perf_counter() - t0}
    Path(out).write_text(json.dumps(rec, indent=1, default=lambda o: o.tolist() if isinstance(o, np.ndarray) else o))
    worst = {m["scale"]: max(m["differences"].values()) for m in moving if "differences" in m}
    print(f"{case_dir}: largest difference by scale {worst}; wall {rec['wall_s']:.0f} s → {out}")


if __name__ == "__main__":
    main(*sys.argv[1:5])
