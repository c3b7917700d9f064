"""Net kernel speed (ns per spring-step) and the deployment's sensitivity to the parameters the
paper does not give (rope diameter, launch direction).

    .venv/bin/python benchmarks/bench_net.py            # speed: numba kernel vs plain numpy
    .venv/bin/python benchmarks/bench_net.py --sweep    # max area vs rope diameter / launch direction

Speed: the 101 × 101 traction net (20 200 segments), one thread, the same time step and state,
the numba kernel and the plain-numpy second model of the same laws
(``flexnet_fe.study.net_numpy``) measured side by side in one run (repetitions interleaved,
medians).
"""

from __future__ import annotations

import argparse
import logging
import os
import tempfile
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from flexnet_fe.atmosphere import isa  # noqa: E402
from flexnet_fe.net.config import DeployConfig, RotaryNet, TractionNet  # noqa: E402


def speed(steps: int = 100, repeats: int = 7) -> None:
    """Kernel vs the numpy second model (``study.net_numpy``), air off and on, side by side."""
    from flexnet_fe.study.net_numpy import net_kernel_throughput

    print(f"traction net 101 x 101 (20 200 segments), {steps} steps x {repeats} interleaved repeats, medians, "
          f"NUMBA_NUM_THREADS = {os.environ['NUMBA_NUM_THREADS']}, load average {os.getloadavg()[0]:.2f}")
    print(f"{'case':10s} {'kernel ns/spring-step':>22s} {'numpy ns/spring-step':>22s} {'numpy/kernel':>13s}")
    for air_on in (False, True):
        r = net_kernel_throughput(101, air_on, steps, repeats)
        print(f"{'air ' + ('on' if air_on else 'off'):10s} {r['ns_per_spring_step_kernel']:22.2f} "
              f"{r['ns_per_spring_step_numpy']:22.2f} {r['ratio']:13.1f}   "
              f"(max |x_kernel - x_numpy| after the timed steps: {r['max_dx_m']:.1e} m)")


def sweep() -> None:
    log = logging.getLogger("flexnet.bench")
    air = isa(8000.0)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        def run(net, air_on, label):
            dep = DeployConfig(duration=0.9, air=air_on, snapshot_interval=0.9)
            s = run_deploy(net, dep, air, Path(tmp) / "run", log)
            rows.append((label, "on" if air_on else "off", s["first_max_area_m2"], s["time_to_first_max_area_s"],
                         s["max_area_m2"], s["time_to_max_area_s"], s["period_s"], s["max_tension_n"], s["wall_s"]))
            print("| " + " | ".join(str(c) if not isinstance(c, float) else f"{c:.4g}" for c in rows[-1]) + " |",
                  flush=True)

        from flexnet_fe.net.deploy import run_deploy
        print("| case | air | 1st max area [m²] | at t [s] | max area (0.9 s) [m²] | at t [s] | period [s] "
              "| max tension [N] | wall [s] |")
        print("|---|---|---|---|---|---|---|---|---|")
        for d in (3e-3, 4e-3, 4.5e-3, 5e-3, 6e-3):
            for air_on in (False, True):
                run(TractionNet(rope_diameter=d), air_on, f"traction d = {d * 1e3:g} mm")
        for az, el in ((30.0, 0.0), (45.0, 20.0), (45.0, 45.0)):
            for air_on in (False, True):
                run(TractionNet(launch_azimuth_deg=az, launch_elevation_deg=el), air_on,
                    f"traction d = 4.5 mm, azimuth {az:g}°, elevation {el:g}°")
        for d in (4e-3, 5e-3, 6e-3, 7e-3):
            for air_on in (False, True):
                run(RotaryNet(rope_diameter=d), air_on, f"rotary d = {d * 1e3:g} mm")
        for air_on in (False, True):
            run(RotaryNet(warp_initial_state="rest"), air_on, "rotary d = 6 mm, warps at rest")


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--sweep", action="store_true", help="parameter sweep instead of the speed benchmark")
    a = p.parse_args()
    sweep() if a.sweep else speed()
