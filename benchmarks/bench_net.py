"""Net kernel speed (ns per spring-step) and the deployment's sensitivity to the parameters the
paper does not give (rope diameter, launch direction).

    .venv/bin/python benchmarks/bench_net.py            # speed: numba kernel vs plain numpy
    .venv/bin/python benchmarks/bench_net.py --sweep    # max area vs rope diameter / launch direction

Speed: the 101 × 101 traction net (20 200 segments), one thread, the same time step and state,
numba kernel and a vectorised numpy step measured side by side in one run.
"""

from __future__ import annotations

import argparse
import logging
import os
import tempfile
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from flexnet_fe.atmosphere import isa  # noqa: E402
from flexnet_fe.net.config import DeployConfig, RotaryNet, TractionNet  # noqa: E402
from flexnet_fe.net.forces import C_CROSS, CD_FRICTION  # noqa: E402
from flexnet_fe.net.state import Environment, initial_state, step_many  # noqa: E402
from flexnet_fe.net.timestep import spring_limit  # noqa: E402
from flexnet_fe.net.topology import build_traction  # noqa: E402


def numpy_step(model, x, v, dt, rho, air, g):
    """One symplectic-Euler step with vectorised numpy (same laws as the kernel, no hub)."""
    i, j = model.springs[:, 0], model.springs[:, 1]
    d = x[j] - x[i]
    l = np.sqrt(np.einsum("ij,ij->i", d, d))
    u = d / l[:, None]
    ldot = np.einsum("ij,ij->i", v[j] - v[i], u)
    stretch = l - (model.rest_length - model.slack_offset)
    t = np.where(stretch > 0, model.stiffness * stretch + model.damping * ldot, 0.0)
    t = np.maximum(t, 0.0)
    fs = t[:, None] * u
    if air:
        vr = 0.5 * (v[i] + v[j])
        vm = np.sqrt(np.einsum("ij,ij->i", vr, vr))
        ve = np.einsum("ij,ij->i", vr, u)
        vn = vr - ve[:, None] * u
        vnm = np.sqrt(np.maximum(vm * vm - ve * ve, 0.0))
        fa = -0.5 * rho * model.diameter[:, None] * l[:, None] * (
            CD_FRICTION * vm[:, None] * vr + C_CROSS * vnm[:, None] * vn)
    n = len(x)
    f = model.mass[:, None] * g[None, :]
    for k in range(3):
        f[:, k] += np.bincount(i, fs[:, k], n) - np.bincount(j, fs[:, k], n)
        if air:
            f[:, k] += 0.5 * (np.bincount(i, fa[:, k], n) + np.bincount(j, fa[:, k], n))
    v += dt * f / model.mass[:, None]
    x += dt * v


def speed(steps: int = 400, repeats: int = 3) -> None:
    import numba
    numba.set_num_threads(1)
    model = build_traction(TractionNet())
    air = isa(8000.0)
    dt = 0.25 * spring_limit(model)
    flight = (0.0, 0.0, 3 * air.speed_of_sound)
    print(f"traction net 101 x 101: {model.n_nodes} nodes, {model.n_springs} segments, dt = {dt:.3g} s, "
          f"{steps} steps, numba threads = {numba.get_num_threads()}")
    print(f"{'case':10s} {'numba ns/spring-step':>22s} {'numpy ns/spring-step':>22s} {'numpy/numba':>12s}")
    for air_on in (False, True):
        env = Environment(np.array([0.0, -air.gravity, 0.0]), air.density if air_on else 0.0, np.zeros(3), air_on)
        st = initial_state(model, flight)
        step_many(model, st, env, dt, 2)  # compile / warm
        best_nb = np.inf
        for _ in range(repeats):
            st = initial_state(model, flight)
            t0 = time.perf_counter()
            step_many(model, st, env, dt, steps)
            best_nb = min(best_nb, time.perf_counter() - t0)
        best_np = np.inf
        for _ in range(repeats):
            x, v = model.x0.copy(), model.v0 + np.asarray(flight)
            t0 = time.perf_counter()
            for _ in range(steps // 10):
                numpy_step(model, x, v, dt, env.rho, air_on, env.gravity)
            best_np = min(best_np, (time.perf_counter() - t0) * 10)
        # same physics: compare one step of each from the same state
        st = initial_state(model, flight)
        x, v = model.x0.copy(), model.v0 + np.asarray(flight)
        step_many(model, st, env, dt, 50)
        for _ in range(50):
            numpy_step(model, x, v, dt, env.rho, air_on, env.gravity)
        diff = np.abs(st.x - x).max()
        per = 1e9 / (steps * model.n_springs)
        print(f"{'air ' + ('on' if air_on else 'off'):10s} {best_nb * per:22.2f} {best_np * per:22.2f} "
              f"{best_np / best_nb:12.1f}   (max |x_numba - x_numpy| after 50 steps: {diff:.1e} m)")


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
