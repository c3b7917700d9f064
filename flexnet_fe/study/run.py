"""The driver of ``flexnet study STAGE|all [--quick] [--out DIR]``: runs the studies, writes per
study ``<name>.csv`` (the rows), ``<name>.json`` (rows, notes, verdict, machine and load) and its
PNG charts into ``out``, then rebuilds ``out/README.md`` from every ``<name>.json`` there (so a
study re-run alone updates its section and keeps the others)."""

from __future__ import annotations

import csv
import json
import logging
import math
import os
import platform
import shutil
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

from flexnet_fe import runs
from flexnet_fe.errors import CaseError
from flexnet_fe.progress import progress_bar
from flexnet_fe.study.common import Context, verdict

LOG = logging.getLogger("flexnet.study")

ACCURACY = ("deploy", "collide", "shell", "flight")
STUDIES = ACCURACY + ("stability", "simplify", "throughput")


def machine() -> dict:
    """CPU model, core count, load averages (1, 5, 15 min), date (UTC), versions."""
    import numpy

    model = platform.processor() or "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"cpu_model": model, "cores": os.cpu_count(), "loadavg": [round(x, 2) for x in os.getloadavg()],
            "date_utc": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "python": platform.python_version(), "numpy": numpy.__version__, "host": platform.node()}


def write_csv(path: Path, rows: list[dict]) -> None:
    keys: list[str] = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys)
        w.writeheader()
        for r in rows:
            w.writerow({k: json.dumps(v) if isinstance(v, (dict, list)) else v for k, v in r.items()})


def _load(out: Path, name: str) -> dict | None:
    p = out / f"{name}.json"
    return json.loads(p.read_text()) if p.is_file() else None


def _study(name: str, ctx: Context, out: Path, run_dir: Path | None) -> dict:
    m0 = machine()
    t0c, t0w = time.process_time(), time.perf_counter()
    rec: dict = {"name": name, "quick": ctx.quick, "machine_start": m0}
    with progress_bar(None, f"study {name}", unit="point") as bar:
        if name in ACCURACY:
            import importlib

            mod = importlib.import_module(f"flexnet_fe.study.{name}")
            rows = mod.rows(ctx, bar)
            rec["verdict"] = verdict(rows)
        elif name == "stability":
            from flexnet_fe.study import stability

            rows = stability.rows(ctx, bar)
        else:
            stage_rows = []
            for s in ACCURACY:
                d = _load(out, s)
                if d is not None:
                    stage_rows += d["rows"]
            notes: list[str] = []
            if name == "simplify":
                from flexnet_fe.study import simplify

                rows = simplify.rows(stage_rows, notes, ctx)
            else:
                from flexnet_fe.study import throughput

                rows = throughput.rows(ctx, stage_rows, run_dir)
            for n in notes:
                ctx.note(name, n)
    rec["rows"] = rows
    rec["notes"] = ctx.notes.get(name, [])
    rec["cpu_s"], rec["wall_s"] = time.process_time() - t0c, time.perf_counter() - t0w
    rec["machine_end"] = machine()
    write_csv(out / f"{name}.csv", rows)
    (out / f"{name}.json").write_text(json.dumps(rec, indent=1, default=str))
    LOG.info("study %s: %d rows, %.1f s wall, %.1f s CPU → %s", name, len(rows), rec["wall_s"], rec["cpu_s"],
             out / f"{name}.csv")
    return rec


def run_study(which: str, out: Path, quick: bool, run_dir: Path | None = None) -> Path:
    """Run study ``which`` (one of :data:`STUDIES` or ``all``) into ``out``; returns the page."""
    from flexnet_fe.study.page import write_page

    if which != "all" and which not in STUDIES:
        raise CaseError("flexnet study", "STAGE", f"unknown study '{which}'; choose from all, {', '.join(STUDIES)}")
    if run_dir is not None and not (Path(run_dir) / runs.STATUS).is_file():
        raise CaseError(str(run_dir), runs.STATUS, "--run-dir is not a run directory (no status.json)")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    names = STUDIES if which == "all" else (which,)
    work = Path(tempfile.mkdtemp(prefix="flexnet-study-"))
    try:
        ctx = Context(quick=quick, work=work)
        for name in names:
            _study(name, ctx, out, run_dir)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return write_page(out)


def finite(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
