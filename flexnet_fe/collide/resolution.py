"""The collision's resolution check (``[collide] resolution_check``): how far each headline moves
when the rope pieces at the fins are halved.

The rope's resolution at the fins is the collision's one knob the headlines are known to depend on
(docs/collide_convergence.md): on radar × traction a strand's friction lock on the rudder tips is
resolved only by pieces ≤ 0.1 mm, and at the case's 0.7 mm Δv reads 8 % low with nothing in the
run to say so. The check runs the impact a second time with ``fin_piece_length`` / 2 (and
``fin_piece_chord`` / 2 when set: the pieces cut where they press, ``collide.adapt``) and reports,
per headline, the relative move (fine − coarse) / fine; a move beyond the tolerance is a warning.
A small move does not prove convergence (it is one halving), a large one disproves it.
"""

from __future__ import annotations

import math

SHARE_MIN = 0.02
"""Fins carrying less than this share of the total fin impulse (in the finer run) are not checked:
their relative move says nothing about the headlines."""

HEADLINES = (("dv_over_v", "dv_over_v_move_rel", "Δv/v"), ("peak_accel_mps2", "peak_accel_move_rel", "CFC peak"),
             ("impulse_ns", "impulse_move_rel", "impulse"), ("duration_s", "duration_move_rel", "contact duration"))
"""(summary key, key of its move, name in the warning)."""


def _move(coarse: float, fine: float) -> float:
    """(fine − coarse) / |fine| [-]; 0 when both are 0, and −1 (all of it gone, sign of −coarse) when
    only the finer run is 0 — always finite, so summary.json stays strict JSON."""
    if fine == 0.0:
        return 0.0 if coarse == 0.0 else -math.copysign(1.0, coarse)
    return (fine - coarse) / abs(fine)


def resolution_moves(coarse: dict, fine: dict, piece: float, tolerance: float,
                     chord: float | None = None) -> tuple[dict, list[str]]:
    """The ``resolution_check`` summary section and its warnings, from the collide summaries of the
    run (``coarse``, pieces of 2 × ``piece`` [m] at the fins) and of the check (``fine``, pieces of
    ``piece``; chord [m]: its ``fin_piece_chord``, when set). Moves are relative to the finer run;
    ``tolerance`` [-] the largest move not flagged.
    Returns (section, warnings): section = {fin_piece_length_m, tolerance, <headline>_move_rel, …,
    fin_impulse_move_rel: {fin: move}, flagged: [names]}."""
    section: dict = {"fin_piece_length_m": piece, "tolerance": tolerance}
    flagged: list[str] = []
    warnings: list[str] = []

    halved = f"{2e3 * piece:.3g} → {1e3 * piece:.3g} mm" + (
        "" if chord is None else f", chords {2e3 * chord:.3g} → {1e3 * chord:.3g} mm")

    def check(name: str, move: float) -> None:
        if abs(move) > tolerance:
            flagged.append(name)
            warnings.append(f"collide: {name} moves {100 * move:+.1f} % when the rope pieces at the fins are halved "
                            f"({halved}; > {100 * tolerance:g} %): not converged in "
                            f"the rope's resolution (collide.fin_piece_length, fin_piece_chord; docs/collide_convergence.md)")

    for key, out, name in HEADLINES:
        section[out] = _move(float(coarse[key]), float(fine[key]))
        check(name, section[out])
    imp_f, imp_c = fine["fin_impulse_ns"], coarse["fin_impulse_ns"]
    total = sum(imp_f.values())
    fins = {}
    for fin, value in imp_f.items():
        if total > 0.0 and value >= SHARE_MIN * total:
            fins[fin] = _move(float(imp_c.get(fin, 0.0)), float(value))
            check(f"{fin} impulse", fins[fin])
    section["fin_impulse_move_rel"] = fins
    section["flagged"] = flagged
    return section, warnings
