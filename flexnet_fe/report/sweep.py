"""``build_sweep_report(table_csv)``: a sweep.csv / batch.csv (``flexnet_fe.sweep.run_many``) →
``<stem>_report.html`` next to it, with PNG plots in ``<stem>_report_files/``.

The table has one row per run: ``label``, the override columns (``net.rope_diameter`` ...),
the flattened summary keys (``shell.wing_1.peak_von_mises_pa`` ...) and ``error`` (empty when
the run succeeded). ``run_many`` writes the override columns first, right after ``label``: the
overrides are the leading columns that are fields of the case schema (a summary key that
happens to share a schema name, like the flight stage's own ``flight.sweep.parameter``, comes
later and is not one). The swept parameters are the overrides that take at least two values
(or the ones given); overrides with one value are listed as fixed, ``name = value``.

Only the headline quantities (:data:`HEADLINES`) are plotted, one panel each against each swept
parameter (one line per combination of the other parameters), units on both axes; every other
column stays in the full table. With no swept parameter (a batch of unrelated cases) nothing is
plotted: the report is a comparison table, one row per case. Failed runs are listed, never
plotted.
"""

from __future__ import annotations

import csv
import json
import math
import re
import shutil
import typing
from dataclasses import dataclass
from pathlib import Path

from flexnet_fe.errors import FlexnetError
from flexnet_fe.io import atomic_write_text
from flexnet_fe.report.units import unit_of
from flexnet_fe.runs import ENSEMBLE_STATS, ENSEMBLE_TABLE, REPORT

LABEL, ERROR = "label", "error"
"""The table's fixed columns (``flexnet_fe.sweep.run_many``)."""

BOOL_TEXT = {"True": 1.0, "False": 0.0, "true": 1.0, "false": 0.0}
"""How Python/JSON booleans appear in the CSV; plotted as 1 / 0."""

MAX_FIN_VM = "shell.max_fin_peak_von_mises_pa"
"""Computed column: the largest fin peak von Mises stress of a run [Pa]."""

FIN_VM = re.compile(r"shell\.[^.]+\.peak_von_mises_pa")

BOOLEAN_HEADLINES = frozenset({"collide.passed_through", "flight.hit"})


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


def parameter_unit(key: str) -> str:
    """The SI unit of a case field, from the ``[unit]`` of its schema description ('' if none)."""
    info = case_field(key)
    desc = (info.description or "") if info is not None else ""
    if "[" in desc and "]" in desc:
        return desc[desc.rindex("[") + 1:desc.rindex("]")]
    return ""


def parameter_label(key: str, unit: str | None = None) -> str:
    """Axis label of a case field: its name and its unit (``unit``, else the schema's)."""
    u = parameter_unit(key) if unit is None else unit
    return f"{key} [{u}]" if u else key


def parameter_axis(key: str, peak_abs: float):
    """Display unit of a swept parameter's axis: the schema's SI unit with an SI prefix that
    fits ``peak_abs`` (a rope diameter of 0.004 m is drawn in mm)."""
    from flexnet_fe.report.units import PREFIXABLE, PREFIXES, Unit

    base = parameter_unit(key)
    if base not in PREFIXABLE or not peak_abs > 0 or not math.isfinite(peak_abs):
        return Unit(base)
    for factor, prefix in reversed(PREFIXES):
        if peak_abs >= factor:
            return Unit(prefix + base, 1.0 / factor)
    return Unit("n" + base, 1e9)


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


HEADLINES: tuple[tuple[str, str], ...] = (
    ("deploy.max_area_m2", "largest net area"),
    ("deploy.time_to_max_area_s", "time to the largest area"),
    ("collide.delta_v_mps", "Δv of the missile"),
    ("collide.dv_over_v", "|Δv| / v of the missile"),
    ("collide.peak_accel_mps2", "peak CG acceleration"),
    ("collide.max_attitude_change_rad", "attitude change"),
    ("collide.passed_through", "net passed through"),
    (MAX_FIN_VM, "largest fin peak von Mises"),
    ("flight.wing_damage", "wing damage used by the flight"),
    ("flight.miss_distance_m", "miss distance"),
    ("flight.hit", "missile hits the aircraft"),
)
"""Headline columns (in panel order) and their titles. ``MAX_FIN_VM`` is computed per row as
the largest ``shell.<fin>.peak_von_mises_pa`` of the row (fins differ between cases)."""


def override_columns(columns: list[str]) -> list[str]:
    """The leading columns after ``label`` that are case-schema fields (see the module doc)."""
    out = []
    for c in columns[1:] if columns and columns[0] == LABEL else columns:
        if c == ERROR or case_field(c) is None:
            break
        out.append(c)
    return out


def swept_parameters(columns: list[str], rows: list[dict[str, str]]) -> list[str]:
    """Override columns that take at least two distinct values."""
    return [c for c in override_columns(columns) if len({(r.get(c) or "").strip() for r in rows}) > 1]


def with_headlines(columns: list[str], rows: list[dict[str, str]]) -> tuple[list[str], list[dict[str, str]]]:
    """Add the computed ``MAX_FIN_VM`` column (largest fin peak von Mises of each row [Pa])."""
    fins = [c for c in columns if FIN_VM.fullmatch(c)]
    if not fins:
        return columns, rows
    out = []
    for r in rows:
        vals = [_number(r.get(c) or "") for c in fins]
        vals = [v for v in vals if v is not None]
        out.append(r | {MAX_FIN_VM: repr(max(vals)) if vals else ""})
    return columns + [MAX_FIN_VM], out


def headline_columns(columns: list[str]) -> list[tuple[str, str]]:
    """(column, title) of the headlines present; Δv/v only when Δv itself is absent."""
    present = [(c, t) for c, t in HEADLINES if c in columns]
    if "collide.delta_v_mps" in columns:
        present = [(c, t) for c, t in present if c != "collide.dv_over_v"]
    return present


def _series(col: Column, param: str, others: list[str], rows: list[dict[str, str]]):
    """{combination of the other parameters: sorted [(x, y)]}, x numeric or a category index."""
    xs_text = [(r.get(param) or "").strip() for r in rows]
    numeric_x = all(_number(t) is not None for t in xs_text)
    categories = list(dict.fromkeys(xs_text))
    groups: dict[tuple, list[tuple[float, float]]] = {}
    for r, xt, y in zip(rows, xs_text, col.values):
        if y is None:
            continue
        x = _number(xt) if numeric_x else float(categories.index(xt))
        groups.setdefault(tuple((o, (r.get(o) or "").strip()) for o in others), []).append((x, y))
    return {k: sorted(v) for k, v in groups.items()}, numeric_x, categories


def _plot_parameter(cols: list[tuple[Column, str]], param: str, others: list[str],
                    rows: list[dict[str, str]], path: Path) -> dict[str, int]:
    """One figure, one panel per headline column against ``param``; returns points per column."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from flexnet_fe.report.units import axis_unit, plain_log_axis

    n = len(cols)
    ncol = min(3, n)
    nrow = math.ceil(n / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.6 * ncol, 3.4 * nrow), squeeze=False)
    drawn = {}
    from matplotlib.ticker import MaxNLocator

    for ax, (col, title) in zip(axes.ravel(), cols):
        groups, numeric_x, categories = _series(col, param, others, rows)
        peak = max((abs(y) for pts in groups.values() for _, y in pts), default=0.0)
        unit = axis_unit(col.name, peak) if not col.boolean else None
        xu = parameter_axis(param, max((abs(x) for pts in groups.values() for x, _ in pts), default=0.0)) \
            if numeric_x else None
        for key, pts in groups.items():
            xs, ys = zip(*pts)
            xs = [x * xu.scale for x in xs] if xu else xs
            ys = [y * (unit.scale if unit else 1.0) for y in ys]
            ax.plot(xs, ys, "o-", label=", ".join(f"{o} = {v}" for o, v in key) or None)
        drawn[col.name] = sum(len(p) for p in groups.values())
        xs_all = [x * (xu.scale if xu else 1.0) for pts in groups.values() for x, _ in pts]
        if numeric_x and xs_all and min(xs_all) > 0 and max(xs_all) / min(xs_all) > 100:
            ax.set_xscale("log")
            plain_log_axis(ax.xaxis)
        if not numeric_x:
            ax.set_xticks(range(len(categories)), categories, rotation=30, ha="right")
        elif ax.get_xscale() == "linear":
            ax.xaxis.set_major_locator(MaxNLocator(5))
        ax.set_xlabel(parameter_label(param, xu.label if xu else None), fontsize=8)
        ax.set_ylabel(title if col.boolean else f"{title} [{unit.label}]", fontsize=8)
        ax.set_title(col.name, fontsize=8)
        if col.boolean:
            ax.set_yticks([0, 1], ["no", "yes"])
            ax.set_ylim(-0.2, 1.2)
        if any(k for k in groups):
            ax.legend(fontsize=6)
        ax.grid(True, alpha=0.3)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return drawn


def _safe(name: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in name)


def _comparison(rows: list[dict[str, str]], heads: list[tuple[str, str]]) -> tuple[list[str], list[list[str]]]:
    """Header (title [unit]) and one row per run: label, status, each headline in its unit."""
    from flexnet_fe.report.units import unit_of

    header = ["case", "status"] + [f"{t} [{unit_of(c).label}]" if c not in BOOLEAN_HEADLINES else t
                                   for c, t in heads]
    body = []
    for r in rows:
        cells = [r.get(LABEL) or "", "failed" if (r.get(ERROR) or "").strip() else "ok"]
        for c, _ in heads:
            text = (r.get(c) or "").strip()
            v = _number(text)
            if not text:
                cells.append("—")
            elif c in BOOLEAN_HEADLINES or text in BOOL_TEXT:
                cells.append("yes" if v else "no")
            elif v is None:
                cells.append(text)
            else:
                cells.append(f"{v * unit_of(c).scale:.4g}")
        body.append(cells)
    return header, body


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
    fixed = [(c, rows[0].get(c, "")) for c in override_columns(columns) if c not in params and rows]
    all_columns, all_rows = with_headlines(columns, rows)
    heads = headline_columns(all_columns)
    outputs = {c.name: c for c in numeric_outputs(all_columns, all_rows, skip={LABEL, ERROR, *params})}
    plotted = [(outputs[c], t) for c, t in heads if c in outputs]

    files = table_csv.parent / f"{table_csv.stem}_report_files"
    if files.exists():
        shutil.rmtree(files)
    files.mkdir()
    plots, points = [], {}
    for p in params:
        if not plotted:
            break
        path = files / _safe(f"headlines__vs__{p}.png")
        points = _plot_parameter(plotted, p, [o for o in params if o != p], all_rows, path)
        plots.append((str(path.relative_to(table_csv.parent)),
                      f"Headline quantities vs {parameter_label(p)}; points per panel: "
                      + ", ".join(f"{k} {v}" for k, v in points.items())))

    own = table_csv.with_suffix(".png")  # a picture the sweep driver drew itself (map.csv → map.png)
    if own.is_file():
        plots.insert(0, (own.name, f"{own.name}: the sweep's own picture, drawn by the tool that wrote "
                                   f"{table_csv.name}"))

    failed = [r for r in rows if (r.get(ERROR) or "").strip()]
    links = {}
    for r in rows:
        label = r.get(LABEL) or ""
        run = table_csv.parent / label
        if label and (run / REPORT).is_file():
            links[label] = f"{label}/report.html"
        elif label and run.is_dir():
            links[label] = f"{label}/"
    comp_header, comp_rows = _comparison(all_rows, heads)
    ens_header, ens_rows, ens_shares = ensemble_statistics(table_csv)
    env = Environment(loader=FileSystemLoader(Path(__file__).parent / "templates"),
                      autoescape=select_autoescape(["html", "j2"]), undefined=StrictUndefined,
                      trim_blocks=True, lstrip_blocks=True)
    html = env.get_template("sweep.html.j2").render(
        table=table_csv.name, columns=columns, rows=rows, error_col=ERROR, label_col=LABEL,
        params=params, fixed=fixed, failed=failed, links=links, plots=plots,
        plotted=[(c.name, t) for c, t in plotted] if params else [],
        comp_header=comp_header, comp_rows=comp_rows, ens_header=ens_header, ens_rows=ens_rows,
        ens_shares=ens_shares, fmt=_fmt_cell)
    out = table_csv.with_name(f"{table_csv.stem}_report.html")
    atomic_write_text(out, html)
    return out


def ensemble_statistics(table_csv: Path) -> tuple[list[str], list[list[str]], list[list[str]]]:
    """(header, rows, shares) of an ensemble's statistics from the ``ensemble.json`` beside its
    ``ensemble.csv`` (``flexnet_fe.ensemble.summarise``); ([], [], []) for any other table. One row
    per headline and per fin (the stress it is held to): members, mean, standard error (and its
    share of the mean), standard deviation, range, the members the tolerance needs; ``shares``:
    (what, members, share, Wilson 95 % interval) for the yes/no outcomes and each fin above its
    allowable."""
    path = Path(table_csv).with_name(ENSEMBLE_STATS)
    if Path(table_csv).name != ENSEMBLE_TABLE or not path.is_file():
        return [], [], []
    st = json.loads(path.read_text())
    items = list(st["headlines"].items())
    items += [(f"shell.{f}.held_to_pa", s["governing"]) for f, s in st["fins"].items()]
    if "largest" in st:
        items.append(("shell.largest_fin_stress_pa", st["largest"]))
    header = ["quantity", "members", "mean", "standard error", "s.e. / mean", "standard deviation", "min", "max",
              f"members for s.e. ≤ {100 * st['tolerance']:g} %"]
    rows = []
    for key, s in items:
        u = unit_of(key)

        def num(v):
            return "" if v is None else f"{v * u.scale:.4g}"
        rows.append([f"{key} [{u.label}]" if u.label else key, str(s["n"]), num(s["mean"]), num(s["sem"]),
                     "" if s["sem_rel"] is None else f"{100 * s['sem_rel']:.2g} %", num(s["std"]), num(s["min"]),
                     num(s["max"]), "" if s["members_for_tolerance"] is None else str(s["members_for_tolerance"])])
    named = list(st.get("outcomes", {}).items())
    named += [(f"{f} above its allowable" if f != "any" else "any fin above its allowable", p)
              for f, p in st.get("over_allowable", {}).items()]
    shares = [[name, f"{p['k']} of {p['n']}", f"{100 * p['share']:.0f} %",
               f"{100 * p['wilson95'][0]:.0f}–{100 * p['wilson95'][1]:.0f} %"] for name, p in named if p["n"]]
    return header, rows, shares


def _fmt_cell(text: str) -> str:
    """A table cell: numbers to 6 significant digits (the CSV keeps them all), text as is."""
    if text in BOOL_TEXT or not text:
        return text
    try:
        return f"{float(text):.6g}"
    except ValueError:
        return text
