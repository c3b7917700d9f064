"""Shell stage time with per-fin time windows and fins on several threads (issue 10).

Runs the shell stage on a finished run's collision loads (``<run_dir>/collide``) once per
configuration, one after the other in this process (side by side: same machine load
period), and prints per fin the window, steps and peak, and per configuration the stage's wall
and CPU time. The peaks are compared with the run directory's own ``summary.json`` (the
reference run: whatever window/workers it used, normally the full window on one thread).

    PYTHONPATH=$PWD .venv/bin/python benchmarks/bench_shell_schedule.py /tmp/lead_def \\
        --configs fin:1,fin:2 [--fins wing_1,rudder_1] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_shell import _run_stage  # noqa: E402


def _load() -> float:
    return os.getloadavg()[0]


def run_config(run_dir: Path, window: str, workers: int, fins) -> dict:
    resolved = json.loads((run_dir / "resolved.json").read_text())
    case = resolved.get("case", resolved)
    load0, c0, w0 = _load(), time.process_time(), time.perf_counter()
    with tempfile.TemporaryDirectory() as td:
        s = _run_stage(run_dir, case["missile"]["mesh_size"], fins, Path(td),
                       shell_set={"window": window, "workers": workers})
    return dict(window=window, workers=workers, wall_s=time.perf_counter() - w0,
                cpu_s=time.process_time() - c0, stage_wall_s=s["wall_s"],
                setup_wall_s=s["setup_wall_s"], loops_wall_s=s["loops_wall_s"],
                finish_wall_s=s["finish_wall_s"],
                load_before=load0, load_after=_load(),
                fins={k: {q: v[q] for q in ("steps", "start_time_s", "end_time_s",
                                           "peak_von_mises_pa", "peak_time_s", "dofs",
                                           "window_accel_before_mps2",
                                           "window_accel_after_mps2",
                                           "window_force_ratio_before",
                                           "window_force_ratio_after")}
                      for k, v in s.items() if isinstance(v, dict) and "steps" in v})


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run_dir")
    ap.add_argument("--configs", default="fin:1,fin:2", help="window:workers, comma separated")
    ap.add_argument("--fins", default="", help="fin names (default: the loaded fins)")
    ap.add_argument("--json", default="")
    a = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    run_dir = Path(a.run_dir)
    fins = [f for f in a.fins.split(",") if f] or None
    ref = json.loads((run_dir / "summary.json").read_text())["shell"]
    out = {"run_dir": str(run_dir), "cpus": os.cpu_count(), "reference": {
        k: {q: v[q] for q in ("steps", "peak_von_mises_pa", "peak_time_s")}
        for k, v in ref.items() if isinstance(v, dict) and "steps" in v},
        "reference_wall_s": ref.get("wall_s"), "runs": []}
    for c in a.configs.split(","):
        window, workers = c.split(":")
        r = run_config(run_dir, window, int(workers), fins)
        out["runs"].append(r)
        print(f"\n== window {window}, {workers} worker(s): wall {r['wall_s']:.1f} s, "
              f"CPU {r['cpu_s']:.1f} s (set-up {r['setup_wall_s']:.1f} s, time loops "
              f"{r['loops_wall_s']:.1f} s, finishing {r['finish_wall_s']:.1f} s), load avg "
              f"{r['load_before']:.2f} -> {r['load_after']:.2f}")
        print(f"{'fin':10s} {'steps':>8s} {'ref steps':>9s} {'window [ms]':>15s} "
              f"{'peak [MPa]':>11s} {'ref [MPa]':>10s} {'rel diff':>9s} {'t_pk [ms]':>9s} "
              f"{'ref t_pk':>9s} {'a_bef':>6s} {'r_bef':>8s} {'a_aft':>6s} {'r_aft':>8s}")
        for name, f in r["fins"].items():
            g = out["reference"].get(name, {})
            pk, rp = f["peak_von_mises_pa"], g.get("peak_von_mises_pa", float("nan"))
            print(f"{name:10s} {f['steps']:8d} {g.get('steps', 0):9d} "
                  f"{1e3 * f['start_time_s']:7.3f}-{1e3 * f['end_time_s']:7.3f} "
                  f"{pk / 1e6:11.5g} {rp / 1e6:10.5g} {(pk - rp) / rp:9.2e} "
                  f"{1e3 * f['peak_time_s']:9.4f} {1e3 * g.get('peak_time_s', 0):9.4f} "
                  f"{f['window_accel_before_mps2']:6.1f} {f['window_force_ratio_before']:8.2e} "
                  f"{f['window_accel_after_mps2']:6.1f} {f['window_force_ratio_after']:8.2e}")
        sys.stdout.flush()
    if a.json:
        Path(a.json).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
