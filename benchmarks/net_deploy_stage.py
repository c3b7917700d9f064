"""Where the deploy stage's time goes, and two source trees side by side (issue 15: the kernel's
share of the stage).

    PYTHONPATH=. .venv/bin/python benchmarks/net_deploy_stage.py --trees OLD_TREE NEW_TREE [--repeats 7]
    PYTHONPATH=. .venv/bin/python benchmarks/net_deploy_stage.py --trees .          # one tree: the breakdown

Each measurement is a fresh process (``--child``) with the tree first on ``sys.path``: it imports
numba and the stage module, loads ``cases/radar_traction`` and calls ``net.deploy.run_deploy`` (the
stage function, figure included) into a scratch folder, with the functions the stage calls
wrapped to add up their thread CPU time: the kernel (``step_many``, its first call loading the
numba cache of ``advance``), the first numba dispatch of the process (``evaluate_tensions`` at
t = 0: numba's run-time initialisation and the cache of ``net_forces``), the area, the other
record work (tensions, energies, loop area), the snapshots, the other files, the figure (importing
matplotlib, drawing, writing the PNG). The trees alternate (ABAB…), so both see the same machine
load; reported per tree: the median [min, max] of each part [s] and the kernel's share of the
stage (run_deploy) and of the stage plus its imports; for two trees the paired ratios (new / old) of
the stage, of the stage without its figure (matplotlib's time varies most) and of the area. Thread CPU time, except ``wall``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

PARTS = {"step_many": "kernel", "evaluate_tensions": "tensions", "net_area": "area", "loop_area": "record_other",
         "energies": "record_other", "drag_limit": "record_other", "write_vtu": "snapshots",
         "write_pvd": "snapshots", "write_history_csv": "files", "write_net_state": "files",
         "plot_deployment": "plot"}


def child(out: str) -> None:
    """One measurement in this process; prints a JSON row."""
    clock = time.thread_time
    row: dict[str, float] = {}
    c = clock()
    import numba  # noqa: F401
    row["import_numba"] = clock() - c
    c = clock()
    import flexnet_fe.net.deploy as deploy
    row["import_stage"] = clock() - c
    from pathlib import Path

    from flexnet_fe.atmosphere import isa
    from flexnet_fe.config import load_case
    case, _ = load_case(Path("cases/radar_traction"))
    first: set[str] = set()

    def wrap(name: str, part: str):
        f = getattr(deploy, name)

        def timed(*a, **k):
            t0 = clock()
            r = f(*a, **k)
            key = "numba_first_dispatch" if name == "evaluate_tensions" and name not in first else part
            if name == "step_many" and name not in first:
                row["kernel_first_call"] = clock() - t0  # also in kernel
            first.add(name)
            row[key] = row.get(key, 0.0) + clock() - t0
            return r
        setattr(deploy, name, timed)

    for name, part in PARTS.items():
        wrap(name, part)
    c, w = clock(), time.perf_counter()
    s = deploy.run_deploy(case.net, case.deploy, isa(case.atmosphere.altitude), Path(out), deploy.logging.getLogger("x"))
    row["run_deploy"] = clock() - c
    row["wall"] = time.perf_counter() - w
    row["rest"] = row["run_deploy"] - sum(row.get(p, 0.0) for p in set(PARTS.values()) | {"numba_first_dispatch"})
    row["max_area_m2"] = s["max_area_m2"]
    print(json.dumps(row))


def measure(tree: str) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        env = {**os.environ, "PYTHONPATH": os.path.abspath(tree), "FLEXNET_NO_PROGRESS": "1"}
        p = subprocess.run([sys.executable, os.path.abspath(__file__), "--child", tmp], env=env, cwd=tree,
                           capture_output=True, text=True, check=True)
        return json.loads(p.stdout.strip().splitlines()[-1])


def report(tree: str, rows: list[dict]) -> None:
    keys = ["import_numba", "import_stage", "numba_first_dispatch", "kernel", "kernel_first_call", "tensions", "area", "record_other",
            "snapshots", "files", "plot", "rest", "run_deploy", "wall"]
    print(f"\n{tree}: {len(rows)} runs, median [min, max] s (thread CPU; wall: run_deploy's wall)")
    for k in keys:
        v = [r.get(k, 0.0) for r in rows]
        print(f"  {k:22s} {statistics.median(v):7.3f}  [{min(v):.3f}, {max(v):.3f}]")
    share = [r["kernel"] / r["run_deploy"] for r in rows]
    share_all = [r["kernel"] / (r["run_deploy"] + r["import_numba"] + r["import_stage"]) for r in rows]
    print(f"  kernel / run_deploy               {statistics.median(share):.3f}  [{min(share):.3f}, {max(share):.3f}]")
    print(f"  kernel / (run_deploy + imports)   {statistics.median(share_all):.3f}  "
          f"[{min(share_all):.3f}, {max(share_all):.3f}]")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--child", help=argparse.SUPPRESS)
    p.add_argument("--trees", nargs="+", default=["."])
    p.add_argument("--repeats", type=int, default=7)
    p.add_argument("--rows", help="also write every measurement to this JSON-lines file")
    a = p.parse_args()
    if a.child:
        return child(a.child)
    print(f"deploy stage (cases/radar_traction), trees {a.trees}, {a.repeats} alternated repeats, "
          f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, load average {os.getloadavg()[0]:.2f}")
    for tree in a.trees:  # compile / load the numba caches once, unmeasured
        measure(tree)
    rows: dict[str, list[dict]] = {t: [] for t in a.trees}
    for rep in range(a.repeats):
        for tree in (a.trees if rep % 2 == 0 else a.trees[::-1]):
            rows[tree].append(measure(tree))
    for tree in a.trees:
        report(tree, rows[tree])
    if len(a.trees) == 2:
        for label, f in (("run_deploy", lambda r: r["run_deploy"]),
                         ("run_deploy without the figure", lambda r: r["run_deploy"] - r["plot"]),
                         ("area", lambda r: r["area"])):
            ratio = [f(n) / f(o) for o, n in zip(*rows.values())]
            print(f"{label} CPU, {a.trees[1]} / {a.trees[0]}, paired: {statistics.median(ratio):.3f} "
                  f"[{min(ratio):.3f}, {max(ratio):.3f}]")
        print(f"load average now {os.getloadavg()[0]:.2f}")
    if a.rows:
        with open(a.rows, "w") as fh:
            for tree, rs in rows.items():
                fh.writelines(json.dumps({"tree": tree, **r}) + "\n" for r in rs)


if __name__ == "__main__":
    main()
