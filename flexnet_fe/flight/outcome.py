"""The outcome of one engagement, read from a run's ``summary.json``: did the missile still hit,
by how much did it miss, and which fin came closest to failing.

The fin margin is MS = σ_allow / σ_peak − 1 [–] (negative: the fin's peak von Mises stress exceeds
its allowable). The allowable is the shell summary's ``allowable_pa`` (the fin material's yield
strength, its one home ``[missile.material]``), else — for a shell stage that did not write it —
the one the flight's damage law used (``flight.damage_from_shell.allowable_pa``).
Used by the engagement map (``flexnet_fe.engagement_map``), which runs the cases.
"""

from __future__ import annotations

from flexnet_fe.runs import governing_peak


def fin_margins(summary: dict) -> dict[str, float]:
    """Per fin MS = allowable / peak von Mises − 1 [–], for the fins with both numbers (the peak:
    the strike envelope where the shell stage computed one, ``runs.governing_peak``)."""
    fl, sh = summary.get("flight", {}), summary.get("shell", {})
    used = fl.get("damage_from_shell", {}).get("allowable_pa", {})
    return {k: (v.get("allowable_pa") or used[k]) / governing_peak(v) - 1.0 for k, v in sh.items()
            if isinstance(v, dict) and governing_peak(v) and (v.get("allowable_pa") or k in used)}


def outcome(summary: dict) -> dict:
    """One engagement's outcome from its ``summary.json``: ``miss_distance_m`` [m], ``hit``,
    ``min_fin_margin`` [–] and ``critical_fin`` (the fin with the smallest margin; "" and None
    without a shell result), ``wing_damage`` [–] and ``rudder_effectiveness`` [–] flown."""
    fl = summary.get("flight", {})
    margins = fin_margins(summary)
    crit = min(margins, key=margins.get) if margins else ""
    return {"miss_distance_m": fl.get("miss_distance_m"), "hit": fl.get("hit"),
            "min_fin_margin": margins.get(crit) if crit else None, "critical_fin": crit,
            "wing_damage": fl.get("wing_damage"), "rudder_effectiveness": fl.get("rudder_effectiveness")}
