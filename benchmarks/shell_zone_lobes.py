"""Largest structural stress on a load's zone circle, sector by sector, per mesh (issue 10).

The reported peak is the largest recovered nodal von Mises outside the active St-Venant zones;
when the zone circle of one load carries two local maxima of similar size (lobes), which of them
is the maximum can change with the mesh. This runs one fin of a finished run's loads at several
``shell.local_mesh_size`` values and, at every peak evaluation in [t0, t1], reads the recovered
nodal von Mises (top/bottom) of the nodes in the band r_ex ≤ r ≤ r_ex + h_local around the
load's contact point, split into sectors (unit direction in the body frame ± 45°), and prints the
largest value per sector with its instant, and the observed order per sector.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/shell_zone_lobes.py /tmp/lead_def rudder_4 \\
        --event-ms 10.165 --t0-ms 10.155 --t1-ms 10.19 --end-time 10.4e-3 \\
        --sectors "aft:-1,0,0;inboard:0,0,1" --local 0.00125,0.000625,0.0003125
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import sys
import tempfile
from pathlib import Path

import numpy as np
from mpi4py import MPI

sys.path.insert(0, str(Path(__file__).resolve().parent))
from shell_event_orders import order  # noqa: E402

from flexnet_fe.shell import stage as S  # noqa: E402
from flexnet_fe.shell.recovery import sample_nodes  # noqa: E402
from flexnet_fe.shell.solve import run  # noqa: E402


def _specs(run_dir: Path, case: dict, out: Path):
    from flexnet_fe.missile.build import build_missile
    from flexnet_fe.missile.config import MissileConfig
    from flexnet_fe.missile.mesh import write_meshes
    mcfg = MissileConfig.model_validate(case["missile"])
    return S.fin_specs(build_missile(mcfg).fins, write_meshes(mcfg, out / "meshes"))


def lobes(run_dir: Path, fin: str, hl: float, a) -> dict:
    case = json.loads((run_dir / "resolved.json").read_text())["case"]
    base = case.get("shell") or {}
    shell = S.ShellConfig.model_validate({**base, "fins": "named", "fin_names": [fin],
                                          "end_time": a.end_time, "local_mesh_size": hl,
                                          "history_interval": base.get("peak_interval", 2.5e-7),
                                          "workers": 1})
    contacts = S.read_fin_contacts(run_dir / "collide" / "fin_contacts.npz")
    acc_t, acc = S.read_body_acceleration(run_dir / "collide" / "history.csv")
    idx = contacts.fin_names.index(fin)
    k = int(np.argmin(np.abs(contacts.t - a.event_ms * 1e-3)))
    ev = np.flatnonzero((contacts.fin == idx) & (contacts.sample == k))
    e = ev[np.argmax(np.linalg.norm(contacts.force[ev], axis=1))]
    p = contacts.point[e]
    sectors = {name: np.array([float(v) for v in d.split(",")]) for name, d in
               (s.split(":") for s in a.sectors.split(";"))}
    with tempfile.TemporaryDirectory() as td:
        spec = next(s for s in _specs(run_dir, case, Path(td)) if s.name == fin)
        job = S.setup_fin(shell, spec, contacts, acc_t, acc, Path(td), a.end_time,
                           logging.getLogger("lobes"), MPI.COMM_WORLD)
        x = job.model.op.x_nodes
        r_ex = float(job.zones.radius.max())
        d = x - p
        r = np.linalg.norm(d, axis=1)
        band = (r >= r_ex) & (r <= r_ex + hl)
        sel = {n: np.flatnonzero(band & (d @ u > math.cos(math.pi / 4) * r))
               for n, u in sectors.items()}
        best = {n: (0.0, 0.0, -1) for n in sectors}
        nodal = np.zeros((len(x), 4))

        def frame(t, u):
            if not (a.t0_ms * 1e-3 <= t <= a.t1_ms * 1e-3):
                return
            sample_nodes(job.R, u, nodal)
            vm = nodal[:, :2].max(axis=1)
            for n, ids in sel.items():
                if len(ids):
                    i = ids[int(np.argmax(vm[ids]))]
                    if vm[i] > best[n][0]:
                        best[n] = (float(vm[i]), t, int(i))

        ts = job.steps
        run(job.model, job.loads, job.R, dt=ts.dt, n_steps=ts.n_steps, sample_every=ts.every,
            frame_every=ts.every, frame=frame,
            exclusion=job.zones.exclusion, peak_every=ts.peak_every, start_step=ts.start_step)
    return {n: dict(value=v, t=t, r=float(r[i]) if i >= 0 else math.nan, nodes=len(sel[n]))
            for n, (v, t, i) in best.items()}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run_dir")
    ap.add_argument("fin")
    ap.add_argument("--event-ms", type=float, required=True)
    ap.add_argument("--t0-ms", type=float, required=True)
    ap.add_argument("--t1-ms", type=float, required=True)
    ap.add_argument("--end-time", type=float, required=True)
    ap.add_argument("--sectors", required=True)
    ap.add_argument("--local", default="0.00125,0.000625,0.0003125")
    a = ap.parse_args(argv)
    rows = []
    for hl in (float(v) for v in a.local.split(",")):
        res = lobes(Path(a.run_dir), a.fin, hl, a)
        rows.append(res)
        print(f"{1e3 * hl:6.3f} mm: " + "; ".join(
            f"{n} {v['value'] / 1e6:.1f} MPa at {1e3 * v['t']:.4f} ms, r = {1e3 * v['r']:.2f} mm "
            f"({v['nodes']} band nodes)" for n, v in res.items()), flush=True)
    if len(rows) >= 3:
        for n in rows[0]:
            vals = [rw[n]["value"] for rw in rows[-3:]]
            p, lim = order(vals)
            print(f"{n}: " + " / ".join(f"{v / 1e6:.1f}" for v in vals)
                  + f" MPa, order {p:.2f}, Richardson {lim / 1e6:.1f} MPa")


if __name__ == "__main__":
    main()
