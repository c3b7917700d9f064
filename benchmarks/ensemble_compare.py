"""Compare ensembles of one case run at different resolutions (docs/validation.md, "Ensembles"):
per headline and fin, each ensemble's mean ± standard error, and the difference of two means with
its standard error sqrt(se_a² + se_b²) and z = difference / that (|z| < 2: the means agree within
their sampling error). Copies each ensemble's statistics and member table into docs/data/.

Usage: python benchmarks/ensemble_compare.py LABEL:ENSEMBLE_DIR LABEL:ENSEMBLE_DIR [...]
(the first is the reference the others are compared with).
"""

from __future__ import annotations

import json
import math
import shutil
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1] / "docs"


def rows_of(stats: dict) -> dict[str, dict]:
    """quantity → its statistics (headlines, each fin's governing stress, the largest)."""
    out = dict(stats["headlines"])
    out.update({f"{fin} [MPa]": s["governing"] for fin, s in stats["fins"].items()})
    if "largest" in stats:
        out["largest fin stress [MPa]"] = stats["largest"]
    return out


def main(argv: list[str]) -> None:
    ens = []
    for arg in argv:
        label, path = arg.split(":", 1)
        stats = json.loads((Path(path) / "ensemble.json").read_text())
        safe = label.replace(" ", "_").replace(".", "p")
        shutil.copy(Path(path) / "ensemble.json", DOCS / "data" / f"ensemble_{safe}.json")
        shutil.copy(Path(path) / "ensemble.csv", DOCS / "data" / f"ensemble_{safe}.csv")
        ens.append((label, rows_of(stats)))
    ref_label, ref = ens[0]
    head = "| quantity | " + " | ".join(f"{lab}: mean ± s.e. (s.d.; range)" for lab, _ in ens)
    head += "".join(f" | {lab} − {ref_label} (z)" for lab, _ in ens[1:]) + " |"
    print(head)
    print("|" + "---|" * (1 + len(ens) + len(ens) - 1))
    for q, r in ref.items():
        scale = 1e-6 if "MPa" in q else 1.0
        cells = []
        for _, e in ens:
            s = e.get(q)
            cells.append("n/a" if s is None or s["std"] is None else
                         f"{s['mean'] * scale:.4g} ± {s['sem'] * scale:.2g} ({s['std'] * scale:.2g}; "
                         f"{s['min'] * scale:.4g}–{s['max'] * scale:.4g})")
        for _, e in ens[1:]:
            s = e.get(q)
            if s is None or s["std"] is None or r["std"] is None:
                cells.append("n/a")
                continue
            d = s["mean"] - r["mean"]
            se = math.hypot(s["sem"], r["sem"])
            cells.append(f"{100 * d / r['mean']:+.1f} % ({d / se:+.1f})" if se > 0 else f"{d * scale:+.3g}")
        print(f"| {q} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main(sys.argv[1:])
