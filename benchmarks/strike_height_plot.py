"""Chart: a rudder's peak stress against the height above the root at which the rope strikes it
(docs/data/strike_height.jsonl, benchmarks/strike_height.py), with the heights and peaks the
default case's runs realised (docs/data/strike_envelope_runs.json). Writes docs/img/strike_height.png.

Usage: python benchmarks/strike_height_plot.py
"""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

DOCS = Path(__file__).resolve().parents[1] / "docs"


def main() -> None:
    rows = [json.loads(line) for line in (DOCS / "data" / "strike_height.jsonl").read_text().splitlines() if line]
    runs = json.loads((DOCS / "data" / "strike_envelope_runs.json").read_text())
    fins = sorted({r["fin"] for r in rows})
    fig, axes = plt.subplots(1, len(fins), figsize=(5.2 * len(fins), 4.0), sharey=True)
    marks = {"1.4": "o", "0.7": "s", "2.8": "^", "0.35": "D"}
    colours = {"1.4": "C0", "0.7": "C1", "2.8": "C2", "0.35": "C3"}
    for ax, fin in zip(axes, fins):
        mine = sorted((r for r in rows if r["fin"] == fin), key=lambda r: r["offset_m"])
        ax.plot([1e3 * r["lowest_point_height_m"] for r in mine], [r["peak_von_mises_pa"] / 1e6 for r in mine],
                "-", color="0.3", label="run of 1.4 mm pieces, its loads moved in span")
        for run in runs["runs"]:
            f = run["fins"].get(fin)
            if not f:
                continue
            ax.plot(f["strike_height_mm"], f["peak_mpa"], marks[run["pieces_mm"]], ms=7, mfc="none",
                    color=colours[run["pieces_mm"]],
                    label=f"a run's own strike, pieces {run['pieces_mm']} mm")
            if f.get("envelope_mpa"):
                ax.axhline(f["envelope_mpa"], color=colours[run["pieces_mm"]], lw=0.6, ls=":")
        ax.set_title(f"radar × traction, {fin}")
        ax.set_xlabel("height of the strike's lowest contact point above the root [mm]")
        ax.grid(alpha=0.3)
        h, lab = ax.get_legend_handles_labels()
        seen = {}
        for hh, ll in zip(h, lab):
            seen.setdefault(ll, hh)
        ax.legend(seen.values(), seen.keys(), fontsize=7, loc="lower center")
    axes[0].set_ylabel("peak von Mises, structural [MPa]")
    fig.suptitle("Where the rope strikes sets the rudder peaks (dotted: each run's strike envelope)", fontsize=10)
    fig.tight_layout()
    out = DOCS / "img" / "strike_height.png"
    fig.savefig(out, dpi=110)
    print(out)


if __name__ == "__main__":
    main()
