"""The engagement map: where must the net meet the missile to defeat it?

A driver in the run layer, over the sweep's run-or-reuse of one variant
(``flexnet_fe.sweep.run_or_reuse``): for every point of a grid over the aim point on the net
(world x, y [m]), the impact incidence [rad] and the base case (one per net type), it runs
deploy → collide → shell → flight into ``<out>/<label>/`` and gathers the outcome
(``flexnet_fe.flight.outcome``: miss distance, hit, the fins' margins allowable / peak von Mises
− 1 from the shell summary, the damage the flight flew with) into ``<out>/map.csv`` and
``<out>/map.png``. Points run in parallel processes (``-j``); a point whose run directory says
every stage is done with the same inputs is not run again (resumable).

Run (quick resolution, see docs/validation.md "engagement map"):

    python -m flexnet_fe.engagement_map cases/engagement_map \\
        --aim-x=-0.3,0,0.3 --aim-y=0,0.3 --incidence-deg 0,10 -j 2 --out runs/engagement_map
"""

from __future__ import annotations

import argparse
import csv
import itertools
import json
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from flexnet_fe.errors import FlexnetError
from flexnet_fe.flight.outcome import outcome
from flexnet_fe.runs import MAP_TABLE

STAGES = ("deploy", "collide", "shell", "flight")
COLUMNS = ("label", "case", "aim_x_m", "aim_y_m", "incidence_deg", "miss_distance_m", "hit",
           "min_fin_margin", "critical_fin", "wing_damage", "rudder_effectiveness", "error")


@dataclass(frozen=True)
class MapPoint:
    case: str
    """base case directory (one per net type)"""
    aim_x_m: float
    aim_y_m: float
    incidence_deg: float

    @property
    def label(self) -> str:
        return (f"{Path(self.case).name}_x{self.aim_x_m:+.3f}_y{self.aim_y_m:+.3f}_i{self.incidence_deg:05.1f}"
                .replace("+", "p").replace("-", "m"))

    def overrides(self) -> list[str]:
        return [f"collide.aim_point=[{self.aim_x_m!r}, {self.aim_y_m!r}]",
                f"collide.incidence_angle={math.radians(self.incidence_deg)!r}",
                f"case.stages={json.dumps(list(STAGES))}"]


def grid(cases: list[str], aim_x: list[float], aim_y: list[float], incidence_deg: list[float]) -> list[MapPoint]:
    """Cartesian product of the axes."""
    return [MapPoint(c, x, y, i) for c, x, y, i in itertools.product(cases, aim_x, aim_y, incidence_deg)]


def run_point(point: MapPoint, out: str) -> dict:
    """Run one point (or reuse its run directory when every stage is done with the same inputs,
    as a sweep does) and return its map row. Top-level so process pools can pickle it."""
    from flexnet_fe.sweep import Variant, run_or_reuse

    row = {"label": point.label, "case": Path(point.case).name, "aim_x_m": point.aim_x_m,
           "aim_y_m": point.aim_y_m, "incidence_deg": point.incidence_deg, "error": ""}
    try:
        row.update(outcome(run_or_reuse(Variant(point.label, Path(point.case), tuple(point.overrides())), out)))
    except (FlexnetError, ArithmeticError, ValueError, RuntimeError, KeyError) as err:
        row["error"] = str(err).replace("\n", " ")
    return row


def write_csv(rows: list[dict], path: Path) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)


def plot_map(rows: list[dict], path: Path, lethal_radius: float = 5.0) -> Path:
    """One panel per (case, incidence) — rows = cases (net types), columns = incidences: aim
    points coloured by miss distance (log), o = hit, X = miss, grey square = failed run; labels =
    the smallest fin margin σ_allow/σ_peak − 1 and the damage flown (wing damage, rudder share)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    cases = sorted({r["case"] for r in rows})
    incs = sorted({r["incidence_deg"] for r in rows})
    fig, axs = plt.subplots(len(cases), len(incs), figsize=(4.6 * len(incs), 3.9 * len(cases)), squeeze=False)
    fig.subplots_adjust(wspace=0.35, hspace=0.45)
    norm = LogNorm(1e-2, 1e3)
    sc = None
    xs, ys = [r["aim_x_m"] for r in rows], [r["aim_y_m"] for r in rows]
    pad = max(0.1, 0.15 * max(max(xs) - min(xs), max(ys) - min(ys)))
    for i, case in enumerate(cases):
        for j, inc in enumerate(incs):
            ax = axs[i][j]
            for r in (r for r in rows if (r["case"], r["incidence_deg"]) == (case, inc)):
                miss = r.get("miss_distance_m")
                if r["error"] or miss is None:
                    ax.plot(r["aim_x_m"], r["aim_y_m"], "s", color="0.6", ms=12)
                    continue
                sc = ax.scatter([r["aim_x_m"]], [r["aim_y_m"]], c=[max(miss, 1e-2)], norm=norm, cmap="viridis_r",
                                marker="o" if miss <= lethal_radius else "X", s=160, edgecolors="k")
                label = f"m {r['min_fin_margin']:+.2f}" if r.get("min_fin_margin") is not None else ""
                label += f"\nw {r.get('wing_damage') or 0:.2f} r {r.get('rudder_effectiveness') or 1:.2f}"
                ax.annotate(label, (r["aim_x_m"], r["aim_y_m"]), textcoords="offset points", xytext=(0, 11),
                            ha="center", fontsize=7)
            ax.set_xlim(min(xs) - pad, max(xs) + pad)
            ax.set_ylim(min(ys) - pad, max(ys) + 2 * pad)
            ax.set_title(f"{case}, incidence {inc:g}°", fontsize=9)
            ax.set_xlabel("aim x [m] (world frame W)")
            ax.set_ylabel("aim y [m]")
            ax.grid(True)
    if sc is not None:
        fig.colorbar(sc, ax=[a for row in axs for a in row], label="miss distance [m]")
    fig.suptitle("Engagement map: o hit / X miss / grey failed; m = min fin margin σ_allow/σ_peak − 1, "
                 "w = wing damage, r = rudder share kept", fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def run_map(points: list[MapPoint], out: Path, jobs: int = 1) -> list[dict]:
    """Run every point (``jobs`` processes), write map.csv and map.png into ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if jobs > 1:
        with ProcessPoolExecutor(max_workers=jobs) as pool:
            rows = list(pool.map(run_point, points, [str(out)] * len(points)))
    else:
        rows = [run_point(p, str(out)) for p in points]
    write_csv(rows, out / MAP_TABLE)
    plot_map(rows, (out / MAP_TABLE).with_suffix(".png"))
    return rows


def _floats(text: str) -> list[float]:
    try:
        return [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m flexnet_fe.engagement_map", description=__doc__.split("\n\n")[0])
    ap.add_argument("cases", nargs="+", help="base case directories (one per net type), each with a [flight] table")
    ap.add_argument("--aim-x", type=_floats, default=[0.0], help="aim points x [m], comma-separated")
    ap.add_argument("--aim-y", type=_floats, default=[0.0], help="aim points y [m], comma-separated")
    ap.add_argument("--incidence-deg", type=_floats, default=[0.0], help="impact incidences [deg], comma-separated")
    ap.add_argument("-j", "--jobs", type=int, default=1, help="parallel processes")
    ap.add_argument("--out", type=Path, default=Path("runs/engagement_map"))
    a = ap.parse_args(argv)
    rows = run_map(grid(a.cases, a.aim_x, a.aim_y, a.incidence_deg), a.out, a.jobs)
    bad = [r for r in rows if r["error"]]
    table = a.out / MAP_TABLE
    print(f"{len(rows)} points, {len(bad)} failed; {table}, {table.with_suffix('.png')}")
    return 0 if not bad else 1


if __name__ == "__main__":
    sys.exit(main())
