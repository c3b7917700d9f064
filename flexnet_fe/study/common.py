"""Shared pieces of the studies (issue 15): the study context, one measured point, relative
errors against the in-run reference, the Pareto front and the verdict on the shipped default.

A study row (dict) holds at least ``stage, knob, value, cpu_s, wall_s, is_default,
is_reference`` and one ``err_<quantity>`` per headline quantity: the relative error of the
point against the fine reference computed in the same run. ``cpu_s`` is the process CPU time
(all threads) [s] and ``wall_s`` the elapsed time [s] of the point's stage call alone.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from flexnet_fe.errors import CaseError, FlexnetError, NumericalError

LOG = logging.getLogger("flexnet.study")

HEADLINE_TOLERANCE = 0.02
"""The issue's bar: a default's headline numbers within 2 % of the converged (reference) value."""


@dataclass
class Context:
    """What every study gets: quick or full, a scratch folder, the notes it adds to the page."""

    quick: bool
    work: Path
    notes: dict[str, list[str]] = field(default_factory=dict)
    cache: dict[Any, Any] = field(default_factory=dict)

    def note(self, section: str, text: str) -> None:
        """Record one line for the page (and log it): a skipped knob, a missing feature, a scene."""
        LOG.info("study %s: %s", section, text)
        self.notes.setdefault(section, []).append(text)

    def scratch(self, name: str) -> Path:
        p = self.work / name
        p.mkdir(parents=True, exist_ok=True)
        return p


@dataclass(frozen=True)
class Point:
    """One variant of a stage: ``knob`` set to ``value`` through case overrides (``--set`` text).
    ``excluded``: why the point cannot be a default although the stage's headlines may favour it (a
    cost measured downstream, stated with its evidence); it is run, tabled and drawn, but not a
    candidate for the front (empty: a candidate)."""

    knob: str
    value: Any
    overrides: tuple[str, ...]
    is_default: bool = False
    is_reference: bool = False
    excluded: str = ""


def measured(fn: Callable[[], Any]) -> tuple[Any, float, float]:
    """(fn(), CPU seconds of this process incl. threads, wall seconds)."""
    c0, w0 = time.process_time(), time.perf_counter()
    out = fn()
    return out, time.process_time() - c0, time.perf_counter() - w0


def rel_error(value: Any, ref: Any) -> float:
    """Relative error of a scalar, |v − r| / |r|, or of a per-fin vector/dict:
    max_f |v_f − r_f| / max_f |r_f| (normalised by the largest reference entry, so that an
    unloaded fin does not divide by zero). NaN when either side is missing."""
    if value is None or ref is None:
        return math.nan
    if isinstance(ref, dict):
        keys = sorted(ref)
        ref = np.array([ref[k] for k in keys], dtype=float)
        value = np.array([value.get(k, 0.0) for k in keys], dtype=float)
    v, r = np.asarray(value, dtype=float), np.asarray(ref, dtype=float)
    scale = float(np.max(np.abs(r))) if r.size else 0.0
    if scale == 0.0:
        return 0.0 if float(np.max(np.abs(v), initial=0.0)) == 0.0 else math.inf
    return float(np.max(np.abs(v - r))) / scale


REPEATS = 3
"""Full study: a point cheaper than REPEAT_BELOW_S is timed REPEATS times and its smallest CPU
and wall times kept (the results are deterministic; on the shared machine a single timing of a
~1 s point varies by up to 2×, measured, which flips Pareto verdicts)."""
REPEAT_BELOW_S = 5.0


def run_points(stage: str, points: list[Point], runner: Callable[[Point], tuple[dict, dict]],
               ctx: Context, bar=None) -> list[dict]:
    """Run every point (reference first), then add ``err_<q>`` columns against the reference.

    ``runner(point) -> (quantities, extra)``: the headline quantities {name: float | dict} and
    extra columns (size, steps, warnings…); it is timed here, after one untimed warm-up run of
    the default point (so that no point pays the JIT compilation), cheap points of a full
    study :data:`REPEATS` times (smallest time kept). A point whose knob the case schema
    does not know is skipped with a note; a point the solver stops (NumericalError) becomes a
    row with ``status = 'stopped: …'`` and no errors. Rows come back in the order given."""
    ordered = sorted(points, key=lambda p: not p.is_reference)
    results: dict[Point, tuple] = {}
    default = next((p for p in points if p.is_default), None)
    if default is not None:  # warm-up (numba/ffcx JIT, imports, caches): not timed, not a row
        try:
            runner(default)
        except NumericalError:
            pass
    for p in ordered:
        try:
            (q, extra), cpu, wall = measured(lambda: runner(p))
            for _ in range(0 if ctx.quick or p.is_reference or cpu > REPEAT_BELOW_S else REPEATS - 1):
                _, c2, w2 = measured(lambda: runner(p))
                cpu, wall = min(cpu, c2), min(wall, w2)
            results[p] = (q, extra, cpu, wall, "ok")
        except CaseError as err:
            ctx.note(stage, f"{p.knob} = {p.value} skipped: {err}")
            if p.is_reference:
                raise FlexnetError(f"study {stage}: the reference point cannot run: {err}") from err
        except NumericalError as err:
            results[p] = ({}, {}, math.nan, math.nan, f"stopped: {str(err)[:160]}")
            if p.is_reference:
                raise FlexnetError(f"study {stage}: the reference point failed: {err}") from err
        if bar is not None:
            bar.update(1)
    ref = next(results[p][0] for p in ordered if p.is_reference)
    rows = []
    for p in points:
        if p not in results:
            continue
        q, extra, cpu, wall, status = results[p]
        row = {"stage": stage, "knob": p.knob, "value": p.value, "cpu_s": cpu, "wall_s": wall,
               "is_default": p.is_default, "is_reference": p.is_reference, "status": status,
               "excluded": p.excluded}
        for name in ref:
            row[f"err_{name}"] = rel_error(q.get(name), ref[name]) if q else math.nan
            v = q.get(name) if q else None
            row[name] = v if not isinstance(v, dict) else max(v.values(), default=0.0)
        row.update(extra)
        rows.append(row)
    return rows


def err_columns(rows: list[dict]) -> list[str]:
    return [k for k in rows[0] if k.startswith("err_")] if rows else []


def worst_error(row: dict) -> float:
    """The largest headline error of a row (NaN for a stopped point)."""
    errs = [row[k] for k in row if k.startswith("err_")]
    return max(errs) if errs and all(np.isfinite(errs)) else math.nan


ERR_RESOLUTION = 1e-4
"""Errors below 0.01 % are not told apart on the front (round-off of the headline values, the
quantised peak search): they count as equal."""

COST_NOISE = 0.15
"""CPU times within ±15 % are not told apart: the machine is shared and a point's time varies by
about that much between repeats under load."""


def pareto_mask(cost: np.ndarray, err: np.ndarray) -> np.ndarray:
    """True for points no other point dominates. j dominates i when j is clearly cheaper
    (cost_j < (1 − COST_NOISE) cost_i) and at least as accurate, or costs about the same
    (cost_j ≤ (1 + COST_NOISE) cost_i) and is clearly more accurate (error less than half),
    errors floored at ERR_RESOLUTION. NaN points are never on the front."""
    cost, err = np.asarray(cost, dtype=float), np.asarray(err, dtype=float)
    ok = np.isfinite(cost) & np.isfinite(err)
    e = np.maximum(err, ERR_RESOLUTION)
    on = np.zeros(len(cost), dtype=bool)
    for i in np.flatnonzero(ok):
        cheaper = ok & (cost < (1.0 - COST_NOISE) * cost[i]) & (e <= e[i])
        better = ok & (cost <= (1.0 + COST_NOISE) * cost[i]) & (e < 0.5 * e[i])
        on[i] = not (cheaper | better).any()
    return on


def candidate_front(rows: list[dict], cost: np.ndarray, err: np.ndarray) -> np.ndarray:
    """:func:`pareto_mask` over the candidate rows: an ``excluded`` row is never on the front."""
    candidate = np.array([not r.get("excluded") for r in rows], dtype=bool)
    return pareto_mask(cost, np.where(candidate, err, math.nan))


def verdict(rows: list[dict], tolerance: float = HEADLINE_TOLERANCE) -> dict:
    """Is the default on the Pareto front (CPU time vs worst headline error) of the candidate points
    (those not ``excluded``), and are all its headline errors within ``tolerance``? Also the cheapest
    candidate within tolerance."""
    cost = np.array([r["cpu_s"] for r in rows], dtype=float)
    err = np.array([worst_error(r) for r in rows], dtype=float)
    front = candidate_front(rows, cost, err)
    for r, f in zip(rows, front):
        r["on_front"] = bool(f)
    d = next((i for i, r in enumerate(rows) if r["is_default"]), None)
    if d is None:
        return {"default_on_front": None, "default_within": None, "default_worst_error": None,
                "cheapest_within": None}
    ok = [i for i, r in enumerate(rows) if not r.get("excluded") and np.isfinite(err[i]) and err[i] <= tolerance
          and not r["is_reference"]]
    cheapest = min(ok, key=lambda i: cost[i]) if ok else None
    return {"default_on_front": bool(front[d]), "default_within": bool(err[d] <= tolerance),
            "default_worst_error": float(err[d]), "tolerance": tolerance,
            "errors": {k: rows[d][k] for k in err_columns(rows)},
            "cheapest_within": (f"{rows[cheapest]['knob']} = {rows[cheapest]['value']}"
                                if cheapest is not None else None)}


def loglog_slope(size, cost) -> float | None:
    """Least-squares slope of log(cost) against log(size) (≥ 2 distinct sizes), else None."""
    s, c = np.asarray(size, dtype=float), np.asarray(cost, dtype=float)
    ok = np.isfinite(s) & np.isfinite(c) & (s > 0) & (c > 0)
    if len(np.unique(s[ok])) < 2:
        return None
    return float(np.polyfit(np.log(s[ok]), np.log(c[ok]), 1)[0])
