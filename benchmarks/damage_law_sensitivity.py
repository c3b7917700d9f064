"""Sensitivity of the flight outcome to the damage law (fin stress → lost aerodynamic area).

Takes a run directory whose shell stage wrote ``shell/<fin>/envelope.xdmf`` (e.g. a run of
cases/radar_traction or one point of the engagement map) and, for each damage law and parameter
and for the envelope's stresses scaled by a load factor λ (a stand-in for a harder impact:
linear-elastic stresses scale with the load), prints the lost area of each fin, the wing damage
/ rudder effectiveness and the miss distance of the paper's engagement (geometry damage model).

Run: PYTHONPATH=. .venv/bin/python benchmarks/damage_law_sensitivity.py RUN_DIR [λ1,λ2,...]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from flexnet_fe.flight.config import DamageLawConfig, FlightConfig
from flexnet_fe.flight.damage import FinDamage, lost_cells, read_cell_field
from flexnet_fe.flight.stage import simulate_flight
from flexnet_fe.missile.config import FinMaterial

LAWS = [DamageLawConfig(law="overstressed_area", threshold_factor=k) for k in (0.8, 1.0, 572.0 / 503.0)] + \
       [DamageLawConfig(law="failure_strain", failure_strain=e) for e in (0.02, 0.05, 0.11)]
"""k = 572/503: 7075-T6 ultimate / yield (ASM / MatWeb); ε_f = 11 %: its elongation at break."""


def law_name(law: DamageLawConfig) -> str:
    if law.law.value == "overstressed_area":
        return f"σ > {law.threshold_factor:.2f} σ_y"
    return f"Neuber ε > {law.failure_strain:.0%}"


def main(run_dir: Path, scales: list[float]) -> None:
    mat = FinMaterial()
    fields = {env.parent.name: read_cell_field(env) for env in sorted((run_dir / "shell").glob("*/envelope.xdmf"))}
    print("peak von Mises per fin [MPa]: " + ", ".join(f"{k} {v[1].max() / 1e6:.0f}" for k, v in fields.items()))
    print("| load factor λ | law | lost area per fin | wing damage | rudder eff. | miss [m] |")
    print("|---|---|---|---|---|---|")
    flight = FlightConfig(dt=2e-4)
    for lam in scales:
        for law in LAWS:
            lost = {k: float(a[lost_cells(lam * p, law, mat.yield_strength, mat.youngs_modulus)].sum() / a.sum())
                    for k, (a, p) in fields.items()}
            fins = FinDamage(np.array([1.0 - lost.get(n, 0.0) for n in FinDamage.NAMES]))
            try:
                r = simulate_flight(flight, 8000.0, fins=fins)
                miss = f"{r.miss_distance_m:.2f}" if r.closest_approach_found else "no closest approach"
            except Exception as err:  # noqa: BLE001 - a diverging missile is a miss; print why
                miss = f"miss ({str(err)[:40]}…)"
            shown = ", ".join(f"{k} {v:.2f}" for k, v in lost.items() if v > 0) or "none"
            print(f"| {lam:g} | {law_name(law)} | {shown} | {fins.wing_damage:.3f} | "
                  f"{fins.rudder_effectiveness:.3f} | {miss} |")


if __name__ == "__main__":
    main(Path(sys.argv[1]), [float(x) for x in (sys.argv[2] if len(sys.argv) > 2 else "1,2,4").split(",")])
