"""Compare ensembles of one case run at different resolutions (docs/validation.md, "Ensembles"):
per headline and fin, each ensemble's mean ± standard error, and the difference of two means with
its standard error sqrt(se_a² + se_b²) and z = difference / that (|z| < 2: the means agree within
their sampling error). Ensembles with the same members (same aim points: the same --members and
cell) are also compared pairwise: the mean of the members' own differences ± its standard error
(the placement's share of the scatter cancels). Copies each ensemble's statistics and member
table into docs/data/.

Usage: python benchmarks/ensemble_compare.py LABEL:ENSEMBLE_DIR LABEL:ENSEMBLE_DIR [...]
(the first is the reference the others are compared with).
"""

from __future__ import annotations

import csv
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


def member_values(path: Path) -> dict[str, dict[str, float]]:
    """member label → quantity → value (the fins' governing stresses [Pa] and the headlines),
    read from an ensemble's member table; members with an error left out."""
    from flexnet_fe.ensemble import HEADLINES, fin_names, governing

    rows = [r for r in csv.DictReader(open(path / "ensemble.csv")) if not r.get("error")]
    out = {}
    for r in rows:
        vals = {k: float(r[k]) for k in HEADLINES if r.get(k) not in (None, "")}
        vals.update({f"{f} [MPa]": float(governing(r, f)) for f in fin_names(rows)
                     if governing(r, f) not in (None, "")})
        gov = [v for k, v in vals.items() if k.endswith("[MPa]")]
        if gov:
            vals["largest fin stress [MPa]"] = max(gov)
        out[r["label"] + f"@{r['aim_x_m']},{r['aim_y_m']}"] = vals
    return out


def paired(a: dict, b: dict, q: str) -> str:
    """mean ± s.e. of the members' differences b − a in q, relative to a's mean, and the pairs used."""
    common = [m for m in a if m in b and q in a[m] and q in b[m]]
    if len(common) < 2:
        return "n/a"
    d = [b[m][q] - a[m][q] for m in common]
    mean_a = sum(a[m][q] for m in common) / len(common)
    md = sum(d) / len(d)
    se = math.sqrt(sum((x - md) ** 2 for x in d) / (len(d) - 1) / len(d))
    return f"{100 * md / mean_a:+.1f} ± {100 * se / abs(mean_a):.1f} % ({len(common)} pairs)"


def main(argv: list[str]) -> None:
    ens = []
    for arg in argv:
        label, path = arg.split(":", 1)
        stats = json.loads((Path(path) / "ensemble.json").read_text())
        safe = label.replace(" ", "_").replace(".", "p")
        shutil.copy(Path(path) / "ensemble.json", DOCS / "data" / f"ensemble_{safe}.json")
        shutil.copy(Path(path) / "ensemble.csv", DOCS / "data" / f"ensemble_{safe}.csv")
        ens.append((label, rows_of(stats), member_values(Path(path))))
    ref_label, ref, ref_members = ens[0]
    head = "| quantity | " + " | ".join(f"{lab}: mean ± s.e. (s.d.; range)" for lab, _, _ in ens)
    head += "".join(f" | {lab} − {ref_label} (z) | paired" for lab, _, _ in ens[1:]) + " |"
    print(head)
    print("|" + "---|" * (1 + len(ens) + 2 * (len(ens) - 1)))
    for q, r in ref.items():
        scale = 1e-6 if "MPa" in q else 1.0
        cells = []
        for _, e, _ in ens:
            s = e.get(q)
            cells.append("n/a" if s is None or s["std"] is None else
                         f"{s['mean'] * scale:.4g} ± {s['sem'] * scale:.2g} ({s['std'] * scale:.2g}; "
                         f"{s['min'] * scale:.4g}–{s['max'] * scale:.4g})")
        for _, e, members in ens[1:]:
            s = e.get(q)
            if s is None or s["std"] is None or r["std"] is None:
                cells += ["n/a", "n/a"]
                continue
            d = s["mean"] - r["mean"]
            se = math.hypot(s["sem"], r["sem"])
            cells.append(f"{100 * d / r['mean']:+.1f} % ({d / se:+.1f})" if se > 0 else f"{d * scale:+.3g}")
            cells.append(paired(ref_members, members, q))
        print(f"| {q} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main(sys.argv[1:])
