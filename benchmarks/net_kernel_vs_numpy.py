"""Issue 15's net-kernel target, side by side: the plain-numpy model (``study.net_numpy.NumpyNet``),
this tree's ``net.kernels.advance`` and another version of ``kernels.py``, in one process.

    git show <rev>:flexnet_fe/net/kernels.py > /tmp/kernels_other.py
    PYTHONPATH=. .venv/bin/python benchmarks/net_kernel_vs_numpy.py /tmp/kernels_other.py [--steps 400 --repeats 9]

The set-up of ``study.net_numpy.net_kernel_throughput`` (the number ``flexnet study throughput``
reports): the 101 × 101 traction net (20 200 segments), Mach 3 at 8 km, gravity, dt = ¼ of the
spring limit, ``steps`` steps per timing from the same state, air off and on. Each repetition times
the three once each, in an order that alternates (this, other, numpy / numpy, other, this), with
thread CPU time, so all three see the same machine load. Reported per case: the median ns per
spring-step of each, and the median [min, max] of the per-repetition ratios numpy / this,
numpy / other and this / other; and whether this and the other end at the same state to the bit
(positions, velocities, tensions).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from flexnet_fe.net import kernels  # noqa: E402
from flexnet_fe.net.state import initial_state, kernel_state  # noqa: E402
from flexnet_fe.study.net_numpy import throughput_scene  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
from net_kernel_ab import _load  # noqa: E402  (the other kernels.py as a module of its own)


def _spread(values) -> str:
    return f"{statistics.median(values):6.2f} [{min(values):6.2f}, {max(values):6.2f}]"


def compare(other, air: bool, steps: int, repeats: int) -> None:
    """One case (air off or on): prints the medians and the paired ratios' spread."""
    model, km, ref, dt, flight = throughput_scene(101, air)  # net_kernel_throughput's scene
    runs = {"this": lambda s: kernels.advance(km, kernel_state(s), steps, dt),
            "other": lambda s: other.advance(km, kernel_state(s), steps, dt),
            "numpy": lambda s: ref.step(s.x, s.v, dt, steps)}
    for name in ("this", "other"):  # compile / load the caches
        runs[name](initial_state(model, flight))
    times = {name: [] for name in runs}
    ends = {}
    for rep in range(repeats):
        for name in (("this", "other", "numpy") if rep % 2 == 0 else ("numpy", "other", "this")):
            s = initial_state(model, flight)
            t0 = time.thread_time()
            runs[name](s)
            times[name].append(time.thread_time() - t0)
            ends[name] = s
    per = 1e9 / (steps * model.n_springs)
    med = {name: statistics.median(t) * per for name, t in times.items()}
    ratio = {key: [a / b for a, b in zip(times[key[0]], times[key[1]])]
             for key in (("numpy", "this"), ("numpy", "other"), ("this", "other"))}
    same = all(np.array_equal(getattr(ends["this"], a), getattr(ends["other"], a)) for a in ("x", "v", "tension"))
    print(f"air {'on ' if air else 'off'}  {med['this']:6.2f} {med['other']:6.2f} {med['numpy']:7.2f}   "
          f"{_spread(ratio['numpy', 'this'])}  {_spread(ratio['numpy', 'other'])}  "
          f"{_spread(ratio['this', 'other'])}   same end state: {same}", flush=True)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("other", help="path of the other kernels.py")
    p.add_argument("--steps", type=int, default=400)
    p.add_argument("--repeats", type=int, default=9)
    a = p.parse_args()
    other = _load(a.other)
    print(f"this: {kernels.__file__}\nother: {other.__file__}\n{a.steps} steps x {a.repeats} repetitions, "
          f"thread CPU time, NUMBA_NUM_THREADS = {os.environ['NUMBA_NUM_THREADS']}, "
          f"load average {os.getloadavg()[0]:.2f}, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
    print("ns per spring-step: this other numpy | ratios, median [min, max]: numpy/this  numpy/other  this/other")
    for air in (False, True):
        compare(other, air, a.steps, a.repeats)
    print(f"load average at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
