"""What one call of the collision kernel costs besides its steps: radar_traction's impact model at
t = 0 (the cropped net, the missile about to strike), calls of 0 … 256 steps with a kept scratch
(``kernel.advance_kept``) and with a new one per call (``kernel.advance``).

    PYTHONPATH=. .venv/bin/python benchmarks/collide_call_overhead.py DEPLOY_DIR

DEPLOY_DIR: a finished deploy stage of cases/radar_traction (its net_state.npz). Prints µs per call
(docs/performance.md, "Collide: a kernel call costs its steps")."""

from __future__ import annotations

import logging
import sys
import time
from pathlib import Path


def main() -> None:
    from flexnet_fe.atmosphere import isa
    from flexnet_fe.collide import kernel as K
    from flexnet_fe.collide import model as M
    from flexnet_fe.collide import simulate as S
    from flexnet_fe.collide.refine import refine_near_fins, split_near_path
    from flexnet_fe.collide.scene import held_net
    from flexnet_fe.config import load_case
    from flexnet_fe.missile.build import build_missile

    case, _ = load_case(Path("cases/radar_traction"), ["collide.resolution_check=false"])
    cfg = case.collide
    net = held_net(case.net, cfg.net_source, Path(sys.argv[1]))
    missile = build_missile(case.missile)
    air = isa(case.atmosphere.altitude)
    net = refine_near_fins(split_near_path(net, missile, cfg), missile, cfg)
    setup = S.build(net, missile, cfg, air.gravity, logging.getLogger("bench"), cfg.crop, air.density)
    km, start = setup.model, setup.start
    st = M.new_state(net.x[setup.used], km.seg.shape[0], km.fin_half.shape[0], start.x_cg, start.v_cg, start.q)
    dt = 3.4e-8  # the contact step once the rope is cut at the fins
    print(f"{st.x.shape[0]} nodes, {km.seg.shape[0]} segments")
    K.advance(km, st, 1, dt, 4)  # compile
    for n, r in [(0, 4), (1, 4), (4, 4), (8, 4), (8, 8), (32, 8), (256, 8)]:
        reps = 50
        t = time.perf_counter()
        for _ in range(reps):
            assert K.advance(km, st, n, dt, r) == M.OK
        new = (time.perf_counter() - t) / reps
        wk = K.new_work(km, st)  # (valid for this state's motion and this window only: made here)
        assert K.advance_kept(km, st, wk, n, dt, r, n) == M.OK
        t = time.perf_counter()
        for _ in range(reps):
            assert K.advance_kept(km, st, wk, n, dt, r, n) == M.OK
        kept = (time.perf_counter() - t) / reps
        print(f"{n:4d} steps, windows of {r}: new work {new * 1e6:9.1f} µs, kept work {kept * 1e6:9.1f} µs per call")

if __name__ == "__main__":
    main()
