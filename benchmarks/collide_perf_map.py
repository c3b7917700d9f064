"""Where the collide kernel's time goes, by compiled function: radar × traction's impact under ``perf``.

    perf record -F 499 -g -o /tmp/impact.data -- env NUMBA_CACHE_DIR=/tmp/empty_cache PYTHONPATH=. \\
        .venv/bin/python benchmarks/collide_perf_map.py profile DEPLOY_DIR [KEY=VALUE ...]
    perf report -i /tmp/impact.data --stdio --no-children --sort symbol -g none
    PYTHONPATH=. .venv/bin/python benchmarks/collide_perf_map.py time DEPLOY_DIR [KEY=VALUE ...]

DEPLOY_DIR: the ``deploy/`` folder of a run of cases/radar_traction (the held net); KEY=VALUE: case
overrides. ``profile`` runs the impact (no resolution check) and then writes ``/tmp/perf-<pid>.map``, the
address and size of every function numba compiled in this process, so ``perf report`` names them (perf
reads that file for JIT code). The functions must be compiled in the process — an empty
``NUMBA_CACHE_DIR`` — because code loaded from numba's cache keeps no LLVM module to read the names from;
the compilation's samples then show up as LLVM and numba frames, easy to tell apart. ``time`` prints the
impact's CPU and wall time and headlines as one JSON line (run two versions of the code at once, one per
core, for a side-by-side ratio). Results: docs/performance.md, "No reference counting in the collide
kernel"."""
from __future__ import annotations

import gc
import json
import logging
import os
import sys
import time
from pathlib import Path

logging.basicConfig(level=logging.WARNING)
CASE = Path(__file__).resolve().parent.parent / "cases" / "radar_traction"


def impact(deploy: str, overrides: list[str]):
    """(summary, CPU [s], wall [s]) of the case's impact, no resolution check, two snapshots."""
    import flexnet_fe.collide.scene  # noqa: F401  (before study.collide: import order)
    from flexnet_fe.study.collide import simulate_case
    from flexnet_fe.study.scenes import case_with

    case = case_with(CASE, tuple(overrides) + ("collide.snapshots=2", "collide.resolution_check=false"))
    c0, w0 = time.process_time(), time.perf_counter()
    _, _, res = simulate_case(case, Path(deploy))
    return res.summary, time.process_time() - c0, time.perf_counter() - w0


def write_perf_map() -> int:
    """Write /tmp/perf-<pid>.map for the numba functions compiled in this process; returns their count.
    Sizes are the gaps to the next function's address (LLVM does not report them)."""
    import numba

    names = {}
    for obj in gc.get_objects():
        if not isinstance(obj, numba.core.registry.CPUDispatcher):
            continue
        for cres in obj.overloads.values():
            lib = cres.library
            try:
                module = lib._final_module
            except Exception:  # loaded from the cache: no module
                continue
            for fn in module.functions:
                if fn.is_declaration:
                    continue
                address = lib._codegen._engine.get_function_address(fn.name)
                if address:
                    names[address] = fn.name
    addresses = sorted(names)
    with open(f"/tmp/perf-{os.getpid()}.map", "w") as fh:
        for k, a in enumerate(addresses):
            size = min(addresses[k + 1] - a if k + 1 < len(addresses) else 4096, 1 << 22)
            fh.write(f"{a:x} {size:x} {names[a]}\n")
    return len(addresses)


def main(argv: list[str]) -> None:
    mode, deploy, overrides = argv[0], argv[1], argv[2:]
    s, cpu, wall = impact(deploy, overrides)
    print(json.dumps({"overrides": overrides, "cpu_s": cpu, "wall_s": wall, "steps": s["steps"],
                      "dv_over_v": s["dv_over_v"], "fin_impulse_ns": s["fin_impulse_ns"],
                      "energy_error_rel": s["energy_error_rel"], "far_net_ratio": s.get("far_net_ratio"),
                      "peak_accel_mps2": s["peak_accel_mps2"]}), flush=True)
    if mode == "profile":
        print("perf map:", write_perf_map(), "functions", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
