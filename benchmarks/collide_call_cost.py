"""What a collide kernel call costs besides its steps, and the collide stage's wall time: two source
trees (e.g. a git worktree of the code before a change, and the change) alternated in one run.

    PYTHONPATH=. .venv/bin/python benchmarks/collide_call_cost.py OUT.jsonl CASE_DIR DEPLOY_DIR \\
        --trees OLD_TREE NEW_TREE [--repeat 2] [--load-intervals 3.125e-7 1e-5] [--stage]

Each measurement runs in its own process with the tree first on PYTHONPATH (so each tree's own
numba cache is used; one untimed warm-up per tree compiles it):
* impact: ``simulate`` of the case's collision without its resolution check, at each
  ``collide.load_interval``; CPU [s] of the process's simulate call, steps, Δv/v, CFC peak;
* ``--stage``: ``flexnet run CASE --stages deploy,collide`` into a scratch folder, wall [s] (the
  resolution check included: it may run in a second process, so CPU time is not the figure).

Rows are appended to OUT.jsonl with the tree, the load average and the machine
(docs/performance.md, "Collide: a kernel call costs its steps")."""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

INNER = r"""
import json, sys, time
from pathlib import Path
from flexnet_fe.study.collide import simulate_case
from flexnet_fe.study.scenes import case_with
case = case_with(Path(sys.argv[1]), ("collide.snapshots=2", "collide.resolution_check=false",
                                     f"collide.load_interval={sys.argv[3]}"))
c0 = time.process_time()
_, _, res = simulate_case(case, Path(sys.argv[2]))
s = res.summary
print(json.dumps({"cpu_s": time.process_time() - c0, "steps": s["steps"], "dv_over_v": s["dv_over_v"],
                  "peak_accel_mps2": s["peak_accel_mps2"], "far_net_ratio": s["far_net_ratio"],
                  "energy_error_rel": s["energy_error_rel"], "fin_impulse_ns": s["fin_impulse_ns"]}))
"""


def _env(tree: Path) -> dict:
    return {**os.environ, "PYTHONPATH": str(tree), "FLEXNET_NO_PROGRESS": "1"}


def impact(tree: Path, case: str, deploy: str, load_interval: float) -> dict:
    # run in the tree: ``python -c`` and ``-m`` put the working directory before PYTHONPATH
    out = subprocess.run([sys.executable, "-c", INNER, case, deploy, repr(load_interval)], env=_env(tree),
                         capture_output=True, text=True, check=True, cwd=tree)
    return json.loads(out.stdout.strip().splitlines()[-1])


def stage(tree: Path, case: str) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "flexnet_fe.cli", "run", case, "--stages", "deploy,collide", "--out",
                        str(Path(tmp) / "run")], env=_env(tree), capture_output=True, text=True, check=True,
                       cwd=tree)
        wall = time.perf_counter() - t0
        s = json.loads((Path(tmp) / "run" / "summary.json").read_text())["collide"]
    return {"wall_s": wall, "impact_wall_s": s["wall_s"],
            "check_wall_s": (s.get("resolution_check") or {}).get("wall_s"), "dv_over_v": s["dv_over_v"]}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("case")
    ap.add_argument("deploy")
    ap.add_argument("--trees", nargs=2, required=True, type=Path)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--load-intervals", nargs="+", type=float, default=[3.125e-7, 1e-5])
    ap.add_argument("--stage", action="store_true")
    args = ap.parse_args()
    args.case, args.deploy = str(Path(args.case).resolve()), str(Path(args.deploy).resolve())
    for tree in args.trees:  # warm-up: compile each tree's kernels into its own cache
        impact(tree, args.case, args.deploy, args.load_intervals[0])
    for rep in range(args.repeat):
        jobs = [("impact", li) for li in args.load_intervals] + ([("stage", None)] if args.stage else [])
        for kind, li in jobs:
            for tree in args.trees:
                load = os.getloadavg()[0]
                res = impact(tree, args.case, args.deploy, li) if kind == "impact" else stage(tree, args.case)
                row = {"what": kind, "tree": str(tree), "load_interval_s": li, "repeat": rep, **res,
                       "load_1min": load, "machine": f"{platform.node()} {os.cpu_count()} cores",
                       "date": time.strftime("%Y-%m-%d %H:%M")}
                with open(args.out, "a") as fh:
                    fh.write(json.dumps(row) + "\n")
                print(json.dumps({k: v for k, v in row.items() if k != "fin_impulse_ns"}), flush=True)


if __name__ == "__main__":
    main()
