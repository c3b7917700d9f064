"""Deploy kernel A/B: this tree's ``net.kernels.advance`` against another version of the module,
side by side in one process (thread CPU time, interleaved repetitions, alternating order).

    git show <rev>:flexnet_fe/net/kernels.py > /tmp/kernels_other.py
    PYTHONPATH=. .venv/bin/python benchmarks/net_kernel_ab.py /tmp/kernels_other.py [--steps 100 --repeats 15]

The other module is loaded under its own name (its own numba dispatchers and cache, next to the
file); both run the 101 × 101 traction net (20 200 segments) and the default rotary net from the
same state (Mach 3 at 8 km, gravity, dt = ½ the stability limit), air off and on. Each repetition
times one ``steps``-step call of each, in alternating order; reported: the median time per
spring-step of each and the median, min and max of the per-repetition ratio this / other
(paired, so both saw the same machine load). Also checks the two end states are equal to the bit.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import statistics
import sys
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from flexnet_fe.atmosphere import isa  # noqa: E402
from flexnet_fe.net import kernels  # noqa: E402
from flexnet_fe.net.config import RotaryNet, TractionNet  # noqa: E402
from flexnet_fe.net.state import Environment, initial_state, kernel_model, kernel_state  # noqa: E402
from flexnet_fe.net.timestep import choose_time_step  # noqa: E402
from flexnet_fe.net.topology import build_net  # noqa: E402


def _load(path: str):
    spec = importlib.util.spec_from_file_location("kernels_other", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # numba's cache pickles references to the module by name
    spec.loader.exec_module(mod)
    # this tree's state types, so that the functions both versions call (net.hub, net.forces) are
    # compiled for the same types: typed with the other module's classes, their cache index in
    # this tree would name a module no other process has, and fail to load there
    mod.DeployModel, mod.DeployState = kernels.DeployModel, kernels.DeployState
    return mod


def _timed(advance, km, model, flight, dt, steps):
    s = initial_state(model, flight)
    ks = kernel_state(s)
    t0 = time.thread_time()
    advance(km, ks, steps, dt)
    return time.thread_time() - t0, s


def compare(other, name, net, air, steps, repeats):
    """One case: prints the medians and the paired ratio's spread."""
    atm = isa(8000.0)
    model = build_net(net)
    env = Environment(np.array([0.0, -atm.gravity, 0.0]), atm.density if air else 0.0, np.zeros(3), air)
    flight = (0.0, 0.0, 3.0 * atm.speed_of_sound)
    s0 = initial_state(model, flight)
    dt = choose_time_step(model, s0.x, s0.v, env.rho, 0.5, None).dt
    km = kernel_model(model, env)
    pair = (kernels.advance, other.advance)
    for adv in pair:  # compile / load the caches
        adv(km, kernel_state(initial_state(model, flight)), 1, dt)
    times, ratios = ([], []), []
    for rep in range(repeats):
        order = (0, 1) if rep % 2 == 0 else (1, 0)
        got = {}
        for w in order:
            got[w] = _timed(pair[w], km, model, flight, dt, steps)
            times[w].append(got[w][0])
        ratios.append(got[0][0] / got[1][0])
    same = all(np.array_equal(getattr(got[0][1], a), getattr(got[1][1], a)) for a in ("x", "v", "tension", "hub"))
    per = 1e9 / (steps * model.n_springs)
    print(f"{name:9s} air {'on ' if air else 'off'} {statistics.median(times[0]) * per:9.2f} "
          f"{statistics.median(times[1]) * per:9.2f}   {statistics.median(ratios):.3f} "
          f"[{min(ratios):.3f}, {max(ratios):.3f}]   end states equal: {same}", flush=True)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("other", help="path of the other kernels.py")
    p.add_argument("--steps", type=int, default=100)
    p.add_argument("--repeats", type=int, default=15)
    a = p.parse_args()
    other = _load(a.other)
    print(f"this: {kernels.__file__}\nother: {other.__file__}\n{a.steps} steps x {a.repeats} paired repeats, "
          f"thread CPU time, NUMBA_NUM_THREADS = {os.environ['NUMBA_NUM_THREADS']}, "
          f"load average {os.getloadavg()[0]:.2f}, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
    print(f"{'case':13s} {'this ns':>9s} {'other ns':>9s}   this/other median [min, max]  (ns per spring-step)")
    for name, net in (("traction", TractionNet()), ("rotary", RotaryNet())):
        for air in (False, True):
            compare(other, name, net, air, a.steps, a.repeats)


if __name__ == "__main__":
    main()
