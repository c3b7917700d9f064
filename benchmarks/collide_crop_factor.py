"""Crop reach of the collision (issue 15, defaults on the Pareto front): the shipped
radar_traction impact at collide.crop_wave_speed_factor 4 and 2, CPU time and headlines side by
side. Usage: PYTHONPATH=. .venv/bin/python benchmarks/collide_crop_factor.py RUN/deploy OUT.json
(measured 2026-11-23: docs/study/collide_crop_factor.json)."""
import json, logging, sys, time
from pathlib import Path
logging.basicConfig(level=logging.WARNING)
from flexnet_fe.study.scenes import CASE, case_with, FULL_COLLIDE
from flexnet_fe.study.collide import simulate_case, headline
ddir = Path(sys.argv[1])  # the deploy/ folder of a run of cases/radar_traction
out = {}
for f in (4.0, 2.0):
    case = case_with(CASE, FULL_COLLIDE + (f"collide.crop_wave_speed_factor={f}",))
    c0, w0 = time.process_time(), time.perf_counter()
    net, missile, res = simulate_case(case, ddir)
    s = res.summary
    out[f] = {"cpu_s": time.process_time() - c0, "wall_s": time.perf_counter() - w0, **headline(s),
              "active_segments": s["active_segments"], "steps": s["steps"], "energy_error_rel": s["energy_error_rel"]}
    print(f, out[f], flush=True)
json.dump(out, open(sys.argv[2], "w"), indent=1)
