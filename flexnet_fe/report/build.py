"""``build_report(run_dir)``: one run directory → ``run_dir/report.html`` (DESIGN.md §3, item 5).

The report is built on the run-directory contract only (resolved.json, status.json,
summary.json, ``<stage>/`` files), never on a stage's internals:

- the case (name, description, stages, every resolved table, versions, case hash);
- the stage status table: a failed stage is shown failed with its error and the tail of its
  log; a stage is shown complete only when status.json says ``done`` AND summary.json has its
  section;
- headline numbers of each complete stage with units (from the key suffixes);
- the shell stress table per fin (peak von Mises [MPa], time, location in frame B, peak maximum
  principal stress, ratio to the fin material's yield strength from ``case.missile.material``);
- every PNG below each stage folder, referenced relatively;
- the peak von Mises history of each fin (from ``shell/<fin>/history.csv``) and a stress picture
  per fin rendered offscreen from ``shell/<fin>/envelope.xdmf`` (else ``fields.xdmf`` at the
  output time nearest the peak), written into ``run_dir/report_files/``.

Missing optional files are listed as notes, never filled in.
"""

from __future__ import annotations

import logging
import math
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from flexnet_fe.io import atomic_write_text, read_history_csv
from flexnet_fe.report.rundir import (RunData, StageInfo, fin_results, flatten, read_run, stage_pngs,
                                      yield_strength)
from flexnet_fe.report.units import PA_TO_MPA, format_value, unit_of

LOG = logging.getLogger("flexnet.report")

FILES_DIR = "report_files"
"""Folder of ``run_dir`` holding the pictures the report renders itself (rebuilt each time)."""

LOG_TAIL_LINES = 20
"""Lines of a failed stage's log.txt shown in the report."""

S_TO_MS = 1e3
"""s → ms (peak times are shown in ms)."""


@dataclass(frozen=True)
class Row:
    """One headline number: dotted key, value text, unit label."""

    key: str
    value: str
    unit: str


@dataclass(frozen=True)
class FinRow:
    """One fin of the shell stress table (display strings) and its picture."""

    name: str
    peak_vm_mpa: str
    peak_time_ms: str
    location_m: str
    max_principal_mpa: str
    yield_ratio: str
    other: tuple[Row, ...]
    picture: str | None
    picture_caption: str


def headline_rows(section: dict, skip: set[str] = frozenset()) -> list[Row]:
    """Rows of a summary section (nested dicts flattened to dotted keys), keys in ``skip`` left out."""
    rows = []
    for key, value in flatten({k: v for k, v in section.items() if k not in skip}).items():
        unit = unit_of(key)
        rows.append(Row(key, format_value(value, unit), unit.label))
    return rows


def _fin_row(name: str, res: dict, yield_pa: float | None, picture: str | None, caption: str) -> FinRow:
    contract = {"peak_von_mises_pa", "peak_time_s", "peak_location_m", "peak_max_principal_pa"}
    vm = res.get("peak_von_mises_pa")
    t = res.get("peak_time_s")
    loc = res.get("peak_location_m")
    p1 = res.get("peak_max_principal_pa")
    ratio = (f"{vm / yield_pa:.3g}" if isinstance(vm, (int, float)) and yield_pa else "—")
    return FinRow(
        name=name,
        peak_vm_mpa=format_value(vm * PA_TO_MPA) if isinstance(vm, (int, float)) else "—",
        peak_time_ms=format_value(t * S_TO_MS) if isinstance(t, (int, float)) else "—",
        location_m=format_value(loc) if loc is not None else "—",
        max_principal_mpa=format_value(p1 * PA_TO_MPA) if isinstance(p1, (int, float)) else "—",
        yield_ratio=ratio,
        other=tuple(headline_rows(res, skip=contract)),
        picture=picture, picture_caption=caption)


def _picture_job(run: RunData, fin: str, res: dict, out_dir: Path):
    """(StressJob or None, description of the field drawn / why there is no picture)."""
    from flexnet_fe.report.pictures import StressJob

    fin_dir = run.run_dir / "shell" / fin
    envelope, fields = fin_dir / "envelope.xdmf", fin_dir / "fields.xdmf"
    png = str(out_dir / f"shell_{fin}_von_mises.png")
    if envelope.is_file():
        return (StressJob(str(envelope), png, None, f"fin {fin}"),
                "peak over time of the cell von Mises stress (envelope.xdmf)")
    if fields.is_file():
        peak_t = res.get("peak_time_s")
        at = float(peak_t) if isinstance(peak_t, (int, float)) else None
        return (StressJob(str(fields), png, at, f"fin {fin}"),
                "von Mises stress at the field output time nearest the peak (fields.xdmf)")
    return None, "no envelope.xdmf or fields.xdmf for this fin"


def _picture_caption(run: RunData, fin: str, res: dict, what: str, pic, notes: list[str]) -> tuple[str | None, str]:
    """(relative png or None, caption) from a render result; checks the envelope maximum
    against the summary's peak (two records of the same number written by the shell stage)."""
    from flexnet_fe.report.pictures import Picture

    if not isinstance(pic, Picture):
        notes.append(f"stress picture of fin '{fin}': {pic}")
        return None, f"could not render: {pic}"
    when = "" if "envelope" in what else f", t = {pic.time_s * S_TO_MS:.4g} ms"
    caption = (f"{what}; field {pic.field}{when}; max in picture "
               f"{pic.max_pa * PA_TO_MPA:.4g} MPa. Undeformed mesh, body frame B [m], seen normal to the fin.")
    vm = res.get("peak_von_mises_pa")
    if "envelope" in what and isinstance(vm, (int, float)) and vm > 0 and not math.isclose(pic.max_pa, vm, rel_tol=1e-6):
        notes.append(f"fin '{fin}': envelope.xdmf maximum {pic.max_pa:.6g} Pa differs from summary.json "
                     f"peak_von_mises_pa {vm:.6g} Pa")
    return str(pic.png.relative_to(run.run_dir)), caption


def _shell_history_plot(run: RunData, fins: list[str], out_dir: Path, notes: list[str]) -> str | None:
    """Peak von Mises stress over the fin vs time for every fin with a history.csv; relative path."""
    curves = {}
    for fin in fins:
        path = run.run_dir / "shell" / fin / "history.csv"
        if not path.is_file():
            continue
        try:
            h = read_history_csv(path)
        except (OSError, ValueError) as err:
            notes.append(f"{path.relative_to(run.run_dir)}: unreadable ({err})")
            continue
        if "t_s" in h and "max_von_mises_pa" in h:
            curves[fin] = (h["t_s"], h["max_von_mises_pa"])
        else:
            notes.append(f"{path.relative_to(run.run_dir)}: no t_s / max_von_mises_pa columns")
    if not curves:
        return None
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    for fin, (t, vm) in curves.items():
        ax.plot(t * S_TO_MS, vm * PA_TO_MPA, label=fin)
    ax.set_xlabel("time t [ms]")
    ax.set_ylabel("max von Mises over the fin [MPa]")
    ax.set_title("Shell stage: peak von Mises stress per fin")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    path = out_dir / "shell_von_mises_history.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return str(path.relative_to(run.run_dir))


def _log_tail(stage: StageInfo) -> str | None:
    if stage.folder is None or not (stage.folder / "log.txt").is_file():
        return None
    lines = (stage.folder / "log.txt").read_text(errors="replace").splitlines()
    return "\n".join(lines[-LOG_TAIL_LINES:])


def _case_tables(case: dict) -> list[tuple[str, list[Row]]]:
    """Every table of the resolved case as rows (values as resolved, SI, no unit conversion)."""
    out = []
    for table, body in case.items():
        if table == "case" or not isinstance(body, dict):
            continue
        out.append((table, [Row(k, format_value(v), "") for k, v in flatten(body).items()]))
    return out


def _shell_view(run: RunData, stage: StageInfo, out_dir: Path, notes: list[str], view: dict) -> None:
    """Fin stress table (complete stage only), stress history plot and fin pictures (whenever
    the files exist; for a stage that is not complete they are labelled as such)."""
    from flexnet_fe.report.pictures import render_stress_isolated

    fins_summary = fin_results(stage.section) if stage.complete else {}
    fin_dirs = sorted(p.name for p in stage.folder.iterdir() if p.is_dir()) if stage.folder else []
    names = list(fins_summary) + [f for f in fin_dirs if f not in fins_summary]
    plot = _shell_history_plot(run, names, out_dir, notes) if stage.folder else None
    if plot:
        view["extra_plots"].append((plot, "Peak von Mises stress over each fin vs time "
                                          "(from shell/<fin>/history.csv)."))
    yield_pa, yield_what = yield_strength(run.case)
    view["yield_note"] = (f"yield strength {yield_pa * PA_TO_MPA:.4g} MPa ({yield_what}, "
                          "from resolved.json case.missile.material)" if yield_pa
                          else f"no ratio to yield: {yield_what}")
    planned = [_picture_job(run, fin, fins_summary.get(fin, {}), out_dir) for fin in names]
    rendered = iter(render_stress_isolated([job for job, _ in planned if job is not None]))
    for fin, (job, what) in zip(names, planned):
        res = fins_summary.get(fin, {})
        pic, caption = (_picture_caption(run, fin, res, what, next(rendered), notes) if job is not None
                        else (None, what))
        if fin in fins_summary:
            view["fins"].append(_fin_row(fin, res, yield_pa, pic, caption))
        elif pic:
            view["extra_plots"].append((pic, f"fin {fin} (no summary numbers: stage {stage.state}): {caption}"))


def _stage_view(run: RunData, stage: StageInfo, out_dir: Path, notes: list[str]) -> dict[str, Any]:
    view: dict[str, Any] = {"info": stage, "rows": [], "fins": [], "extra_plots": [],
                            "pngs": [str(p) for p in stage_pngs(run.run_dir, stage.folder)] if stage.folder else [],
                            "log": str((stage.folder / "log.txt").relative_to(run.run_dir))
                            if stage.folder and (stage.folder / "log.txt").is_file() else None,
                            "log_tail": _log_tail(stage) if stage.state == "failed" else None,
                            "yield_note": None,
                            # a stage the case does not ask for and that left nothing: status row only
                            "show": stage.requested is not False or stage.folder is not None
                            or stage.section is not None}
    if stage.name == "shell" and (stage.complete or stage.folder is not None):
        _shell_view(run, stage, out_dir, notes, view)
    if stage.complete:
        skip = set(fin_results(stage.section)) if stage.name == "shell" else set()
        view["rows"] = headline_rows(stage.section, skip)
    return view


def build_report(run_dir: Path) -> Path:
    """Write ``run_dir/report.html`` from the run directory's files; return its path.

    Raises :class:`FlexnetError` when ``run_dir`` is not a run directory. Pictures go to
    ``run_dir/report_files/`` (deleted and rebuilt on every call); all images are referenced
    relatively, so the report folder can be moved or archived whole.
    """
    from jinja2 import Environment, FileSystemLoader, StrictUndefined, select_autoescape

    run = read_run(Path(run_dir))
    out_dir = run.run_dir / FILES_DIR
    if out_dir.exists():
        shutil.rmtree(out_dir)
    out_dir.mkdir()
    notes = list(run.notes)
    stages = [_stage_view(run, s, out_dir, notes) for s in run.stages]
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
        stages=stages,
        notes=notes)
    path = run.run_dir / "report.html"
    atomic_write_text(path, html)
    LOG.info("report → %s", path)
    return path
