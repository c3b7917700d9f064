"""Merging the rope's cut pieces back once they leave the fins (``collide.simulate._merge_idle``): the
paper cases' impacts with the merge off (``MERGE_REACH`` = inf, the thirteenth session's code) and on,
one after the other in one process, CPU time and headlines side by side.

    PYTHONPATH=. .venv/bin/python benchmarks/collide_merge.py OUT.jsonl CASE:DEPLOY_DIR [...] [--reach R ...]

--reach: the MERGE_REACH values to run [output intervals' travel], inf = merge off (default: inf and
the shipped value). Each row: case, merge (bool), merge_reach, the headlines (Δv/v, CFC peak, per-fin impulse), energy and momentum
errors, steps, cut and merged counts, CPU [s] of the impact, load, machine, date
(docs/performance.md, "Collide: merging the cut pieces back")."""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
from pathlib import Path


def main() -> None:
    from flexnet_fe.collide import simulate as S
    from flexnet_fe.study.collide import simulate_case
    from flexnet_fe.study.scenes import case_with

    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("cases", nargs="+", help="CASE_DIR:DEPLOY_DIR")
    ap.add_argument("--reach", nargs="+", type=float, default=None)
    args = ap.parse_args()
    shipped = S.MERGE_REACH
    for arg in args.cases:
        case_dir, deploy = arg.split(":")
        case = case_with(Path(case_dir), ("collide.snapshots=2", "collide.resolution_check=false"))
        for reach in args.reach or (math.inf, shipped):
            merge = math.isfinite(reach)
            S.MERGE_REACH = reach
            c0, load = time.process_time(), os.getloadavg()[0]
            _, _, res = simulate_case(case, Path(deploy))
            s = res.summary
            row = {"case": Path(case_dir).name, "merge": merge, "merge_reach": reach if merge else None,
                   "dv_over_v": s["dv_over_v"],
                   "peak_accel_mps2": s["peak_accel_mps2"], "fin_impulse_ns": dict(s["fin_impulse_ns"]),
                   "energy_error_rel": s["energy_error_rel"], "momentum_error_rel": s["momentum_error_rel"],
                   "rope_refinement_j": s["rope_refinement_j"], "energy_exchanged_j": s["energy_exchanged_j"],
                   "steps": s["steps"], "dt_s": s["dt_s"], "near_net_segment_share": s["near_net_segment_share"],
                   "cut_nodes": s["cut_nodes"], "merged_nodes": s["merged_nodes"],
                   "cpu_s": time.process_time() - c0, "load_1min": load,
                   "machine": f"{platform.node()} {os.cpu_count()} cores", "date": time.strftime("%Y-%m-%d %H:%M")}
            with open(args.out, "a") as fh:
                fh.write(json.dumps(row) + "\n")
            print(json.dumps(row), flush=True)
    S.MERGE_REACH = shipped


if __name__ == "__main__":
    main()
