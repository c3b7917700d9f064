"""Collision benchmark and convergence study (not a test): for each paper case, the headline numbers
under dt → 0 at fixed stiffness, under a decade of contact modulus, and the kernel cost per
spring-step.

    .venv/bin/python benchmarks/bench_collide.py [--out DIR] [--deploy-root DIR] [--cases ...]
                                                 [--dt-scales 1,0.5,0.25] [--moduli 3.16e10,1e11,3.16e11]
                                                 [--doc docs/collide_convergence.md]

Each case is deployed once (its [deploy] table) into DIR/<case>/deploy — or the deploy stage of an
existing run directory DEPLOY_ROOT/<case>/deploy is used — then collided with the case's tables
(the case's dt × each scale; each transverse modulus at the case's dt rule). Every run's headline
numbers (CFC-filtered peak |a|, Δv/v, impulse per fin, contact duration, outcome, energy error)
are written as markdown tables to --doc, with the change relative to the finest dt.
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
        return simulate(net, missile, cfg, air.gravity, log, **kw).summary
    except NumericalError as err:
        log.warning("%s", err)
        return None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--deploy-root", type=Path, default=None)
    ap.add_argument("--cases", nargs="*", default=list(CASES))
    ap.add_argument("--dt-scales", default="1,0.5,0.25")
    ap.add_argument("--moduli", default="3.16e10,1e11,3.16e11")
    ap.add_argument("--doc", type=Path, default=None)
    args = ap.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="bench_collide_"))
    log = logging.getLogger("bench_collide")
    logging.basicConfig(level=logging.WARNING)
    lines = ["| run | peak \\|a\\| CFC [m/s²] | raw peak [m/s²] | Δv/v | impulse [N s] | fin impulses [N s] | "
             "contact [ms] | outcome | energy error | max δ/(r+h/2) | steps | wall [s] | vs finest dt "
             "(peak, Δv/v, impulse, duration) |", "|" + "---|" * 13]
    for name in args.cases:
        case, _ = load_case(ROOT / "cases" / name)
        air = isa(case.atmosphere.altitude)
        dep = (args.deploy_root / name / "deploy") if args.deploy_root else out / name / "deploy"
        if not (dep / "net_state.npz").is_file():
            run_deploy(case.net, case.deploy, air, dep, log)
        net = held_net(case.net, case.collide.net_source, dep)
        missile = build_missile(case.missile)
        scales = [float(x) for x in args.dt_scales.split(",")]
        runs = {sc: _run(net, missile, case.collide, air, log, dt_scale=sc, n_snapshots=2) for sc in scales}
        ref = runs[min(scales)]
        for sc in scales:
            lines.append(_row(f"{name}, dt × {sc:g}", runs[sc], ref))
        for e_t in (float(x) for x in args.moduli.split(",")):
            if e_t == net.rope.transverse_modulus:
                continue
            soft = dataclasses.replace(net, rope=net.rope._replace(transverse_modulus=e_t))
            lines.append(_row(f"{name}, E_t = {e_t:.3g} Pa", _run(soft, missile, case.collide, air, log,
                                                                   n_snapshots=2), runs[1.0]))
        print("\n".join(lines[-len(scales) - 2:]), flush=True)
    text = "\n".join(lines) + "\n"
    print(text)
    if args.doc:
        args.doc.write_text(f"<!-- written by benchmarks/bench_collide.py on {time.strftime('%Y-%m-%d %H:%M')} -->\n"
                            + text)


if __name__ == "__main__":
    main()
