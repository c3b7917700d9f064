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


IMPULSE = "collide.fin_impulse_ns."


def member_values(path: Path) -> dict[str, dict[str, float]]:
    """member label → quantity → value (the fins' governing stresses [Pa], the headlines and each
    fin's impulse [N s]), read from an ensemble's member table; members with an error left out."""
    from flexnet_fe.ensemble import HEADLINES, fin_names, governing, largest_fin_stress

    rows = [r for r in csv.DictReader(open(path / "ensemble.csv")) if not r.get("error")]
    fins = fin_names(rows)
    out = {}
    for r in rows:
        vals = {k: float(r[k]) for k in HEADLINES if r.get(k) not in (None, "")}
        vals.update({f"{k[len(IMPULSE):]} impulse [N s]": float(r[k]) for k in r
                     if k.startswith(IMPULSE) and r[k] not in (None, "")})
        vals.update({f"{f} [MPa]": float(governing(r, f)) for f in fins if governing(r, f) not in (None, "")})
        if fins:
            vals["largest fin stress [MPa]"] = largest_fin_stress(r, fins)
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


def plot(ens: list, path: Path) -> None:
    """Per fin: each ensemble's members (dots; the same member joined by a grey line across
    ensembles) and its mean ± 2 standard errors (bar)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    quantities = [q for q in ens[0][1] if q.endswith("[MPa]")]
    fig, ax = plt.subplots(figsize=(1.5 * len(quantities) + 2.0, 4.8))
    width = 0.6 / max(len(ens) - 1, 1)
    for i, q in enumerate(quantities):
        xs = [i - 0.3 + j * width for j in range(len(ens))]
        for j in range(len(ens) - 1):  # the same aim point joined between neighbouring ensembles
            for m in ens[j][2]:
                y0, y1 = ens[j][2][m].get(q), ens[j + 1][2].get(m, {}).get(q)
                if y0 is not None and y1 is not None:
                    ax.plot(xs[j:j + 2], [1e-6 * y0, 1e-6 * y1], "-", color="0.75", lw=0.6, zorder=1)
        for j, (label, stats, members) in enumerate(ens):
            ys = [1e-6 * v[q] for v in members.values() if q in v]
            ax.plot([xs[j]] * len(ys), ys, "o", color=f"C{j}", ms=3.5, alpha=0.8, zorder=2,
                    label=f"{label}: members" if i == 0 else None)
            s = stats.get(q)
            if s and s["sem"] is not None:
                ax.errorbar([xs[j] + 0.06], [1e-6 * s["mean"]], yerr=[2e-6 * s["sem"]], fmt="s", color=f"C{j}",
                            capsize=4, ms=6, zorder=3, label=f"{label}: mean ± 2 s.e." if i == 0 else None)
    ax.set_xticks(range(len(quantities)), [q.replace(" [MPa]", "") for q in quantities], rotation=30, ha="right")
    ax.set_ylabel("von Mises held to [MPa]")
    ax.grid(True, axis="y", alpha=0.4)
    ax.legend(fontsize=8, ncol=2)
    ax.set_title(f"radar × traction: ensembles over one net cell at {len(ens)} rope resolutions "
                 "(grey: the same aim point)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(path)


def main(argv: list[str]) -> None:
    from flexnet_fe.ensemble import statistics as ensemble_statistics

    ens = []
    for arg in argv:
        label, path = arg.split(":", 1)
        stats = json.loads((Path(path) / "ensemble.json").read_text())
        safe = label.replace(" ", "_").replace(".", "p")
        shutil.copy(Path(path) / "ensemble.json", DOCS / "data" / f"ensemble_{safe}.json")
        shutil.copy(Path(path) / "ensemble.csv", DOCS / "data" / f"ensemble_{safe}.csv")
        members = member_values(Path(path))
        rows = rows_of(stats)
        for q in next(iter(members.values()), {}):  # each fin's impulse: from the member table
            if q.endswith("impulse [N s]"):
                rows[q] = ensemble_statistics([m[q] for m in members.values() if q in m], stats["tolerance"])
        ens.append((label, rows, members))
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
    plot(ens, DOCS / "img" / "ensemble_pieces.png")


if __name__ == "__main__":
    main(sys.argv[1:])
