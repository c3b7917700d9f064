"""Observed order of a fin's structural peak event by event (issue 10, "no observed order").

The reported peak is the maximum over the whole run; when two load events give peaks of
similar size, which one is the maximum can change with the mesh, and an observed order
computed on the maximum then means nothing. This runs one fin of a finished run's collision
loads at several local mesh sizes (``shell.local_mesh_size``) with a history row at every
peak evaluation (``history_interval = peak_interval``, so the rows carry the same structural
maxima the running peak is taken from), and reports the largest row value in each given time
window, with its observed order and Richardson limit (three finest sizes, ratio 2).

    PYTHONPATH=$PWD .venv/bin/python benchmarks/shell_event_orders.py /tmp/lead_def rudder_4 \\
        --local 0.0025,0.00125,0.000625 --end-time 10.4e-3 --windows 9.7-9.95,10.0-10.4
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_shell import _run_stage  # noqa: E402

from flexnet_fe.io import read_history_csv  # noqa: E402


def order(f: list[float]) -> tuple[float, float]:
    """(observed order, Richardson limit) from values on meshes h, h/2, h/4 (coarse first);
    NaN when the increments do not shrink monotonically."""
    d1, d2 = f[1] - f[0], f[2] - f[1]
    if d1 == 0 or d2 / d1 <= 0 or abs(d2) >= abs(d1):
        return math.nan, math.nan
    p = math.log2(d1 / d2)
    return p, f[2] + d2 / (2 ** p - 1)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run_dir")
    ap.add_argument("fin")
    ap.add_argument("--local", default="0.0025,0.00125,0.000625")
    ap.add_argument("--end-time", type=float, required=True)
    ap.add_argument("--windows", required=True, help="t0-t1 in ms, comma separated")
    ap.add_argument("--json", default="")
    a = ap.parse_args(argv)
    run_dir = Path(a.run_dir)
    case = json.loads((run_dir / "resolved.json").read_text())["case"]
    wins = [tuple(float(x) * 1e-3 for x in w.split("-")) for w in a.windows.split(",")]
    rows = []
    for hl in (float(x) for x in a.local.split(",")):
        pi = (case.get("shell") or {}).get("peak_interval", 2.5e-7)
        with tempfile.TemporaryDirectory() as td:
            t0 = time.perf_counter()
            s = _run_stage(run_dir, case["missile"]["mesh_size"], [a.fin], Path(td),
                           a.end_time, {"local_mesh_size": hl, "history_interval": pi,
                                        "workers": 1})
            h = read_history_csv(Path(td) / "shell" / a.fin / "history.csv")
        f = s[a.fin]
        row = dict(local=hl, dofs=f["dofs"], steps=f["steps"], wall=time.perf_counter() - t0,
                   peak=f["peak_von_mises_pa"], t_peak=f["peak_time_s"],
                   nodal_peak=f["peak_nodal_von_mises_pa"], windows=[])
        for w0, w1 in wins:
            m = (h["t_s"] >= w0) & (h["t_s"] <= w1)
            i = int(np.argmax(np.where(m, h["max_von_mises_pa"], -1.0)))
            row["windows"].append(dict(value=float(h["max_von_mises_pa"][i]),
                                       t=float(h["t_s"][i]),
                                       loc=[float(h[f"max_von_mises_{c}_m"][i]) for c in "xyz"]))
        rows.append(row)
        print(f"{hl * 1e3:6.3f} mm: {row['dofs']} DOFs, {row['steps']} steps, {row['wall']:.0f} s; "
              f"peak {row['peak'] / 1e6:.1f} MPa at {row['t_peak'] * 1e3:.4f} ms; windows: "
              + "; ".join(f"{w['value'] / 1e6:.1f} MPa at {w['t'] * 1e3:.4f} ms "
                          f"({', '.join(f'{1e3 * c:.1f}' for c in w['loc'])} mm)"
                          for w in row["windows"]), flush=True)
    if len(rows) >= 3:
        for k, (w0, w1) in enumerate(wins):
            vals = [r["windows"][k]["value"] for r in rows[-3:]]
            p, lim = order(vals)
            print(f"window {w0 * 1e3:.3f}-{w1 * 1e3:.3f} ms: "
                  + " / ".join(f"{v / 1e6:.1f}" for v in vals)
                  + f" MPa, order {p:.2f}, Richardson {lim / 1e6:.1f} MPa")
        p, lim = order([r["peak"] for r in rows[-3:]])
        print(f"reported peak: " + " / ".join(f"{r['peak'] / 1e6:.1f}" for r in rows[-3:])
              + f" MPa, order {p:.2f}, Richardson {lim / 1e6:.1f} MPa")
    if a.json:
        Path(a.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
