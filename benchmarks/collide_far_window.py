"""Cost of the collide kernel's far-net window against its fine steps (issue 9 speed; not a test).

Runs radar_traction's collision (this tree, shipped case) to the output call CALL, keeps that state,
then times in one process: one far-net window (``kernel._far_window``: the split, the slow forces,
the moves), the window-start check alone, all rope forces, and a whole call of ``advance`` per step.
Results: docs/performance.md, "Collide: the far net in windows and nose cones".

    PYTHONPATH=. .venv/bin/python benchmarks/collide_far_window.py DEPLOY_DIR [CALL] [REPS]
"""
from __future__ import annotations

import sys
import time
import types
from pathlib import Path

import numpy as np
from numba import njit

from flexnet_fe.collide import kernel as K
from flexnet_fe.collide import simulate as SIM
from flexnet_fe.frames import quat_to_matrix
from flexnet_fe.study.collide import simulate_case
from flexnet_fe.study.scenes import case_with


class _Stop(Exception):
    pass


def _state_at(deploy: Path, call: int):
    """(model, state, steps per call, dt, ratio) when the run reaches output call ``call``."""
    seen = {}

    def advance(km, st, n, dt, ratio):
        seen["k"] = seen.get("k", 0) + 1
        if seen["k"] == call:
            seen["at"] = (km, st._replace(**{f: getattr(st, f).copy() for f in st._fields}), n, dt, ratio)
            raise _Stop
        return K.advance(km, st, n, dt, ratio)

    real = SIM.K
    SIM.K = types.SimpleNamespace(advance=advance, energies=K.energies, net_energies=K.net_energies)
    try:
        simulate_case(case_with(Path("cases/radar_traction"), ["collide.snapshots=2"]), deploy)
    except _Stop:
        pass
    finally:
        SIM.K = real
    return seen["at"]


@njit
def _windows(km, st, reps, w, dt):
    wk = K._work(km, st.x.shape[0])
    alln = np.arange(st.x.shape[0])
    for r in range(reps):
        wk.r[:, :] = quat_to_matrix(st.mq)
        K._far_window(km, st, wk, alln, w, dt, r == 0)


@njit
def _checks(km, st, reps):
    wk = K._work(km, st.x.shape[0])
    alln = np.arange(st.x.shape[0])
    for _ in range(reps):
        K._far_check(km, st, wk, alln)


@njit
def _ropes(km, st, reps, dt):
    wk = K._work(km, st.x.shape[0])
    for _ in range(reps):
        K._rope_forces(km, st, wk, dt, wk.fseg, wk.nlist[0])


def main() -> None:
    deploy = Path(sys.argv[1])
    call = int(sys.argv[2]) if len(sys.argv) > 2 else 700
    reps = int(sys.argv[3]) if len(sys.argv) > 3 else 200
    km, st, n, dt, ratio = _state_at(deploy, call)
    copy = lambda: st._replace(**{f: getattr(st, f).copy() for f in st._fields})  # noqa: E731
    _windows(km, copy(), 1, 16, dt), _checks(km, copy(), 1), _ropes(km, copy(), 1, dt)  # compile
    K.advance(km, copy(), 1, dt, ratio)
    out = {}
    for name, fn, args in (("window", _windows, (reps, 16, 1e-12)), ("check", _checks, (reps,)),
                           ("all rope forces", _ropes, (reps, 1e-12))):
        s = copy()
        t = time.perf_counter()
        fn(km, s, *args)
        out[name] = (time.perf_counter() - t) / reps
    t = time.perf_counter()
    K.advance(km, copy(), n, dt, ratio)
    per_step = (time.perf_counter() - t) / n
    print(f"radar_traction at output call {call}: {km.seg.shape[0]} segments, {st.x.shape[0]} nodes, ratio {ratio}")
    for name, sec in out.items():
        print(f"  {name}: {sec * 1e6:.0f} µs")
    print(f"  advance, per step over one call of {n}: {per_step * 1e6:.1f} µs (window / 16: "
          f"{out['window'] / 16 * 1e6:.1f} µs)")


if __name__ == "__main__":
    main()
