"""Ensembles: a case's headline numbers as statistics over where in a net cell the missile arrives.

Why. The fin peaks of one run are not a defined number: a rope strike's stress follows where
along the edge the rope lands and how much of the rope bundle arrives together, and both follow
millimetre-scale details of the scene (docs/validation.md, "Where the rope strikes": a 0.5–1 mm
move of the aim point moves a rudder peak by up to 11 %, the peaks spread ±20–27 % over seven runs
while the impulses agree within 1 %). No guidance places a missile to a millimetre within a 5 cm
net cell, so the number a structural engineer can use is a statistic over that placement: its
mean with the mean's standard error (which falls as 1/√n, so the statistic converges in the
number of members), its spread and its extremes, and the share of members in which a fin exceeds
its allowable or the missile still hits, with its 95 % interval.

What. ``n`` members of one case, identical but for ``collide.aim_point``: member 0 is the case as
given; member k is moved by the k-th point of the R2 low-discrepancy sequence (Roberts 2018:
fractional parts of 1/2 + k (1/g, 1/g²), g the plastic number, the real root of g³ = g + 1)
mapped onto one net cell of side ``cell`` (default ``[net].mesh_size``) centred on the case's aim
point — an even cover of every placement within a cell for any n. The members are a sweep
(``flexnet_fe.sweep.run_many``: resumable, ``-j`` processes or MPI); ``<out>/ensemble.csv`` holds
one row per member (its aim point and flattened summary), ``<out>/ensemble.json`` the statistics
of every headline (:data:`HEADLINES`, each fin's peak and governing stress, the case's largest),
``<out>/ensemble.png`` the members' fin stresses with their means and standard errors.

Run:

    flexnet ensemble cases/radar_traction --members 8 --set shell.peak_check=false --out runs/ens
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from flexnet_fe.errors import CaseError
from flexnet_fe.io import atomic_write_text
from flexnet_fe.runs import ENSEMBLE_STATS, ENSEMBLE_TABLE, FIN_PEAK, FIN_STRIKE_ENVELOPE
from flexnet_fe.sweep import ERROR, LABEL, Variant, run_many

PLASTIC = 1.324717957244746025960908854478
"""the plastic number, the real root of g³ = g + 1 (R2 sequence's generator)"""

AIM_X, AIM_Y = "aim_x_m", "aim_y_m"
"""member table columns: the member's aim point [m] (the case's ``collide.aim_point``)"""

HEADLINES = ("collide.dv_over_v", "collide.peak_accel_mps2", "collide.contact_duration_s",
             "flight.miss_distance_m")
"""whole-case headlines summarised when the members' summaries have them"""

OUTCOMES = ("flight.hit", "collide.passed_through")
"""yes/no headlines summarised as the share of members where they hold (:func:`proportion`)"""

Z95 = 1.959963984540054
"""the standard normal's two-sided 95 % quantile"""


_FIN_KEY = re.compile(r"^shell\.([^.]+)\." + re.escape(FIN_PEAK) + "$")


def cell_offsets(n: int, cell: float) -> np.ndarray:
    """Aim-point offsets [m] of ``n`` members over one square net cell of side ``cell`` [m],
    shape (n, 2): member k at ((frac(1/2 + k/g), frac(1/2 + k/g²)) − 1/2) · cell, so member 0 is
    the case's own point and every offset lies in [−cell/2, cell/2)²."""
    k = np.arange(n, dtype=float)[:, None]
    alpha = np.array([1.0 / PLASTIC, 1.0 / PLASTIC ** 2])
    return (np.mod(0.5 + k * alpha, 1.0) - 0.5) * cell


MEMBER_0 = "member_00"
"""the label of member 0, the case as given (:func:`members`)"""


def members(case_path: Path, base: list[str], aim: tuple[float, float], cell: float, n: int) -> list[Variant]:
    """The ensemble's runs: the case with ``base`` overrides and its aim point ``aim`` [m] moved
    by :func:`cell_offsets`; labels ``member_00`` … (their folders under the ensemble's out)."""
    out = []
    for k, (dx, dy) in enumerate(cell_offsets(n, cell)):
        x, y = aim[0] + float(dx), aim[1] + float(dy)
        out.append(Variant(f"member_{k:02d}", Path(case_path), (*base, f"collide.aim_point=[{x!r}, {y!r}]"),
                           ((AIM_X, repr(x)), (AIM_Y, repr(y)))))
    return out


def statistics(values, tolerance: float) -> dict[str, Any]:
    """Statistics of one headline over the members that have it (``values``, shape (n,)): n, mean,
    std (sample, n − 1), sem = std/√n, sem_rel = sem/|mean|, min, max, ``members_for_tolerance``
    = ⌈(std / (tolerance |mean|))²⌉ (the members that bring sem_rel to ``tolerance``) and
    ``converged`` = sem_rel ≤ tolerance. With n < 2 the spread is undefined (None, not converged);
    with a zero mean the relative figures are None and ``converged`` means every member agrees."""
    v = np.asarray(values, float)
    n = int(v.size)
    out: dict[str, Any] = {"n": n, "mean": float(v.mean()) if n else None,
                           "min": float(v.min()) if n else None, "max": float(v.max()) if n else None,
                           "std": None, "sem": None, "sem_rel": None, "members_for_tolerance": None,
                           "converged": False}
    if n < 2:
        return out
    std = float(v.std(ddof=1))
    sem = std / math.sqrt(n)
    mean = out["mean"]
    if mean == 0.0:  # no relative error to speak of: converged only if every member agrees
        out.update(std=std, sem=sem, converged=std == 0.0)
        return out
    rel = sem / abs(mean)
    need = math.ceil((std / (tolerance * abs(mean))) ** 2)
    out.update(std=std, sem=sem, sem_rel=rel, members_for_tolerance=need, converged=rel <= tolerance)
    return out


def proportion(k: int, n: int) -> dict[str, Any]:
    """A share of members, k of n, with its Wilson score 95 % interval (Wilson 1927; it stays in
    [0, 1] and is not empty at k = 0 or n, unlike the normal approximation):
    centre (p + z²/2n) / (1 + z²/n), half-width z √(p(1 − p)/n + z²/4n²) / (1 + z²/n)."""
    if n == 0:
        return {"k": 0, "n": 0, "share": None, "wilson95": None}
    p, z2 = k / n, Z95 ** 2
    centre = (p + z2 / (2 * n)) / (1 + z2 / n)
    half = Z95 * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / (1 + z2 / n)
    return {"k": k, "n": n, "share": p, "wilson95": [max(0.0, centre - half), min(1.0, centre + half)]}


def _yes(v) -> bool | None:
    """A yes/no cell (a bool, or its CSV text) → bool; None when empty."""
    if v in (None, ""):
        return None
    return v is True or str(v).strip().lower() in ("true", "1", "1.0")


def _exceed(rows: list[dict], fins: list[str]) -> dict[str, Any]:
    """Per fin (and ``any``), the share of members whose stress held to exceeds the fin's allowable
    (``shell.<fin>.allowable_pa``); fins without an allowable left out."""
    out, hits = {}, [False] * len(rows)
    for f in fins:
        pairs = [(governing(r, f), r.get(f"shell.{f}.allowable_pa")) for r in rows]
        over = [float(g) > float(a) if g not in (None, "") and a not in (None, "") else None for g, a in pairs]
        if all(o is None for o in over):
            continue
        out[f] = proportion(sum(bool(o) for o in over), sum(o is not None for o in over))
        hits = [h or bool(o) for h, o in zip(hits, over)]
    if out:
        out["any"] = proportion(sum(hits), len(rows))
    return out


def fin_names(rows: list[dict]) -> list[str]:
    """The fins with a peak in any member row (flattened ``shell.<fin>.peak_von_mises_pa``), in order."""
    names: dict[str, None] = {}
    for r in rows:
        for key in r:
            m = _FIN_KEY.match(key)
            if m and r[key] is not None:
                names[m.group(1)] = None
    return list(names)


def governing(row: dict, fin: str) -> float | None:
    """The stress [Pa] a fin is held to in a member row (``runs.governing_peak``, flattened)."""
    v = row.get(f"shell.{fin}.{FIN_STRIKE_ENVELOPE}")
    return v if v not in (None, "") else row.get(f"shell.{fin}.{FIN_PEAK}")


def largest_fin_stress(row: dict, fins: list[str]) -> float:
    """The case's largest fin stress [Pa] in a member row: the largest stress any of ``fins`` is
    held to (:func:`governing`); 0 when none has one."""
    return max((float(v) for v in (governing(row, f) for f in fins) if v not in (None, "")), default=0.0)


def summarise(rows: list[dict], tolerance: float) -> dict[str, Any]:
    """The ensemble's statistics from its member rows (failed members left out and counted):
    ``headlines`` (key → :func:`statistics`), ``fins`` (fin → {"peak": …, "governing": …}),
    ``largest`` (the case's largest fin stress [Pa] per member: over its fins, each held to its
    strike envelope where computed, else its peak), ``outcomes`` (:data:`OUTCOMES` → :func:`proportion`) and
    ``over_allowable`` (fin, and ``any``, → the share of members above the fin's allowable), with
    ``members``, ``failed`` and ``tolerance``. Values may be numbers or their CSV text."""
    ok = [r for r in rows if not r.get(ERROR)]

    def stat(vals):
        return statistics([float(v) for v in vals if v not in (None, "")], tolerance)

    fins = fin_names(ok)
    out = {"members": len(rows), "failed": [r[LABEL] for r in rows if r.get(ERROR)], "tolerance": tolerance,
           "headlines": {k: stat(r.get(k) for r in ok) for k in HEADLINES if any(k in r for r in ok)},
           "fins": {f: {"peak": stat(r.get(f"shell.{f}.{FIN_PEAK}") for r in ok),
                        "governing": stat(governing(r, f) for r in ok)} for f in fins}}
    out["outcomes"] = {k: proportion(sum(_yes(r.get(k)) is True for r in ok), sum(_yes(r.get(k)) is not None
                                                                                 for r in ok))
                       for k in OUTCOMES if any(_yes(r.get(k)) is not None for r in ok)}
    if fins:
        out["largest"] = stat(largest_fin_stress(r, fins) for r in ok)
        out["over_allowable"] = _exceed(ok, fins)
    return out


def plot(rows: list[dict], stats: dict, path: Path) -> Path:
    """Each fin's governing stress [MPa] in every member (dots; member 0, the case as given, a
    black ring), with the members' mean ± 2 standard errors (bar) and ± one standard deviation (box)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [r for r in rows if not r.get(ERROR)]
    fins = list(stats["fins"]) + (["largest"] if "largest" in stats else [])
    fig, ax = plt.subplots(figsize=(1.1 * len(fins) + 3.0, 4.6))
    for i, fin in enumerate(fins):
        s = stats["largest"] if fin == "largest" else stats["fins"][fin]["governing"]
        pairs = [(r[LABEL], largest_fin_stress(r, list(stats["fins"])) if fin == "largest" else governing(r, fin))
                 for r in ok]
        pairs = [(label, float(v)) for label, v in pairs if v not in (None, "")]
        xs = i + np.linspace(-0.18, 0.18, max(len(pairs), 1))[: len(pairs)]
        ax.plot(xs, [1e-6 * v for _, v in pairs], "o", color="C0", ms=4, alpha=0.8)
        given = [(x, v) for x, (label, v) in zip(xs, pairs) if label == MEMBER_0]
        if given:  # the case as given (member 0), when it ran
            ax.plot([given[0][0]], [1e-6 * given[0][1]], "o", mfc="none", mec="k", ms=9)
        if s.get("std") is not None:
            ax.add_patch(plt.Rectangle((i + 0.24, 1e-6 * (s["mean"] - s["std"])), 0.14, 2e-6 * s["std"],
                                       color="C1", alpha=0.3))
            ax.errorbar([i + 0.31], [1e-6 * s["mean"]], yerr=[2e-6 * s["sem"]], fmt="s", color="C3", capsize=4)
    ax.set_xticks(range(len(fins)), fins, rotation=30, ha="right")
    ax.set_ylabel("von Mises held to [MPa]")
    ax.grid(True, axis="y", alpha=0.4)
    ax.set_title(f"{len(ok)} members over one net cell: dots = members (ring: the case as given); "
                 "red = mean ± 2 s.e.; band = ± 1 s.d.", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def case_aim_and_cell(case, case_file: str, cell: float | None) -> tuple[tuple[float, float], float]:
    """The case's aim point [m] and the net cell [m] the members cover (``cell`` or ``[net].mesh_size``)."""
    if case.collide is None:
        raise CaseError(case_file, "collide", "an ensemble moves the collision's aim point: the case has no [collide]")
    if cell is None:
        if case.net is None:
            raise CaseError(case_file, "net.mesh_size", "no [net] table to take the cell from; give --cell")
        cell = float(case.net.mesh_size)
    if not cell > 0.0:
        raise CaseError(case_file, "--cell", f"must be > 0 m, got {cell}")
    return (float(case.collide.aim_point[0]), float(case.collide.aim_point[1])), cell


def run_ensemble(variants: list[Variant], out: Path, tolerance: float, jobs: int = 1, force: bool = False,
                 executor: str = "local") -> dict:
    """Run (or reuse) the members, write ensemble.csv, ensemble.json and ensemble.png into ``out``;
    returns the statistics (:func:`summarise`)."""
    out = Path(out)
    rows = run_many(variants, out, out / ENSEMBLE_TABLE, jobs=jobs, force=force, executor=executor)
    stats = summarise(rows, tolerance)
    atomic_write_text(out / ENSEMBLE_STATS, json.dumps(stats, indent=1) + "\n")
    if stats["fins"]:
        plot(rows, stats, (out / ENSEMBLE_TABLE).with_suffix(".png"))
    return stats


def describe(stats: dict) -> str:
    """The statistics as lines for the terminal: mean ± standard error (relative), spread, members needed."""
    def line(name, s, scale=1.0, unit=""):
        if s["n"] < 2:
            return f"  {name}: {s['n']} member(s), no spread"
        flag = "" if s["converged"] or s["sem_rel"] is None else \
            f"  (> {100 * stats['tolerance']:g} %: ~{s['members_for_tolerance']} members)"
        rel = "" if s["sem_rel"] is None else f" (s.e. {100 * s['sem_rel']:.2g} %)"
        return (f"  {name}: {s['mean'] * scale:.4g} ± {s['sem'] * scale:.2g}{unit}{rel}, "
                f"range {s['min'] * scale:.4g}–{s['max'] * scale:.4g}, s.d. {s['std'] * scale:.3g}{flag}")
    out = [line(k, s) for k, s in stats["headlines"].items()]
    out += [line(f"{f} (held to)", s["governing"], 1e-6, " MPa") for f, s in stats["fins"].items()]
    if "largest" in stats:
        out.append(line("largest fin stress", stats["largest"], 1e-6, " MPa"))
    shares = [(k, p) for k, p in stats.get("outcomes", {}).items()]
    shares += [(f"{f} above its allowable" if f != "any" else "any fin above its allowable", p)
               for f, p in stats.get("over_allowable", {}).items()]
    out += [f"  {name}: {p['k']}/{p['n']} members (95 % interval {100 * p['wilson95'][0]:.0f}–"
            f"{100 * p['wilson95'][1]:.0f} %)" for name, p in shares if p["n"]]
    return "\n".join(out)
