"""``build_sweep_report(table_csv)``: a sweep.csv / batch.csv (``flexnet_fe.sweep.run_many``) →
``<stem>_report.html`` next to it, with PNG plots in ``<stem>_report_files/``.

The table has one row per run: ``label``, the override columns (``net.rope_diameter`` ...),
the flattened summary keys (``shell.wing_1.peak_von_mises_pa`` ...) and ``error`` (empty when
the run succeeded). The swept parameters are the override columns: a column is one when its
dotted name is a field of the case schema (:class:`flexnet_fe.config.Case`) and it takes at
least two values; they may also be given explicitly. Each numeric output that varies is
plotted against each swept parameter (one line per combination of the other parameters);
with no swept parameter (a batch), against the run label. Failed runs are listed, not plotted.
"""

from __future__ import annotations

import csv
import shutil
import typing
from dataclasses import dataclass
from pathlib import Path

from flexnet_fe.errors import FlexnetError
from flexnet_fe.io import atomic_write_text
from flexnet_fe.report.units import unit_of

LABEL, ERROR = "label", "error"
"""The table's fixed columns (``flexnet_fe.sweep.run_many``)."""

BOOL_TEXT = {"True": 1.0, "False": 0.0, "true": 1.0, "false": 0.0}
"""How Python/JSON booleans appear in the CSV; plotted as 1 / 0."""


@dataclass(frozen=True)
class Column:
    """One output column: numeric values per row (``None``: empty or failed row)."""

    name: str
    values: tuple[float | None, ...]
    boolean: bool


def read_table(path: Path) -> tuple[list[str], list[dict[str, str]]]:
    """(column names, rows as {column: text}) of a CSV table with a header row."""
    path = Path(path)
    if not path.is_file():
        raise FlexnetError(f"{path}: no such table")
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        columns = list(reader.fieldnames or [])
        rows = [{c: (r.get(c) or "") for c in columns} | {ERROR: r.get(ERROR) or ""} for r in reader]
    if LABEL not in columns:
        raise FlexnetError(f"{path}: not a sweep/batch table (no '{LABEL}' column)")
    return columns, rows


def _unwrap_models(annotation) -> list:
    """The pydantic model classes inside an annotation (Optional, Union, Annotated unwrapped)."""
    from pydantic import BaseModel

    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [m for arg in typing.get_args(annotation) for m in _unwrap_models(arg)]


def case_field(key: str):
    """The pydantic FieldInfo of a dotted case-file path (``net.rope_diameter``), else None."""
    from flexnet_fe.config import Case

    models, info = [Case], None
    for part in key.split("."):
        hits = [m.model_fields[part] for m in models if part in m.model_fields]
        if not hits:
            return None
        info = hits[0]
        models = [m for h in hits for m in _unwrap_models(h.annotation)]
    return info


def parameter_label(key: str) -> str:
    """Axis label of a case field: its name and the ``[unit]`` from its schema description."""
    info = case_field(key)
    desc = (info.description or "") if info is not None else ""
    if "[" in desc and "]" in desc:
        return f"{key} {desc[desc.rindex('['):desc.rindex(']') + 1]}"
    return key


def _number(text: str) -> float | None:
    if text in BOOL_TEXT:
        return BOOL_TEXT[text]
    try:
        return float(text)
    except ValueError:
        return None


def numeric_outputs(columns: list[str], rows: list[dict[str, str]], skip: set[str]) -> list[Column]:
    """Output columns whose every non-empty value in successful rows is a number or a boolean."""
    ok = [not (r.get(ERROR) or "").strip() for r in rows]
    out = []
    for c in columns:
        if c in skip:
            continue
        texts = [(r.get(c) or "").strip() if good else "" for r, good in zip(rows, ok)]
        present = [t for t in texts if t]
        if not present or any(_number(t) is None for t in present):
            continue
        out.append(Column(c, tuple(_number(t) if t else None for t in texts),
                          boolean=all(t in BOOL_TEXT for t in present)))
    return out


def swept_parameters(columns: list[str], rows: list[dict[str, str]]) -> list[str]:
    """Columns that are case-schema fields and take at least two distinct values."""
    return [c for c in columns if c not in (LABEL, ERROR) and case_field(c) is not None
            and len({(r.get(c) or "").strip() for r in rows}) > 1]


def _plot(col: Column, param: str | None, others: list[str], rows: list[dict[str, str]], path: Path) -> int:
    """Plot ``col`` vs ``param`` (None: vs run label); returns the number of points drawn."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    unit = unit_of(col.name)
    xkey = param or LABEL
    xs_text = [(r.get(xkey) or "").strip() for r in rows]
    numeric_x = param is not None and all(_number(t) is not None for t in xs_text)
    categories = list(dict.fromkeys(xs_text))
    groups: dict[tuple, list[tuple[float, float]]] = {}
    for r, xt, y in zip(rows, xs_text, col.values):
        if y is None:
            continue
        x = _number(xt) if numeric_x else float(categories.index(xt))
        groups.setdefault(tuple((o, (r.get(o) or "").strip()) for o in others), []).append((x, y * unit.scale))
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    drawn = 0
    for key, pts in groups.items():
        pts.sort()
        xs, ys = zip(*pts)
        label = ", ".join(f"{o} = {v}" for o, v in key) or None
        if param is None:
            ax.bar(xs, ys)
        else:
            ax.plot(xs, ys, "o-", label=label)
        drawn += len(pts)
    if not numeric_x:
        ax.set_xticks(range(len(categories)), categories, rotation=30, ha="right")
    ax.set_xlabel(parameter_label(param) if param else "run")
    ax.set_ylabel(f"{col.name} [{unit.label}]" if unit.label else col.name)
    if col.boolean:
        ax.set_yticks([0, 1], ["false", "true"])
    if any(k for k in groups):
        ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return drawn


def _safe(name: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in name)


def build_sweep_report(table_csv: Path, parameters: list[str] | None = None) -> Path:
    """Write ``<stem>_report.html`` next to ``table_csv`` (and its plots); return its path.

    ``parameters``: the swept columns (default: inferred, see the module doc). A named
    parameter that is not a column is an error.
    """
    from jinja2 import Environment, FileSystemLoader, StrictUndefined, select_autoescape

    table_csv = Path(table_csv)
    columns, rows = read_table(table_csv)
    if parameters is None:
        params = swept_parameters(columns, rows)
    else:
        missing = [p for p in parameters if p not in columns]
        if missing:
            raise FlexnetError(f"{table_csv}: no column(s) {missing} to use as swept parameters")
        params = list(parameters)
    fixed = [c for c in columns if c not in params and c not in (LABEL, ERROR) and case_field(c) is not None]
    outputs = numeric_outputs(columns, rows, skip={LABEL, ERROR, *params, *fixed})
    varying = [c for c in outputs if len({v for v in c.values if v is not None}) > 1]
    constant = [c for c in outputs if c not in varying]

    files = table_csv.parent / f"{table_csv.stem}_report_files"
    if files.exists():
        shutil.rmtree(files)
    files.mkdir()
    plots = []
    for col in varying:
        for p in (params or [None]):
            path = files / _safe(f"{col.name}__vs__{p or LABEL}.png")
            n = _plot(col, p, [o for o in params if o != p], rows, path)
            plots.append((str(path.relative_to(table_csv.parent)),
                          f"{col.name} vs {p or 'run'} ({n} points)"))

    failed = [r for r in rows if (r.get(ERROR) or "").strip()]
    links = {}
    for r in rows:
        label = r.get(LABEL) or ""
        run = table_csv.parent / label
        if label and (run / "report.html").is_file():
            links[label] = f"{label}/report.html"
        elif label and run.is_dir():
            links[label] = f"{label}/"
    env = Environment(loader=FileSystemLoader(Path(__file__).parent / "templates"),
                      autoescape=select_autoescape(["html", "j2"]), undefined=StrictUndefined,
                      trim_blocks=True, lstrip_blocks=True)
    html = env.get_template("sweep.html.j2").render(
        table=table_csv.name, columns=columns, rows=rows, error_col=ERROR, label_col=LABEL,
        params=params, fixed=fixed, failed=failed, links=links, plots=plots,
        constant=[(c.name, next(r[c.name] for r in rows if r[c.name] and not r[ERROR])) for c in constant],
        fmt=_fmt_cell)
    out = table_csv.with_name(f"{table_csv.stem}_report.html")
    atomic_write_text(out, html)
    return out


def _fmt_cell(text: str) -> str:
    """A table cell: numbers to 6 significant digits (the CSV keeps them all), text as is."""
    if text in BOOL_TEXT or not text:
        return text
    try:
        return f"{float(text):.6g}"
    except ValueError:
        return text
