"""Energy report (issue 12 item 4): a glstat-like plot and CSV per stage history.

Reads the energy terms a stage writes as ``history.csv`` columns ending in ``_j`` [J]
(``<stage>/history.csv`` and ``<stage>/<part>/history.csv``, e.g. ``shell/wing_1``). Each
column is put in one glstat class by its name (:func:`classify`):

    kinetic          *kinetic*
    internal         *elastic*, *strain*, *internal*, *hourglass*
    contact          *contact*
    dissipated       *dissipat*, *damping*, *friction*
    external work    *work*
    balance          energy_balance_j, energy_error_j
    other            anything else ending in _j (plotted, not summed)

    total(t) = kinetic + internal + contact + dissipated            [J]
    balance(t) = total(t) − external work(t) − total(0)             [J]  (zero for a closed balance)

The balance is the stage's own column when it writes one (``energy_balance_j``, else the
older ``energy_error_j``): the stage knows the sign convention of its terms. Otherwise the
report computes it from the classes above and *says so* in the caption and the CSV column name
(``energy_balance_report_j``): a term the stage does not write (e.g. Rayleigh damping in the
shell stage before it wrote it) then shows up as a balance error, which is the point.

The relative error is the balance over the largest |total| or |external work| of the history
(the energy scale of the event), as ``energy_error_rel`` in the CSV.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexnet_fe.io import read_history_csv, write_history_csv
from flexnet_fe.report.units import TIME_AXIS, axis_unit
from flexnet_fe.runs import HISTORY

CLASSES = ("kinetic", "internal", "contact", "dissipated", "external_work", "balance", "other")
STORED = ("kinetic", "internal", "contact", "dissipated")
"""Classes summed into the glstat 'total energy'."""

BALANCE_COLUMNS = ("energy_balance_j", "energy_error_j")
"""Stage-written balance columns, preferred in this order."""

_PATTERNS = (("balance", ("energy_balance", "energy_error")),
             ("kinetic", ("kinetic",)),
             ("internal", ("elastic", "strain", "internal", "hourglass")),
             ("contact", ("contact",)),
             ("dissipated", ("dissipat", "damping", "friction")),
             ("external_work", ("work",)))


def classify(column: str) -> str:
    """The glstat class of an energy column (see the module doc)."""
    name = column.lower()
    for cls, keys in _PATTERNS:
        if any(k in name for k in keys):
            return cls
    return "other"


@dataclass(frozen=True)
class EnergyTable:
    """One history's energy terms and balance.

    label        e.g. 'collide', 'shell/wing_1'
    t_s          times [s], shape (n,)
    terms        {column: values [J] (n,)} of every ``_j`` column except the balance
    classes      {column: class}
    total_j      glstat total (n,) [J]
    work_j       external work (n,) [J] (zeros when the stage writes none)
    balance_j    balance (n,) [J]
    balance_from stage column name, or 'report' when computed here
    error_rel    balance / energy scale, (n,) [–]
    """

    label: str
    t_s: np.ndarray
    terms: dict
    classes: dict
    total_j: np.ndarray
    work_j: np.ndarray
    balance_j: np.ndarray
    balance_from: str
    error_rel: np.ndarray


def energy_table(label: str, history: dict) -> EnergyTable | None:
    """The energy table of a history (``{column: array}``), or None without ``_j`` columns."""
    cols = [c for c in history if c.endswith("_j")]
    if not cols or "t_s" not in history:
        return None
    t = np.asarray(history["t_s"], dtype=float)
    classes = {c: classify(c) for c in cols}
    terms = {c: np.asarray(history[c], dtype=float) for c in cols if classes[c] != "balance"}
    zero = np.zeros_like(t)
    total = sum((v for c, v in terms.items() if classes[c] in STORED), zero.copy())
    work = sum((v for c, v in terms.items() if classes[c] == "external_work"), zero.copy())
    stage_col = next((c for c in BALANCE_COLUMNS if c in history), None)
    if stage_col is not None:
        balance, source = np.asarray(history[stage_col], dtype=float), stage_col
    else:
        balance, source = total - work - (total[0] if len(total) else 0.0), "report"
    scale = max(float(np.nanmax(np.abs(total), initial=0.0)), float(np.nanmax(np.abs(work), initial=0.0)))
    err = balance / scale if scale > 0 else np.zeros_like(balance)
    return EnergyTable(label, t, terms, {c: classes[c] for c in terms}, total, work, balance, source, err)


def write_energy_csv(table: EnergyTable, path: Path) -> None:
    """``t_s``, every term, ``total_j``, ``external_work_total_j``, the balance (named
    ``energy_balance_report_j`` when computed by the report) and ``energy_error_rel``."""
    cols = {"t_s": table.t_s, **table.terms, "total_j": table.total_j, "external_work_total_j": table.work_j,
            ("energy_balance_report_j" if table.balance_from == "report" else table.balance_from): table.balance_j,
            "energy_error_rel": table.error_rel}
    write_history_csv(path, cols)


def plot_energy(table: EnergyTable, png: Path) -> None:
    """glstat-like figure: every term, the total and the external work vs time (top); the
    balance [J] and its relative value (bottom)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    peak = max([float(np.nanmax(np.abs(v), initial=0.0)) for v in table.terms.values()]
               + [float(np.nanmax(np.abs(table.total_j), initial=0.0))])
    eu = axis_unit("e_j", peak)
    t = table.t_s * TIME_AXIS.scale
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(7.5, 5.8), sharex=True, height_ratios=(2.2, 1))
    for c, v in table.terms.items():
        ax.plot(t, v * eu.scale, label=f"{c} ({table.classes[c].replace('_', ' ')})")
    ax.plot(t, table.total_j * eu.scale, "k-", lw=2, label="total = kinetic + internal + contact + dissipated")
    if np.any(table.work_j):
        ax.plot(t, table.work_j * eu.scale, "k--", lw=1.5, label="external work")
    ax.set_ylabel(f"energy [{eu.label}]")
    ax.set_title(f"Energy, {table.label}")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    bu = axis_unit("e_j", float(np.nanmax(np.abs(table.balance_j), initial=0.0)))
    bx.plot(t, table.balance_j * bu.scale, "r-")
    src = "stage column " + table.balance_from if table.balance_from != "report" else \
        "computed by the report: total − external work − total(0)"
    bx.set_ylabel(f"balance [{bu.label}]")
    bx.set_xlabel(f"time t [{TIME_AXIS.label}]")
    bx.set_title(f"energy balance ({src}); final {table.error_rel[-1]:+.3g} of the energy scale"
                 if len(table.error_rel) else "energy balance", fontsize=8)
    bx.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=100)
    plt.close(fig)


def energy_histories(run_dir: Path, stages: list[str]) -> list[tuple[str, Path]]:
    """(label, history.csv) of every stage history and part history, in stage order."""
    out = []
    for stage in stages:
        d = Path(run_dir) / stage
        if (d / HISTORY).is_file():
            out.append((stage, d / HISTORY))
        if d.is_dir():
            out += [(f"{stage}/{p.parent.name}", p) for p in sorted(d.glob("*/history.csv"))]
    return out


@dataclass(frozen=True)
class EnergyFigure:
    """A rendered energy figure: label, png and csv (relative to the run dir), balance source,
    largest |relative error| over the history."""

    label: str
    png: str
    csv: str
    balance_from: str
    max_error_rel: float
    final_error_rel: float


def energy_report(run_dir: Path, stages: list[str], out_dir: Path, notes: list[str]) -> list[EnergyFigure]:
    """Plot and CSV of every history with ``_j`` columns into ``out_dir``."""
    run_dir = Path(run_dir)
    figs = []
    for label, path in energy_histories(run_dir, stages):
        try:
            table = energy_table(label, read_history_csv(path))
        except (OSError, ValueError) as err:
            notes.append(f"{path.relative_to(run_dir)}: unreadable ({err})")
            continue
        if table is None or len(table.t_s) == 0:
            continue
        stem = "energy_" + label.replace("/", "_")
        png, csv = out_dir / f"{stem}.png", out_dir / f"{stem}.csv"
        write_energy_csv(table, csv)
        plot_energy(table, png)
        err = np.abs(table.error_rel[np.isfinite(table.error_rel)])
        figs.append(EnergyFigure(label, str(png.relative_to(run_dir)), str(csv.relative_to(run_dir)),
                                 table.balance_from, float(err.max(initial=0.0)),
                                 float(table.error_rel[-1])))
    return figs
