"""One stage's wall time under two source trees (e.g. a git worktree of the code before a change, and
the change), alternated in one run, on copies of one finished run directory.

    PYTHONPATH=. .venv/bin/python benchmarks/stage_wall.py OUT.jsonl CASE_DIR RUN_DIR --stage shell \\
        --trees OLD_TREE NEW_TREE [--repeat 1]
    PYTHONPATH=. .venv/bin/python benchmarks/stage_wall.py OUT.jsonl CASE_DIR RUN_DIR --stage shell \\
        --sets KEY=A KEY=B [--repeat 1]

``--sets``: one tree (this one), two values of a case field (``flexnet run --set``) instead.

Each measurement copies RUN_DIR (without the stage's own folder) to a scratch folder and runs
``flexnet run CASE_DIR --stages STAGE`` there in its own process with the tree first on PYTHONPATH.
Row: tree, wall [s] (``process_wall_s``) and peak resident memory [GiB] of the process (GNU time: /usr/bin/time, Debian
package ``time``), the stage summary's ``*wall_s`` keys, and per fin (shell) the
peak von Mises [Pa] — which must not depend on the tree when the change is one of scheduling —
with the load average and the machine (docs/performance.md)."""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def measure(tree: Path, case: str, run_dir: Path, stage: str, setting: str | None = None) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        copy = Path(tmp) / "run"
        shutil.copytree(run_dir, copy, ignore=shutil.ignore_patterns(stage, "report*", "run.lock"))
        env = {**os.environ, "PYTHONPATH": str(tree), "FLEXNET_NO_PROGRESS": "1"}
        t0 = time.perf_counter()
        # (in the tree: ``python -m`` puts the working directory before PYTHONPATH)
        rss = Path(tmp) / "max_rss_kb"  # the process's peak resident memory (GNU time, its threads included)
        subprocess.run(["/usr/bin/time", "-f", "%M", "-o", str(rss), sys.executable, "-m", "flexnet_fe.cli", "run",
                        str(Path(case).resolve()), "--stages", stage, "--out", str(copy),
                        *(["--set", setting] if setting else [])],
                       env=env, capture_output=True, text=True, check=True, cwd=tree)
        wall = time.perf_counter() - t0
        s = json.loads((copy / "summary.json").read_text())[stage]
        max_rss_gb = int(rss.read_text().split()[-1]) / 1024 ** 2
    row = {"process_wall_s": wall, "max_rss_gb": max_rss_gb, **{k: v for k, v in s.items() if k.endswith("wall_s")}}
    if stage == "collide":  # the check's own wall, and the headlines (which a speed change must not move)
        row["check_wall_s"] = (s.get("resolution_check") or {}).get("wall_s")
        row.update({k: s[k] for k in ("dv_over_v", "peak_accel_mps2", "fin_impulse_ns") if k in s})
    if stage == "shell":
        fins = {k: v for k, v in s.items() if isinstance(v, dict) and "peak_von_mises_pa" in v}
        row["peaks_pa"] = {k: v["peak_von_mises_pa"] for k, v in fins.items()}
        row["nodal_peaks_pa"] = {k: v["peak_nodal_von_mises_pa"] for k, v in fins.items()}
    return row


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("case")
    ap.add_argument("run_dir", type=Path)
    ap.add_argument("--stage", required=True)
    side = ap.add_mutually_exclusive_group(required=True)
    side.add_argument("--trees", nargs=2, type=Path)
    side.add_argument("--sets", nargs=2, metavar="KEY=VALUE")
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args()
    args.run_dir = args.run_dir.resolve()
    here = Path(__file__).resolve().parents[1]
    sides = [(t, None) for t in args.trees] if args.trees else [(here, s) for s in args.sets]
    for rep in range(args.repeat):
        for tree, setting in sides:
            load = os.getloadavg()[0]
            row = {"stage": args.stage, "tree": str(tree), "set": setting, "repeat": rep,
                   **measure(tree, args.case, args.run_dir, args.stage, setting), "load_1min": load,
                   "machine": f"{platform.node()} {os.cpu_count()} cores", "date": time.strftime("%Y-%m-%d %H:%M")}
            with open(args.out, "a") as fh:
                fh.write(json.dumps(row) + "\n")
            print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
