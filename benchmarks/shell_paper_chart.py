"""Paper-fin convergence chart (issue 10): the structural peak (outside the St-Venant zones) and
the peak with the zones included, against the element size at the loads, from the rows that
``bench_shell.py paper`` prints (collected in docs/data/shell_paper_convergence.json).

    .venv/bin/python benchmarks/shell_paper_chart.py docs/data/shell_paper_convergence.json \
        docs/img/shell_paper_convergence.png
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(src: Path, png: Path) -> None:
    data = json.loads(Path(src).read_text())
    rows = data["rows"]
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(13, 4.8))
    styles = {1.0: ("tab:orange", "s"), 2.0: ("tab:blue", "o"), 3.0: ("tab:green", "^")}
    for f, (col, mk) in styles.items():
        loc = sorted((r for r in rows if r["factor"] == f and r["local"]), key=lambda r: -r["h"])
        if loc:
            ax.plot([1e3 * r["h"] for r in loc], [r["peak"] / 1e6 for r in loc], mk + "-",
                    color=col, label=f"structural peak, r_ex = {f:g}·max(t, d) "
                                    f"= {1e3 * loc[0]['radius']:.0f} mm (local refinement)")
    f2 = sorted((r for r in rows if r["factor"] == 2.0 and r["local"]), key=lambda r: -r["h"])
    ax.plot([1e3 * r["h"] for r in f2], [r["raw"] / 1e6 for r in f2], "x--", color="tab:red",
            label="peak with the load zones included (singular)")
    uni = sorted((r for r in rows if r["factor"] == 2.0 and not r["local"]), key=lambda r: -r["h"])
    ax.plot([1e3 * r["h"] for r in uni], [r["peak"] / 1e6 for r in uni], "o:", color="tab:gray",
            label="structural peak, r_ex = 12 mm, uniform mesh")
    rich = json.loads(Path(src).read_text()).get("richardson_factor2_pa")
    if rich:
        ax.axhline(rich / 1e6, color="tab:blue", lw=0.8, ls="--",
                   label=f"Richardson limit (r_ex = 12 mm): {rich / 1e6:.0f} MPa")
    ax.set_xscale("log")
    ax.invert_xaxis()
    ax.set_xlabel("element size at the contact loads h [mm] (20 mm elsewhere)")
    ax.set_ylabel("peak von Mises, radar × traction wing_1 [MPa]")
    ax.set_title("wing_1 to 3.45 ms: structural peak vs peak at the loads")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7.5, loc="upper left")
    wings = data.get("rows_all_wings_14ms", [])
    for k, name in enumerate(sorted({r["fin"] for r in wings})):
        rr = sorted((r for r in wings if r["fin"] == name), key=lambda r: -r["h"])
        col = f"C{k}"
        ax2.plot([1e3 * r["h"] for r in rr], [r["peak"] / 1e6 for r in rr], "o-", color=col,
                 label=f"{name} structural peak")
        ax2.plot([1e3 * r["h"] for r in rr], [r["raw"] / 1e6 for r in rr], "x:", color=col,
                 label=f"{name} with load zones")
    ax2.set_xscale("log")
    ax2.invert_xaxis()
    ax2.set_xlabel("element size at the contact loads h [mm] (first point: 20 mm uniform)")
    ax2.set_ylabel("peak von Mises over 14 ms [MPa]")
    ax2.set_title("All loaded wings, r_ex = 12 mm, local refinement")
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=7, ncol=2, loc="upper left")
    fig.tight_layout()
    fig.savefig(png, dpi=120)


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]))
