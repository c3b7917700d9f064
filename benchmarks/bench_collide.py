"""Collision benchmark and convergence study (not a test): for each paper case, the headline numbers
under dt → 0 at fixed stiffness, under rope subdivision near the contact, under a decade of contact
modulus, and the kernel cost per spring-step.

    .venv/bin/python benchmarks/bench_collide.py [--out DIR] [--deploy-root DIR] [--cases ...]
                                                 [--dt-scales 1,0.5,0.25] [--subdivide 1,2,4] [--sub-margin 0.2]
                                                 [--moduli 3.16e10,1e11,3.16e11] [--doc FILE]

Each case is deployed once (its [deploy] table) into DIR/<case>/deploy — or the deploy stage of an
existing run directory DEPLOY_ROOT/<case>/deploy is used — then collided with the case's tables:
the case's dt × each scale (at the case's rope_split); each rope subdivision k near the flight path
at the case's dt rule; each transverse modulus at the case's dt rule. Every run's headline numbers
(CFC-filtered peak |a|, Δv/v, impulse per fin, contact duration, outcome, energy error) are printed
as they arrive and written as a markdown table to --doc (rewritten after each group), with the
change relative to the finest dt / the finest k / the case's modulus. docs/collide_convergence.md
is assembled from these tables.
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import tempfile
import time
from pathlib import Path


from flexnet_fe.atmosphere import isa
from flexnet_fe.collide.scene import held_net
from flexnet_fe.collide.simulate import simulate
from flexnet_fe.config import load_case
from flexnet_fe.errors import NumericalError
from flexnet_fe.missile.build import build_missile
from flexnet_fe.net.deploy import run_deploy

ROOT = Path(__file__).resolve().parents[1]
CASES = ("radar_traction", "radar_rotary", "infrared_traction")
HEAD = ("peak_accel_mps2", "dv_over_v", "impulse_ns", "duration_s")


def _row(label, s, ref=None) -> str:
    if s is None:
        return f"| {label} | tunnelling (run stopped) | | | | | | | |"
    fins = {k: v for k, v in s["fin_impulse_ns"].items() if v > 0}
    fin_txt = ", ".join(f"{k} {v:.3g}" for k, v in fins.items())
    rel = ""
    if ref is not None:
        rel = ", ".join(f"{(s[k] - ref[k]) / ref[k]:+.2%}" for k in HEAD if ref[k])
    return (f"| {label} | {s['peak_accel_mps2']:.4g} | {s['peak_accel_raw_mps2']:.4g} | {s['dv_over_v']:.4g} | "
            f"{s['impulse_ns']:.4g} | {fin_txt} | {s['duration_s'] * 1e3:.3g} | "
            f"{'passed' if s['passed_through'] else 'carried/contact'} | {s['energy_error_rel']:.2%} | "
            f"{s['max_penetration_ratio']:.2f} | {s['steps']} | {s['wall_s']:.1f} | {rel} |")


def _run(net, missile, cfg, air, log, **kw):
    try:
        return simulate(net, missile, cfg, air.gravity, log, air_density=air.density, **kw).summary
    except NumericalError as err:
        log.warning("%s", err)
        return None


def _write(doc: Path | None, lines: list[str]) -> None:
    if doc:
        doc.write_text(f"<!-- written by benchmarks/bench_collide.py on {time.strftime('%Y-%m-%d %H:%M')} -->\n"
                       + "\n".join(lines) + "\n")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--deploy-root", type=Path, default=None)
    ap.add_argument("--cases", nargs="*", default=list(CASES))
    ap.add_argument("--dt-scales", default="1,0.5,0.25", help="case dt × each (fixed stiffness)")
    ap.add_argument("--moduli", default="3.16e10,1e11,3.16e11", help="rope transverse moduli [Pa]; '' for none")
    ap.add_argument("--subdivide", default="1,2,4", help="rope subdivision k near the path (at the case dt)")
    ap.add_argument("--sub-margin", type=float, default=0.2,
                    help="segments within the missile's bounding radius + this [m] of the path are split")
    ap.add_argument("--doc", type=Path, default=None)
    args = ap.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="bench_collide_"))
    log = logging.getLogger("bench_collide")
    logging.basicConfig(level=logging.WARNING)
    lines = ["| run | peak \\|a\\| CFC [m/s²] | raw peak [m/s²] | Δv/v | impulse [N s] | fin impulses [N s] | "
             "contact [ms] | outcome | energy error | max δ/(r+h/2) | steps | wall [s] | vs reference "
             "(peak, Δv/v, impulse, duration) |", "|" + "---|" * 13]
    for name in args.cases:
        case, _ = load_case(ROOT / "cases" / name)
        air = isa(case.atmosphere.altitude)
        dep = (args.deploy_root / name / "deploy") if args.deploy_root else out / name / "deploy"
        if not (dep / "net_state.npz").is_file():
            run_deploy(case.net, case.deploy, air, dep, log)
        net = held_net(case.net, case.collide.net_source, dep)
        missile = build_missile(case.missile)
        scales = sorted((float(x) for x in args.dt_scales.split(",") if x), reverse=True)
        runs = {}
        for sc in scales:
            runs[sc] = _run(net, missile, case.collide, air, log, dt_scale=sc, n_snapshots=2)
            print(_row(f"{name}, dt × {sc:g}", runs[sc]), flush=True)
        ref = runs[min(scales)] if scales else None
        lines += [_row(f"{name}, dt × {sc:g} (vs dt × {min(scales):g})", runs[sc], ref) for sc in scales]
        _write(args.doc, lines)
        subs = [int(x) for x in args.subdivide.split(",") if x]
        sub_runs = {}
        for k in subs:
            cfg_k = case.collide.model_copy(update={"rope_split": k, "rope_split_margin": args.sub_margin})
            reuse = k == case.collide.rope_split and args.sub_margin == case.collide.rope_split_margin and 1.0 in runs
            sub_runs[k] = runs[1.0] if reuse else _run(net, missile, cfg_k, air, log, n_snapshots=2)
            print(_row(f"{name}, rope split k = {k}", sub_runs[k]), flush=True)
        if subs:
            lines += [_row(f"{name}, rope split k = {k} near the path, case dt (vs k = {max(subs)})", sub_runs[k],
                           sub_runs[max(subs)]) for k in subs]
            _write(args.doc, lines)
        for e_t in (float(x) for x in args.moduli.split(",") if x):
            if e_t == net.rope.transverse_modulus:
                continue
            soft = dataclasses.replace(net, rope=net.rope._replace(transverse_modulus=e_t))
            lines.append(_row(f"{name}, E_t = {e_t:.3g} Pa (vs case)", _run(soft, missile, case.collide, air, log,
                                                                             n_snapshots=2), runs.get(1.0)))
            _write(args.doc, lines)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
