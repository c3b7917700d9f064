"""``build_report(run_dir)``: one run directory → ``run_dir/report.html`` (DESIGN.md §3, issue 12).

The report is built on the run-directory contract only (resolved.json, status.json,
summary.json, ``<stage>/`` files), never on a stage's internals. From the top:

1. **Warnings** (red box): every warning any stage logged (:mod:`.verdict`).
2. **Verdict**: PASS / FAIL / UNDECIDED / INCOMPLETE; per fin peak von Mises and max principal with time,
   location, error estimate, allowable (and its source), margin of safety and PASS/FAIL; the
   missile's Δv, peak acceleration (filtered or not, said), pass-through; the flight outcome.
3. **Pictures**: the whole missile's stress (envelope and at the largest peak), the net at
   first contact / mid-passage / exit, the collision animation (GIF), the ParaView files.
4. Notes (what was missing or inconsistent), the stage status table, the energy report.
5. One section per stage: headline numbers with units (:mod:`.units`), stress histories with
   the allowable drawn, per-fin pictures with the peak marked, the stage's own PNGs.
6. The resolved case.

Pictures go to ``run_dir/report_files/`` (rebuilt on every call), rendered in one child
process (:func:`flexnet_fe.report.pictures.render_isolated`). Missing optional files are
listed as notes, never filled in.
"""

from __future__ import annotations

import logging
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from flexnet_fe.io import atomic_write_text
from flexnet_fe.report.figures import Figure
from flexnet_fe.report.rundir import RunData, StageInfo, fin_results, flatten, read_run, stage_pngs
from flexnet_fe.report.units import (PA_TO_MPA, S_TO_MS, format_value, unit_label, unit_of,
                                     unknown_units)
from flexnet_fe.report.verdict import Verdict, build_verdict
from flexnet_fe.runs import REPORT, STAGE_LOG

LOG = logging.getLogger("flexnet.report")

FILES_DIR = "report_files"
"""Folder of ``run_dir`` holding what the report renders itself (rebuilt each time)."""

LOG_TAIL_LINES = 20
"""Lines of a failed stage's log.txt shown in the report."""


@dataclass(frozen=True)
class Row:
    """One headline number: dotted key, value text, unit label."""

    key: str
    value: str
    unit: str


def headline_rows(section: dict, skip: set[str] = frozenset()) -> list[Row]:
    """Rows of a summary section (nested dicts flattened to dotted keys), keys in ``skip`` and
    ``warnings`` lists (shown in the red box) left out."""
    rows = []
    for key, value in flatten({k: v for k, v in section.items() if k not in skip}).items():
        if key.rsplit(".", 1)[-1] == "warnings":
            continue
        unit = unit_of(key)
        rows.append(Row(key, format_value(value, unit), unit_label(key, value)))
    return rows


def _log_tail(stage: StageInfo) -> str | None:
    if stage.folder is None or not (stage.folder / STAGE_LOG).is_file():
        return None
    lines = (stage.folder / STAGE_LOG).read_text(errors="replace").splitlines()
    return "\n".join(lines[-LOG_TAIL_LINES:])


def _case_tables(case: dict) -> list[tuple[str, list[Row]]]:
    """Every table of the resolved case as rows (values as resolved, SI, no unit conversion),
    each with the unit its schema description gives (``[m]`` ...; '' when it names none)."""
    from flexnet_fe.report.sweep import parameter_unit

    out = []
    for table, body in case.items():
        if table == "case" or not isinstance(body, dict):
            continue
        out.append((table, [Row(k, format_value(v), parameter_unit(f"{table}.{k}") if v is not None
                                and not isinstance(v, (bool, str)) else "")
                            for k, v in flatten(body).items()]))
    return out


def _stage_view(run: RunData, stage: StageInfo) -> dict[str, Any]:
    skip = set(fin_results(stage.section)) if stage.name == "shell" and stage.complete else set()
    return {"info": stage, "rows": headline_rows(stage.section, skip) if stage.complete else [],
            "figures": [], "pictures": [],
            "pngs": [str(p) for p in stage_pngs(run.run_dir, stage.folder)] if stage.folder else [],
            "log": str((stage.folder / STAGE_LOG).relative_to(run.run_dir))
            if stage.folder and (stage.folder / STAGE_LOG).is_file() else None,
            "log_tail": _log_tail(stage) if stage.state == "failed" else None,
            # a stage the case does not ask for and that left nothing: status row only
            "show": stage.requested is not False or stage.folder is not None or stage.section is not None}


def _unit_notes(run: RunData, notes: list[str]) -> None:
    for s in run.stages:
        if s.complete:
            missing = [k for k in unknown_units(flatten(s.section)) if k.rsplit(".", 1)[-1] != "warnings"]
            if missing:
                notes.append(f"summary.json {s.name}: no unit known for " + ", ".join(missing)
                             + " (shown with '?'; add it to flexnet_fe/report/units.py)")


def build_report(run_dir: Path, *, pictures: bool = True) -> Path:
    """Write ``run_dir/report.html`` from the run directory's files; return its path.
    ``pictures=False`` leaves out the 3-D pictures (offscreen VTK in a child process, the
    slow part); the plots, tables, energy report and ParaView files are still written.

    Raises :class:`FlexnetError` when ``run_dir`` is not a run directory. Pictures go to
    ``run_dir/report_files/`` (deleted and rebuilt on every call); all images are referenced
    relatively, so the report folder can be moved or archived whole.
    """
    from jinja2 import Environment, FileSystemLoader, StrictUndefined, select_autoescape

    from flexnet_fe.report.energy import energy_report
    from flexnet_fe.report.figures import assemble_figures

    run = read_run(Path(run_dir))
    out_dir = run.run_dir / FILES_DIR
    if out_dir.exists():
        shutil.rmtree(out_dir)
    out_dir.mkdir()
    notes = list(run.notes)
    verdict: Verdict = build_verdict(run)
    stages = [_stage_view(run, s) for s in run.stages]
    _unit_notes(run, notes)
    energy = energy_report(run.run_dir, [s.name for s in run.stages], out_dir, notes)
    warnings = list(verdict.warnings) + _energy_warnings(run, energy)
    top = assemble_figures(run, verdict, stages, out_dir, notes, pictures)
    meta = run.case.get("case", {}) or {}
    env = Environment(loader=FileSystemLoader(Path(__file__).parent / "templates"),
                      autoescape=select_autoescape(["html", "j2"]), undefined=StrictUndefined,
                      trim_blocks=True, lstrip_blocks=True)
    html = env.get_template("report.html.j2").render(
        name=meta.get("name") or (run.status or {}).get("case") or run.run_dir.name,
        description=meta.get("description", ""),
        requested=meta.get("stages") or [],
        case_tables=_case_tables(run.case),
        resolved=run.resolved or {},
        run_dir=str(run.run_dir),
        verdict=verdict, warnings=warnings, top=top, energy=energy,
        stages=stages, notes=notes, fmt=format_value, mpa=PA_TO_MPA, ms=S_TO_MS)
    path = run.run_dir / REPORT
    atomic_write_text(path, html)
    LOG.info("report → %s", path)
    return path


def _energy_warnings(run: RunData, energy) -> list:
    """A balance over tolerance in a history whose stage summary gives no energy_error_rel of
    its own (the summary's own value is checked by the verdict)."""
    from flexnet_fe.report.verdict import ENERGY_TOL_REL, Warning_

    out = []
    for fig in energy:
        stage = fig.label.split("/")[0]
        part = fig.label.split("/")[1] if "/" in fig.label else None
        section = (run.summary or {}).get(stage) or {}
        own = (section.get(part) or {}) if part else section
        if isinstance(own, dict) and "energy_error_rel" in own:
            continue
        if fig.max_error_rel > ENERGY_TOL_REL:
            src = ("computed by the report from the _j columns (a term the stage does not write, e.g. "
                   "damping, counts as error)" if fig.balance_from == "report" else f"stage column {fig.balance_from}")
            out.append(Warning_(stage, f"{fig.label}: energy balance error up to {fig.max_error_rel:.3g} of the "
                                       f"energy scale > {ENERGY_TOL_REL:.3g} ({src})"))
    return out
