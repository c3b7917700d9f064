"""Flight-stage timing: one engagement (paper §VI baseline) at two step sizes, side by side.

Run: .venv/bin/python benchmarks/bench_flight.py
Prints wall time per engagement, ns per RK4 step (5 right-hand-side evaluations incl. the
closest-approach check) and the ratio between the two steps (ideal: 2.0).
"""

from __future__ import annotations

import time

from flexnet_fe.flight.config import FlightConfig
from flexnet_fe.flight.stage import simulate_flight

ALT = 8000.0


def main() -> None:
    simulate_flight(FlightConfig(), ALT)  # compile / load the numba cache
    rows = []
    for dt in (1e-4, 5e-5):
        best = None
        for _ in range(3):
            t0 = time.perf_counter()
            r = simulate_flight(FlightConfig(dt=dt), ALT)
            wall = time.perf_counter() - t0
            if best is None or wall < best[0]:
                best = (wall, r.kernel_wall_s, r.steps, r.miss_distance_m)
        rows.append((dt, *best))
    print(f"{'dt [s]':>8} {'wall [s]':>9} {'kernel [s]':>10} {'steps':>7} {'ns/step':>8} {'miss [m]':>14}")
    for dt, wall, kern, steps, miss in rows:
        print(f"{dt:8.0e} {wall:9.3f} {kern:10.3f} {steps:7d} {1e9 * kern / steps:8.0f} {miss:14.9f}")
    print(f"kernel time ratio dt/2 : dt = {rows[1][2] / rows[0][2]:.2f} (ideal 2.00)")


if __name__ == "__main__":
    main()
