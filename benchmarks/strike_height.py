"""How a rudder's peak stress depends on where the rope strikes it (issue 10; the rope's pieces).

The default case's rudder peaks move -35..+64 % between rope pieces of 0.7 / 1.4 / 2.8 mm while
the fin impulses agree within 2 % (docs/validation.md, "The rope's pieces move the fin peaks").
Each rudder peak follows one strike of the rope, riding on the body, on the fin's leading edge
2-12 mm above the root. This script takes a finished run's fin loads, moves the contact points of
one fin that lie within ``--band`` of the root along the leading edge by a spanwise offset (the
same forces, the same instants), and reruns that fin's shell stage for each offset, so the peak's
dependence on the strike height is measured with everything else fixed.

Usage: python benchmarks/strike_height.py RUN_DIR FIN OUT_DIR --offsets -1e-3 0 1e-3 2e-3 ...
Writes OUT_DIR/strike_height.jsonl (one line per offset: offset [m], the strike's spanwise
height before/after [m], peak von Mises [Pa], its time and location).
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def fin_frame(case, name: str):
    """(the fin's planform, its spanwise unit vector (3,)) in the body frame of fin_contacts.npz
    (x from the nose, negative aft; roll angle from +y towards +z)."""
    m = case.missile
    kind, k = name.rsplit("_", 1)
    fin = m.wings if kind == "wing" else m.rudders
    phi = math.radians(fin.roll_angles_deg[int(k) - 1])
    radial = np.array([0.0, math.cos(phi), math.sin(phi)])
    return fin, radial


def shift_points(points: np.ndarray, fin, radial: np.ndarray, body_radius: float, band: float,
                 offset: float) -> tuple[np.ndarray, np.ndarray]:
    """Move the points whose spanwise height s = r·radial − R is below ``band`` by ``offset``
    spanwise along the swept leading edge (x by −offset·tan Λ). Returns (new points, mask)."""
    s = points @ radial - body_radius
    mask = s < band
    out = points.copy()
    tan = math.tan(math.radians(fin.leading_edge_sweep_deg))
    out[mask] += offset * radial
    out[mask, 0] -= offset * tan
    return out, mask


def main(argv=None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("run", type=Path)
    ap.add_argument("fin")
    ap.add_argument("out", type=Path)
    ap.add_argument("--offsets", type=float, nargs="+", required=True)
    ap.add_argument("--band", type=float, default=0.02)
    a = ap.parse_args(argv)
    from flexnet_fe.config import load_case
    case, _ = load_case(ROOT / "cases" / "radar_traction")
    fin, radial = fin_frame(case, a.fin)
    R = case.missile.body_diameter / 2
    z = dict(np.load(a.run / "collide" / "fin_contacts.npz"))
    fi = list(z["fin_names"]).index(a.fin)
    sel = z["fin"] == fi
    a.out.mkdir(parents=True, exist_ok=True)
    log = (a.out / "strike_height.jsonl").open("a")
    for off in a.offsets:
        d = a.out / f"off_{off * 1e3:+.2f}mm"
        if d.exists():
            shutil.rmtree(d)
        d.mkdir()
        for p in ("deploy", "collide"):
            shutil.copytree(a.run / p, d / p, ignore=shutil.ignore_patterns("snapshots"))
        for f in ("resolved.json", "status.json", "summary.json"):
            shutil.copy(a.run / f, d / f)
        zz = dict(z)
        pts, mask = shift_points(z["point"][sel], fin, radial, R, a.band, off)
        zz["point"] = z["point"].copy()
        zz["point"][sel] = pts
        np.savez(d / "collide" / "fin_contacts.npz", **zz)
        cmd = [sys.executable, "-m", "flexnet_fe.cli", "run", str(ROOT / "cases" / "radar_traction"),
               "--out", str(d), "--stages", "shell", "--force",
               "--set", "shell.peak_check=false", "--set", 'shell.fins="named"',
               "--set", f'shell.fin_names=["{a.fin}"]']
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode:
            print(r.stderr[-2000:])
            raise SystemExit(f"offset {off}: shell failed")
        res = json.loads((d / "summary.json").read_text())["shell"][a.fin]
        s0 = z["point"][sel][mask] @ radial - R
        row = {"fin": a.fin, "offset_m": off, "band_m": a.band, "points_moved": int(mask.sum()),
               "lowest_point_height_m": float(s0.min() + off) if len(s0) else None,
               "peak_von_mises_pa": res["peak_von_mises_pa"], "peak_time_s": res["peak_time_s"],
               "peak_location_m": res["peak_location_m"], "run": str(a.run)}
        print(json.dumps(row), flush=True)
        log.write(json.dumps(row) + "\n")
        log.flush()
        shutil.rmtree(d / "deploy")


if __name__ == "__main__":
    main()
