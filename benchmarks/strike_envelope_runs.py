"""Collect the strike-envelope runs of the default case (docs/validation.md, "Where the rope
strikes") into docs/data/strike_envelope_runs.json: for each run its rope pieces and aim point,
and per fin the run's own peak, its strike envelope and the moves' peaks; for the rudders also the
height above the root of the first strike's lowest contact point (its first 20 µs of loads).

Usage: python benchmarks/strike_envelope_runs.py LABEL:PIECES_MM:AIM_X,AIM_Y:RUN_DIR ...
(each RUN_DIR a run of cases/radar_traction whose shell stage ran with shell.strike_envelope).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

DOCS = Path(__file__).resolve().parents[1] / "docs"
BODY_RADIUS = 0.1015
"""[m] the radar's body radius (the rudders' root)"""
SPANWISE = {"rudder_1": (0, 1, 0), "rudder_2": (0, 0, 1), "rudder_3": (0, -1, 0), "rudder_4": (0, 0, -1)}
"""the rudders' spanwise unit vectors in the body frame (roll 0, 90, 180, 270°)"""


def strike_heights(run: Path) -> dict[str, float]:
    """[mm] per rudder: the lowest spanwise height above the root of its loads in their first 20 µs."""
    z = np.load(run / "collide" / "fin_contacts.npz")
    t, names = z["t"], list(z["fin_names"])
    k = np.repeat(np.arange(len(t)), np.diff(z["row_start"]))
    out = {}
    for fin, u in SPANWISE.items():
        m = z["fin"] == names.index(fin)
        tt = t[k[m]]
        s = z["point"][m] @ np.array(u, float) - BODY_RADIUS
        out[fin] = round(1e3 * float(s[tt < tt.min() + 20e-6].min()), 2)
    return out


def main(argv: list[str]) -> None:
    runs = []
    for arg in argv:
        label, pieces, aim, path = arg.split(":", 3)
        run = Path(path)
        shell = json.loads((run / "summary.json").read_text())["shell"]
        heights = strike_heights(run)
        fins = {}
        for name, r in shell.items():
            if not isinstance(r, dict) or "strike_envelope" not in r:
                continue
            e = r["strike_envelope"]
            fins[name] = {"peak_mpa": round(r["peak_von_mises_pa"] / 1e6, 1),
                          "envelope_mpa": round(r["strike_envelope_von_mises_pa"] / 1e6, 1),
                          "moves_mm": [round(1e3 * o, 3) for o in e["offsets_m"]],
                          "moves_mpa": [round(p / 1e6, 1) for p in e["peaks_pa"]]}
            if name in heights:
                fins[name]["strike_height_mm"] = heights[name]
        runs.append({"label": label, "pieces_mm": pieces, "aim_point_m": [float(a) for a in aim.split(",")],
                     "run": str(run), "shell_wall_s": round(shell["wall_s"], 1),
                     "finish_wall_s": round(shell["finish_wall_s"], 1), "fins": fins})
    out = DOCS / "data" / "strike_envelope_runs.json"
    out.write_text(json.dumps({"case": "radar_traction", "runs": runs}, indent=1) + "\n")
    print(out)


if __name__ == "__main__":
    main(sys.argv[1:])
