"""How long each fin's contact hangs on its leading-edge/tip corner, from a collide stage's files
(docs/collide_convergence.md, twelfth pass: the rudder-tip friction lock).

    PYTHONPATH=. .venv/bin/python benchmarks/collide_corner_hang.py RUN_DIR [RUN_DIR ...] [--radius 3e-3]

For every fin of the run's missile (the case's ``[missile]``, rebuilt from RUN_DIR/resolved.json):
the output intervals in which ``collide/fin_contacts.npz`` holds a contact point within ``--radius``
[m] of the planform's leading-edge/tip corner (planform corner 2: ``missile.planform.TIP_CORNERS``)
whose force on the fin points mostly aft (F_x < −|F|/2: the strand is dragged, not merely
touching); prints the first and last such time, their count × the interval (the hang's length)
and the aft impulse −Σ F_x dt [N s] they carry.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from flexnet_fe.missile.build import build_missile
from flexnet_fe.missile.config import MissileConfig


def corner_hang(run: Path, radius: float) -> list[tuple[str, float, float, float, float]]:
    """[(fin name, first [s], last [s], hang [s], aft impulse [N s])] of one run directory."""
    resolved = json.loads((run / "resolved.json").read_text())
    missile = build_missile(MissileConfig(**resolved["case"]["missile"]))
    with np.load(run / "collide" / "fin_contacts.npz", allow_pickle=False) as z:
        t, row_start, fin, point, force = z["t"], z["row_start"], z["fin"], z["point"], z["force"]
    dt = t[1] - t[0]
    k = np.repeat(np.arange(t.size), np.diff(row_start))
    out = []
    for f in missile.fins:
        corner = np.asarray(f.corners)[2]  # leading edge meets the tip (planform order: root TE, root LE, tip LE, tip TE)
        near = ((fin == f.index) & (np.linalg.norm(point - corner, axis=1) < radius)
                & (force[:, 0] < -0.5 * np.linalg.norm(force, axis=1)))
        times = np.unique(t[k[near]])
        if times.size:
            out.append((f.name, times[0], times[-1], times.size * dt, float(-force[near, 0].sum() * dt)))
        else:
            out.append((f.name, np.nan, np.nan, 0.0, 0.0))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path)
    ap.add_argument("--radius", type=float, default=3e-3)
    args = ap.parse_args()
    for run in args.runs:
        print(f"{run}:")
        for name, first, last, hang, imp in corner_hang(run, args.radius):
            if hang > 0.0:
                print(f"  {name:9s} {1e3 * first:6.2f}–{1e3 * last:6.2f} ms  hang {1e3 * hang:5.2f} ms  aft impulse {imp:.3f} N s")


if __name__ == "__main__":
    main()
