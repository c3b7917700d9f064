"""Collision benchmark and paper-case study (not a test): wall time per paper case, ns per
spring-step with contact on, crop vs full net, segment test on vs off, Eq. (31) vs penalty.

    .venv/bin/python benchmarks/bench_collide.py [--out DIR] [--cases radar_traction ...] [--no-variants]

Each case is deployed once (its [deploy] table) into DIR/<case>/deploy, then collided with the
case's [collide] table (cropped), with the full net, and with the variants. Everything measured
here is printed side by side as a markdown table; the plots of the case runs are copied to
docs/img/collide_<case>_*.png.
"""

from __future__ import annotations

import argparse
import logging
import shutil
import tempfile
import time
from pathlib import Path


from flexnet_fe.atmosphere import isa
from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.collide.scene import held_net
from flexnet_fe.collide.simulate import simulate
from flexnet_fe.collide.stage import run_collide
from flexnet_fe.config import load_case
from flexnet_fe.errors import NumericalError
from flexnet_fe.missile.geometry import build_missile
from flexnet_fe.net.deploy import run_deploy

ROOT = Path(__file__).resolve().parents[1]
CASES = ("radar_traction", "radar_rotary", "infrared_traction")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--cases", nargs="*", default=list(CASES))
    ap.add_argument("--no-variants", action="store_true")
    args = ap.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="bench_collide_"))
    log = logging.getLogger("bench_collide")
    logging.basicConfig(level=logging.WARNING)
    rows, var_rows = [], []
    for name in args.cases:
        case, _ = load_case(ROOT / "cases" / name)
        air = isa(case.atmosphere.altitude)
        dep = out / name / "deploy"
        t0 = time.perf_counter()
        run_deploy(case.net, case.deploy, air, dep, log)
        t_dep = time.perf_counter() - t0
        stage = out / name / "collide"
        t0 = time.perf_counter()
        s = run_collide(case.net, case.deploy, case.missile, case.collide, air, dep, stage, log)
        t_stage = time.perf_counter() - t0
        for png in stage.glob("collide_*.png"):
            shutil.copy(png, ROOT / "docs" / "img" / png.name.replace("collide_", f"collide_{name}_"))
        net = held_net(case.net, case.collide.net_source, dep)
        missile = build_missile(case.missile)
        full = simulate(net, missile, case.collide, air.gravity, log, crop=False, n_snapshots=2).summary
        ns_crop = s["wall_s"] / (s["steps"] * s["active_segments"]) * 1e9
        ns_full = full["wall_s"] / (full["steps"] * full["active_segments"]) * 1e9
        rows.append((name, s, full, t_dep, t_stage, ns_crop, ns_full))
        if args.no_variants:
            continue
        for label, upd in (("segment test on", {"fin_segment_test": True}),
                           ("Eq. (31) stiffness", {"stiffness_rule": "hertz_eq31", "fin_segment_test": True})):
            cfg = CollideConfig.model_validate({**case.collide.model_dump(), **upd, "allow_tunnelling": True})
            try:
                v = simulate(net, missile, cfg, air.gravity, log, n_snapshots=2).summary
                var_rows.append((name, label, v, ""))
            except NumericalError as e:
                var_rows.append((name, label, None, str(e)[:120]))
    print(f"\nruns in {out}\n")
    print("| case | free nodes / all | active segments | steps | dt [s] | collide wall [s] | stage wall (with files) [s] "
          "| ns per spring-step (crop) | full-net wall [s] | ns per spring-step (full) | peak |a| crop / full |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name, s, full, t_dep, t_stage, ns_c, ns_f in rows:
        print(f"| {name} | {s['free_nodes']} / {full['free_nodes']} | {s['active_segments']} | {s['steps']} | "
              f"{s['dt_s']:.3g} | {s['wall_s']:.1f} | {t_stage:.1f} | {ns_c:.1f} | {full['wall_s']:.1f} | {ns_f:.1f} | "
              f"{s['peak_accel_mps2'] / full['peak_accel_mps2']:.4f} |")
    print("\n| case | peak |a| [m/s²] | at [ms] | peak per axis (body) [m/s²] | |Δv|/v | attitude change [rad] "
          "| contact duration [ms] | passed through | max penetration [m] | unresolved fin crossings "
          "| momentum err | energy err |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, s, full, *_ in rows:
        ax = ", ".join(f"{a:.3g}" for a in s["peak_accel_axis_mps2"])
        print(f"| {name} | {s['peak_accel_mps2']:.4g} | {s['peak_accel_time_s'] * 1e3:.2f} | {ax} | "
              f"{s['dv_over_v']:.2e} | {s['max_attitude_change_rad']:.2e} | {s['duration_s'] * 1e3:.2f} | "
              f"{s['passed_through']} | {s['max_penetration_m']:.2e} | {s['segment_crossings_unresolved']} | "
              f"{s['momentum_error_rel']:.1e} | {s['energy_error_rel']:.1e} |")
    if var_rows:
        print("\n| case | variant | peak |a| [m/s²] | |Δv|/v | passed through | max penetration [m] | "
              "tunnelling (depth/limit) | energy err | note |")
        print("|---|---|---|---|---|---|---|---|---|")
        for name, label, v, note in var_rows:
            if v is None:
                print(f"| {name} | {label} | – | – | – | – | – | – | {note} |")
            else:
                print(f"| {name} | {label} | {v['peak_accel_mps2']:.4g} | {v['dv_over_v']:.2e} | "
                      f"{v['passed_through']} | {v['max_penetration_m']:.3g} | "
                      f"{v['tunnelling']} ({v['max_penetration_ratio']:.3g}) | {v['energy_error_rel']:.1e} | |")


if __name__ == "__main__":
    main()
