"""Rope resolution at the fins (issue 9 §6): one paper case's impact at several
``collide.fin_piece_length`` and both readings of Eq. (4) (``net.damping_law``), headlines and
cost side by side; and the chart of docs/img/collide_rope_resolution.png.

    PYTHONPATH=. .venv/bin/python benchmarks/collide_rope_resolution.py run CASE DEPLOY_DIR OUT.jsonl \
        [--pieces 1.4e-3 0.7e-3 0.35e-3] [--law segment] [--set KEY=VALUE ...]
    PYTHONPATH=. .venv/bin/python benchmarks/collide_rope_resolution.py plot OUT.jsonl PNG
    PYTHONPATH=. .venv/bin/python benchmarks/collide_rope_resolution.py table OUT.jsonl
    PYTHONPATH=. .venv/bin/python benchmarks/collide_rope_resolution.py friction OUT.jsonl PNG

``run`` appends one JSON row per point to OUT.jsonl (case, law, piece [m], Δv/v, CFC peak [m/s²],
per-fin impulse [N s], contact duration [s], energy error, steps, dt [s], wall and CPU [s], the
machine's load); DEPLOY_DIR is the ``deploy/`` folder of a run of CASE (the held net). ``plot``
draws each headline's deviation from the finest segment-law point of its case against the piece
length (log axis); fins that take less than 2 % of their case's total fin impulse are skipped
(their relative scatter says nothing about the headlines). ``table`` prints the rows as the Markdown
table of docs/collide_convergence.md. ``friction`` draws Δv/v and the rudders' impulses against the
piece length, one line per friction coefficient (the rows' ``collide.friction_coefficient=`` override,
0.2 where none): the rudder-tip friction lock of docs/collide_convergence.md, twelfth pass.
Results: docs/collide_convergence.md.
"""
from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import time
from pathlib import Path

logging.basicConfig(level=logging.WARNING)


def run(args) -> None:
    from flexnet_fe.study.collide import simulate_case
    from flexnet_fe.study.scenes import FULL_COLLIDE, case_with

    for piece in args.pieces:
        ov = FULL_COLLIDE + (f"collide.fin_piece_length={piece}", f"net.damping_law={args.law}") + tuple(args.set)
        case = case_with(Path(args.case), ov)
        c0, w0, load = time.process_time(), time.perf_counter(), os.getloadavg()[0]
        _, _, res = simulate_case(case, Path(args.deploy))
        s = res.summary
        row = {"case": Path(args.case).name, "law": args.law, "piece_m": piece, "overrides": list(args.set),
               "dv_over_v": s["dv_over_v"], "peak_accel_mps2": s["peak_accel_mps2"],
               "fin_impulse_ns": dict(s["fin_impulse_ns"]), "duration_s": s["duration_s"],
               "passed_through": s.get("passed_through"), "energy_error_rel": s["energy_error_rel"],
               "steps": s["steps"], "dt_s": s["dt_s"], "warnings": len(s["warnings"]),
               "active_segments": s["active_segments"], "crop_boundary_motion_m": s["crop_boundary_motion_m"],
               "momentum_error_rel": s["momentum_error_rel"],
               "wall_s": time.perf_counter() - w0, "cpu_s": time.process_time() - c0, "load_1min": load,
               "machine": f"{platform.node()} {os.cpu_count()} cores", "date": time.strftime("%Y-%m-%d")}
        with open(args.out, "a") as fh:
            fh.write(json.dumps(row) + "\n")
        print(json.dumps(row), flush=True)


def _series(rows: list[dict]) -> dict[str, list[tuple[float, float]]]:
    """Headline name -> [(piece [mm], value)] of one case and law, sorted by piece."""
    out: dict[str, list[tuple[float, float]]] = {}
    total = sum(rows[0]["fin_impulse_ns"].values())
    for r in sorted(rows, key=lambda r: r["piece_m"]):
        mm = 1e3 * r["piece_m"]
        out.setdefault("Δv", []).append((mm, r["dv_over_v"]))
        out.setdefault("CFC peak", []).append((mm, r["peak_accel_mps2"]))
        for fin, imp in r["fin_impulse_ns"].items():
            if rows[0]["fin_impulse_ns"][fin] >= 0.02 * total:
                out.setdefault(fin, []).append((mm, imp))
    return out


_COLOURS = {"Δv": "black", "CFC peak": "tab:red", "wing_1": "tab:blue", "wing_2": "tab:cyan",
            "wing_3": "tab:green", "wing_4": "tab:olive", "rudder_1": "tab:purple", "rudder_2": "tab:pink",
            "rudder_3": "tab:orange", "rudder_4": "tab:brown"}


def plot(args) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    rows = [json.loads(line) for line in open(args.jsonl) if line.strip()]
    cases = sorted({r["case"] for r in rows})
    fig, axes = plt.subplots(1, len(cases), figsize=(5.0 * len(cases), 5.0), squeeze=False, sharey=True)
    for ax, case in zip(axes[0], cases):
        seg = [r for r in rows if r["case"] == case and r["law"] == "segment"]
        ref = min(seg, key=lambda r: r["piece_m"])
        ref_series = _series([ref] + [r for r in seg if r is not ref])
        for law, style in (("segment", "-o"), ("material", "s")):
            mine = [r for r in rows if r["case"] == case and r["law"] == law]
            if not mine:
                continue
            for name, pts in _series(mine).items():
                if name not in ref_series:
                    continue
                ref_v = dict(ref_series[name])[1e3 * ref["piece_m"]]
                ax.semilogx([p for p, _ in pts], [100 * (v / ref_v - 1) for _, v in pts], style,
                            color=_COLOURS.get(name, "0.5"), ms=5 if law == "segment" else 6, lw=1.2,
                            mfc="none" if law == "material" else None,
                            label=name if law == "segment" else None)
        ax.axhspan(-2, 2, color="0.88", zorder=0)
        ax.set_xlim(0.25, 2.0)
        ax.set_xticks([0.35, 0.7, 1.4])
        ax.set_xticklabels(["0.35", "0.7", "1.4"])
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_title(f"{case}", fontsize=10)
        ax.set_xlabel("rope piece length at the fins, fin_piece_length [mm]")
        ax.grid(True, which="major", lw=0.3)
        ax.legend(fontsize=7, ncol=2, loc="upper left")
    axes[0][0].set_ylabel("deviation from the finest segment-law run [%]")
    fig.suptitle("Rope resolution at the fins: lines and dots, Eq. (4) per piece (segment law); open squares, "
                 "the dashpot as a material (sixth pass); grey, ±2 %", fontsize=10)
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)


def _mu(row: dict) -> float:
    """The row's friction coefficient: its ``collide.friction_coefficient=`` override, else the case's 0.2."""
    for o in row["overrides"]:
        if o.startswith("collide.friction_coefficient="):
            return float(o.split("=", 1)[1])
    return 0.2


def friction(args) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    rows = [json.loads(line) for line in open(args.jsonl) if line.strip()]
    ticks = sorted({1e3 * r["piece_m"] for r in rows})
    fig, axes = plt.subplots(1, 3, figsize=(14.0, 4.6))
    for mu, colour in zip(sorted({_mu(r) for r in rows}), ("tab:blue", "black", "tab:red", "tab:green")):
        mine = sorted((r for r in rows if _mu(r) == mu), key=lambda r: r["piece_m"])
        mm = [1e3 * r["piece_m"] for r in mine]
        axes[0].semilogx(mm, [1e4 * r["dv_over_v"] for r in mine], "-o", color=colour, label=f"μ = {mu:g}")
        for ax, fin in ((axes[1], "rudder_2"), (axes[2], "rudder_3")):
            ax.semilogx(mm, [r["fin_impulse_ns"][fin] for r in mine], "-o", color=colour, label=f"μ = {mu:g}")
    for ax, what in zip(axes, ("Δv/v [1e-4]", "rudder_2 impulse [N s]", "rudder_3 impulse [N s]")):
        ax.set_xlabel("rope piece length at the fins, fin_piece_length [mm]")
        ax.set_ylabel(what)
        ax.set_xticks(ticks)
        ax.set_xticklabels([f"{p:g}" for p in ticks])
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.axvline(0.7, color="0.6", lw=0.8, ls="--")
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("radar × traction: the rudder-tip friction lock. From μ = 0.2 the strands on rudders 2 and 3 "
                 "hang on the leading-edge/tip corner;\nhow long is resolved only by rope pieces ≤ 0.1 mm "
                 "(dashed: the case's 0.7 mm)", fontsize=10)
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)


def _fins(impulse: dict[str, float], kind: str) -> str:
    """The impulses [N s] of fins ``kind``_1..4, 0 where a fin took none."""
    return " ".join(f"{impulse.get(f'{kind}_{i}', 0.0):.3f}" for i in range(1, 5))


def table(args) -> None:
    """Print OUT.jsonl as a Markdown table, one row per run in file order."""
    print("| case, law, fin pieces | Δv/v | CFC peak [m/s²] | wings 1–4 [N s] | rudders 1–4 [N s] "
          "| contact over | energy error | steps (dt) | CPU (wall, load) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for line in open(args.jsonl):
        if not line.strip():
            continue
        r = json.loads(line)
        imp = r["fin_impulse_ns"]
        steps = f"{r['steps']:_}".replace("_", " ")
        print(f"| {r['case']}, {r['law']}, {1e3 * r['piece_m']:g} mm | {r['dv_over_v']:.4e} "
              f"| {r['peak_accel_mps2']:.2f} | {_fins(imp, 'wing')} | {_fins(imp, 'rudder')} | {1e3 * r['duration_s']:.1f} ms "
              f"| {100 * r['energy_error_rel']:.3f} % | {steps} ({r['dt_s']:.2e} s) "
              f"| {r['cpu_s']:.0f} s ({r['wall_s']:.0f} s, {r['load_1min']:.1f}) |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("case")
    r.add_argument("deploy")
    r.add_argument("out")
    r.add_argument("--pieces", type=float, nargs="+", default=[1.4e-3, 0.7e-3, 0.35e-3])
    r.add_argument("--law", choices=("segment", "material"), default="segment")
    r.add_argument("--set", action="append", default=[])
    p = sub.add_parser("plot")
    p.add_argument("jsonl")
    p.add_argument("png")
    t = sub.add_parser("table")
    t.add_argument("jsonl")
    f = sub.add_parser("friction")
    f.add_argument("jsonl")
    f.add_argument("png")
    args = ap.parse_args()
    {"run": run, "plot": plot, "table": table, "friction": friction}[args.cmd](args)


if __name__ == "__main__":
    main()
