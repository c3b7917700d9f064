"""Batches and sweeps: many runs, one table.

A sweep is a cartesian product of ``--set``-style overrides of one base case; each point runs
into its own run directory ``<out>/<label>/`` and the headline numbers of every point are
gathered into ``<out>/sweep.csv`` (one row per point; failures are rows with their error).
"""

from __future__ import annotations

import csv
import itertools
import logging
from pathlib import Path
from typing import Any

from flexnet_fe.config import load_case
from flexnet_fe.errors import CaseError, FlexnetError
from flexnet_fe.progress import progress_bar

LOG = logging.getLogger("flexnet")


def parse_axis(text: str) -> tuple[str, list[str]]:
    """``net.rope_diameter=2e-3,3e-3`` → ("net.rope_diameter", ["2e-3", "3e-3"])."""
    if "=" not in text:
        raise CaseError("--vary", text, "expected key=v1,v2,...")
    key, values = text.split("=", 1)
    vals = [v.strip() for v in values.split(",") if v.strip()]
    if not vals:
        raise CaseError("--vary", key, "no values")
    return key.strip(), vals


def sweep_points(axes: list[tuple[str, list[str]]]) -> list[list[str]]:
    """Cartesian product of the axes as lists of ``key=value`` overrides."""
    return [[f"{k}={v}" for (k, _), v in zip(axes, combo)]
            for combo in itertools.product(*[vals for _, vals in axes])]


def flatten(summary: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested summary → {"deploy.max_area_m2": ..., ...} (scalars only)."""
    out: dict[str, Any] = {}
    for k, v in summary.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(flatten(v, key + "."))
        elif isinstance(v, (int, float, str, bool)) or v is None:
            out[key] = v
    return out


def run_many(jobs: list[tuple[str, Path, list[str]]], out: Path, table: Path) -> list[dict[str, Any]]:
    """Run each (label, case path, overrides) into ``out/label`` and write ``table`` (CSV).

    A failing point does not stop the others; its row carries ``error``.
    """
    from flexnet_fe.pipeline import run_case

    rows = []
    with progress_bar(len(jobs), "runs", unit="run") as bar:
        for label, case_path, overrides in jobs:
            row: dict[str, Any] = {"label": label, **dict(o.split("=", 1) for o in overrides)}
            try:
                case, case_dir = load_case(case_path, overrides)
                row.update(flatten(run_case(case, case_dir, out / label)))
                row["error"] = ""
            except (FlexnetError, ArithmeticError, ValueError, RuntimeError) as err:
                LOG.error("%s: %s", label, err)
                row["error"] = str(err)
            rows.append(row)
            bar.update(1)
    columns = list(dict.fromkeys(k for r in rows for k in r))
    table.parent.mkdir(parents=True, exist_ok=True)
    with open(table, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns)
        w.writeheader()
        w.writerows(rows)
    return rows
