"""radar_traction's impact (no resolution check, fin loads at the 10 µs output interval) at one
``collide.rope_split``: its headlines and CPU appended as one JSON row.

    PYTHONPATH=. .venv/bin/python benchmarks/collide_rope_split.py OUT.jsonl DEPLOY_DIR K [KEY=VALUE ...]

Rows of docs/data/collide_rope_split.jsonl (k = 4 / 8 / 16 / 32; docs/collide_convergence.md,
sixteenth pass; the case file's rope_split comment)."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path


def main() -> None:
    from flexnet_fe.config import load_case
    from flexnet_fe.study.collide import simulate_case

    out, deploy, k, extra = sys.argv[1], Path(sys.argv[2]), int(sys.argv[3]), sys.argv[4:]
    overrides = ["collide.resolution_check=false", "collide.load_interval=1e-5", f"collide.rope_split={k}", *extra]
    case, _ = load_case(Path("cases/radar_traction"), overrides)
    c0 = time.process_time()
    _, _, res = simulate_case(case, deploy)
    s = res.summary
    row = {k_: s[k_] for k_ in ("dv_over_v", "peak_accel_mps2", "impulse_ns", "fin_impulse_ns", "duration_s",
                                "energy_error_rel", "steps")}
    row.update(rope_split=k, cpu_s=time.process_time() - c0, overrides=overrides, date=time.strftime("%Y-%m-%d %H:%M"))
    with open(out, "a") as fh:
        fh.write(json.dumps(row) + "\n")
    print(json.dumps(row))


if __name__ == "__main__":
    main()
