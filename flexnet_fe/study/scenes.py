"""The scenes the studies run: the paper case ``cases/radar_traction`` (full study) or a reduced
version of it (``--quick``), as case-file overrides, so every knob is set the way a user sets it
(``--set``) and a knob the schema does not know is refused by the schema, not guessed."""

from __future__ import annotations

from pathlib import Path

from flexnet_fe.config import load_case

CASE = Path(__file__).resolve().parents[2] / "cases" / "radar_traction"
"""The default case (the issue's speed target names it)."""

FLIGHT_CASE = Path(__file__).resolve().parents[2] / "cases" / "flight_baseline"

QUICK_NET = ("net.edge_length=2.0", "net.mesh_size=0.1", "net.corner_mass=0.2")
"""Reduced traction net for --quick: 2 m square, 10 cm mesh (441 nodes), 0.2 kg corner masses
(the paper's 5 m / 5 cm / 1 kg net has 10 201 nodes)."""

QUICK_DEPLOY = QUICK_NET + ("deploy.duration=0.2", "deploy.snapshot_interval=0.2")
FULL_DEPLOY = ("deploy.snapshot_interval=0.4",)
"""Snapshots (.vtu) are not part of what the study measures: one at the end only."""

NO_FIN_CUT = ("collide.fin_piece_length=1.0", "collide.fin_piece_chord=1.0")
"""The rope not cut at the fins, neither at the start nor during the run (a 1 m piece or chord is
longer than any bar of the reduced nets, so ``collide.refine`` and ``collide.adapt`` cut nothing): the reduced scenes check the machinery, the step and the
contact law, not the rope's resolution at the fin edges, which the full study and
docs/collide_convergence.md measure on the shipped case (its 1.4 mm pieces would multiply the
quick scenes' cost ≈ 10–50×)."""

LOADS_AT_OUTPUT = ("collide.load_interval=1e-5",)
"""The collision studies read Δv, impulses and the CFC peak, which do not depend on the fin loads'
sampling: sample them at the output interval (the case's 0.3125 µs would call the kernel 32× per
interval and cap the step at it)."""

COARSE_FIN_CUT = ("collide.fin_piece_length=0.02", "collide.fin_piece_chord=0.02")
"""The quick impact's rope cut to 2 cm pieces where a fin passes (at the start and while it presses,
``collide.refine``, ``collide.adapt``): uncut, its 20 cm bars each meet a wing edge with 20 cm of rope
that cannot bend round it, and the default line law lets one through (tunnelling at wing_4, 366 m/s;
the segment law reached 0.87 of the core) — the run stops, as it must. Cut to 2 cm both laws
stay below 0.45 of it and the quick points cost 4–7 s (2026-11-28, either law; uncut, Δv/v read
2.4e-4 against 2.9e-5 cut: the coarse bars hooked on the wings)."""

QUICK_COLLIDE = ("net.edge_length=2.0", "net.mesh_size=0.2", "collide.net_source='flat_taut'",
                 "collide.snapshots=2", "collide.rope_split=1", "collide.max_duration=0.012") + COARSE_FIN_CUT \
    + LOADS_AT_OUTPUT
"""Reduced impact for --quick: the radar missile at 500 m/s through a flat taut 2 m net with a
20 cm mesh (121 nodes) instead of the deployed 5 m / 5 cm net at its maximum area, ropes not
split (rope_split 1), cut to 2 cm at the fins (``COARSE_FIN_CUT``), run to the 12 ms duration (no
extension: the case's 30 ms cap would run on while the coarse rope hangs on the rudders) — the
quick scene checks the machinery and the dt/travel resolution; the rope split's convergence is
the full study's — at 20 cm cells it is far from converged: Δv/v 1.36e-4 / 6.8e-5 / 4.8e-5 at
k = 2 / 4 / 8, measured 2026-11-23, uncut, segment law)."""
FULL_COLLIDE = ("collide.snapshots=2",) + LOADS_AT_OUTPUT


def case_with(path: Path, overrides) -> object:
    """The validated case with ``overrides`` (``KEY=VALUE`` strings); CaseError on a bad key."""
    case, _ = load_case(path, list(overrides))
    return case
