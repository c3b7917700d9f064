"""Charts of the studies (matplotlib, Agg): accuracy against CPU time with the Pareto front and
the shipped default, and the stability maps."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from flexnet_fe.study.common import COST_NOISE, ERR_RESOLUTION, HEADLINE_TOLERANCE, candidate_front  # noqa: E402

ERR_FLOOR = 1e-6
"""Errors of exactly zero (the reference itself, or a knob that changes nothing) are drawn here."""

UNITS = {"max_area_m2": "max area", "time_to_max_area_s": "time of max area", "dv_over_v": "Δv/v",
         "fin_impulse_ns": "per-fin impulse", "peak_accel_mps2": "filtered peak accel.",
         "peak_von_mises_pa": "peak fin von Mises", "miss_distance_m": "miss distance"}


def _plain(ax, which: str = "xy") -> None:
    """Log axes with plain tick labels (0.5, 1, 2 rather than 5×10⁻¹)."""
    from matplotlib.ticker import NullFormatter, ScalarFormatter

    for axis in [a for n, a in (("x", ax.xaxis), ("y", ax.yaxis)) if n in which]:
        if axis.get_scale() == "log":
            f = ScalarFormatter()
            f.set_scientific(True)
            f.set_powerlimits((-3, 4))
            axis.set_major_formatter(f)
            axis.set_minor_formatter(NullFormatter())


def _label(r: dict) -> str:
    if r["is_reference"]:
        return "reference"
    if r["is_default"]:
        return "default"
    return f"{r['knob'].split('.')[-1]}={r['value']}"


LABEL_PT = 7
"""Font size of the point labels [pt]."""


def _boxes_overlap(a: tuple, b: tuple) -> bool:
    """Axis-aligned boxes (x0, y0, x1, y1) overlap."""
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def label_offsets(anchors: np.ndarray, widths: np.ndarray, height: float, frame: tuple,
                  keep_clear: float = 6.0) -> list:
    """Greedy placement of point labels without overlaps: for each point (display coordinates
    ``anchors`` (n, 2) [pt], label sizes ``widths`` (n,) × ``height`` [pt]) the first offset [pt] of a
    ring of candidates around it, then of wider rings, whose box lies inside ``frame`` (x0, y0, x1, y1)
    [pt] and overlaps no label placed before it and no point (a disc of ``keep_clear`` pt). Returns
    [(dx, dy, leader)] per point: ``leader`` is True past the first ring, where the label is drawn with
    a line to its point. A point whose every candidate collides gets the last (the chart is crowded
    there; its label may overlap)."""
    placed: list[tuple] = []
    out = []
    for (x, y), w in zip(anchors, widths):
        choice = None
        for ring, r in enumerate((4.0, 14.0, 26.0, 40.0)):
            for dx, dy in ((r, r), (r, -r - height), (-r - w, r), (-r - w, -r - height), (r, -height / 2),
                           (-r - w, -height / 2), (-w / 2, r + 2), (-w / 2, -r - height - 2)):
                box = (x + dx, y + dy, x + dx + w, y + dy + height)
                outside = box[0] < frame[0] or box[1] < frame[1] or box[2] > frame[2] or box[3] > frame[3]
                hits_label = outside or any(_boxes_overlap(box, b) for b in placed)
                hits_point = any(_boxes_overlap(box, (px - keep_clear, py - keep_clear, px + keep_clear,
                                                      py + keep_clear)) for px, py in anchors)
                choice = (dx, dy, ring > 0, box)
                if not (hits_label or hits_point):
                    break
            else:
                continue
            break
        placed.append(choice[3])
        out.append(choice[:3])
    return out


def _annotate_points(ax, fig, xs, ys, labels: list[str]) -> None:
    """Point labels placed by :func:`label_offsets` (axes limits final: call after the scatters)."""
    fig.canvas.draw()  # fixes the autoscaled limits, hence the data → display transform
    px_per_pt = fig.dpi / 72.0
    anchors = ax.transData.transform(np.column_stack([xs, ys])) / px_per_pt
    widths = np.array([0.55 * LABEL_PT * len(t) for t in labels])
    frame = tuple(ax.get_window_extent().extents / px_per_pt)
    for (dx, dy, leader), t, x, y in zip(label_offsets(anchors, widths, LABEL_PT * 1.2, frame), labels, xs, ys):
        ax.annotate(t, (x, y), textcoords="offset points", xytext=(dx, dy), fontsize=LABEL_PT,
                    arrowprops=dict(arrowstyle="-", color="0.5", lw=0.6, shrinkA=0, shrinkB=4) if leader else None)


NAMED_POINTS_MAX = 10
"""Charts with more points than this label them by number, with a key under the chart (names crowd)."""


def accuracy_chart(stage: str, rows: list[dict], path: Path, title: str) -> None:
    """One panel per headline: relative error vs CPU time [s], log-log."""
    cols = [k for k in rows[0] if k.startswith("err_")]
    wide = len(cols) > 1
    ok = [r for r in rows if r["status"] == "ok"]
    names = [_label(r) for r in ok]
    numbered = len(ok) > NAMED_POINTS_MAX
    key_rows = math.ceil(len(ok) / (4 if wide else 2)) if numbered else 0
    key_h = 0.16 * key_rows  # [in]
    fig, axes = plt.subplots(1, len(cols), squeeze=False,
                             figsize=(5.2 * len(cols) if wide else 8.0, (4.6 if wide else 5.4) + key_h))
    cost = np.array([r["cpu_s"] for r in ok], dtype=float)
    for ax, col in zip(axes[0], cols):
        err = np.array([max(r[col], ERR_FLOOR) for r in ok], dtype=float)
        front = candidate_front(ok, cost, err)
        order = np.argsort(cost[front])
        ax.step(cost[front][order], err[front][order], where="post", color="0.5", lw=1.2)
        ax.scatter(cost[front], err[front], s=260, facecolors="none", edgecolors="0.4", lw=1.2,
                   label=f"on the Pareto front: no point {100 * COST_NOISE:.0f} % cheaper and as accurate,\n"
                         "nor one as cheap (within as much) with under half the error")
        ax.axhspan(ERR_FLOOR / 2, ERR_RESOLUTION, color="0.9", zorder=0, label="error < 0.01 % (not resolved)")
        for r, c, e in zip(ok, cost, err):
            style = (dict(marker="*", s=220, color="tab:red", zorder=5, label="shipped default")
                     if r["is_default"] else dict(marker="s", s=60, color="k", zorder=4, label="reference")
                     if r["is_reference"] else dict(marker="X", s=60, color="0.45", zorder=3,
                                                     label="excluded from the front (why: under the table)")
                     if r.get("excluded") else dict(marker="o", s=36, color="tab:blue", zorder=3, label="variant"))
            ax.scatter([c], [e], **style)
        ax.axhline(HEADLINE_TOLERANCE, color="tab:orange", ls="--", lw=1, label="2 % bar")
        ax.set_xscale("log")
        ax.set_yscale("log")
        _plain(ax, "x")
        ax.set_xlabel("CPU time of the stage [s]")
        ax.set_ylabel(f"relative error of {UNITS.get(col[4:], col[4:])} [-]")
        ax.grid(True, which="both", alpha=0.3)
    h, lab = axes[0][0].get_legend_handles_labels()
    uniq = dict(zip(lab, h))
    fig.legend(uniq.values(), uniq.keys(), fontsize=8, loc="lower center", ncol=6 if wide else 3, frameon=False,
               bbox_to_anchor=(0.5, (key_h + 0.05) / fig.get_figheight()))
    fig.suptitle(f"{title} (errors of 0 drawn at {ERR_FLOOR:g})", fontsize=10)
    bottom = ((0.42 if wide else 0.7) + key_h) / fig.get_figheight()
    if numbered:
        per_row = 4 if wide else 2
        for k, name in enumerate(names):
            fig.text((0.06 + (k % per_row) / per_row * 0.9), (key_h - 0.16 * (k // per_row)) / fig.get_figheight(),
                     f"{k + 1}: {name}", fontsize=LABEL_PT + 1, va="top")
    fig.tight_layout(rect=(0, bottom, 1, 1))
    labels = [str(k + 1) for k in range(len(ok))] if numbered else names
    for ax, col in zip(axes[0], cols):  # after the layout: the labels are placed in its final coordinates
        _annotate_points(ax, fig, cost, [max(r[col], ERR_FLOOR) for r in ok], labels)
    fig.savefig(path, dpi=110)
    plt.close(fig)


MARK = {"ok": dict(marker="o", color="tab:blue"), "flagged": dict(marker="^", color="tab:orange"),
        "stopped": dict(marker="x", color="k")}


def _status_scatter(ax, xs, ys, rows):
    for x, y, r in zip(xs, ys, rows):
        st = MARK[r["status"]]
        ax.scatter([x], [y], s=50, label=f"{r['status']}" + (" (guard)" if r["status"] != "ok" else ""), **st)
        if r["escaped"]:
            ax.scatter([x], [y], s=220, facecolors="none", edgecolors="tab:red", lw=2, label="wrong number escaped")


def dt_map_chart(rows: list[dict], path: Path) -> None:
    maps = [m for m in ("net", "collide", "shell") if any(r["map"] == m for r in rows)]
    if not maps:
        return
    fig, axes = plt.subplots(1, len(maps), figsize=(5 * len(maps), 4.2), squeeze=False)
    for ax, m in zip(axes[0], maps):
        rs = [r for r in rows if r["map"] == m]
        x = np.array([r.get("dt_over_dt_crit", math.nan) for r in rs], dtype=float)
        if m == "collide":
            x = np.array([r["dt_scale"] for r in rs], dtype=float)
        y = np.array([r.get("energy_growth", math.nan) for r in rs], dtype=float)
        top = np.nanmax(y) * 2 if np.isfinite(y).any() else 10.0
        y = np.where(np.isfinite(y), y, top)
        _status_scatter(ax, x, np.maximum(y, 1e-6), rs)
        ax.set_xscale("log")
        ax.set_yscale("log")
        if m == "collide":
            ax.set_xlabel("dt / dt chosen by the solver [-]")
            ax.set_ylabel("energy balance error / energy exchanged [-]")
        else:
            ax.axvline(1.0, color="0.5", ls=":", lw=1)
            ax.set_xlabel("dt / dt_crit [-]")
            ax.set_ylabel("energy growth max(E)/E_ref [-] (stopped: drawn at top)")
        _plain(ax, "x")
        ax.set_title({"net": "net (deploy, forced dt)", "collide": "collision (dt_scale)",
                      "shell": "shell (plate, dt = r·dt_crit)"}[m], fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        _legend_once(ax)
    _save(fig, path)


def _legend_once(ax) -> None:
    """A legend with one entry per label (scatter points repeat their labels)."""
    h, lab = ax.get_legend_handles_labels()
    uniq = dict(zip(lab, h))
    ax.legend(uniq.values(), uniq.keys(), fontsize=7)


def _save(fig, path: Path) -> None:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def contact_chart(rows: list[dict], path: Path) -> None:
    rs = [r for r in rows if r["map"] == "contact"]
    if not rs:
        return
    fs = sorted({r["pass_through_fraction"] for r in rs})
    fig, axes = plt.subplots(1, len(fs), figsize=(5 * len(fs), 4.2), squeeze=False)
    for ax, f in zip(axes[0], fs):
        sub = [r for r in rs if r["pass_through_fraction"] == f]
        for r in sub:
            pen = r["penetration_ratio"]
            c = "k" if not np.isfinite(pen) else plt.cm.viridis(min(pen, 1.0))
            ax.scatter([r["impact_speed_mps"]], [r["stiffness"]], s=80, marker=MARK[r["status"]]["marker"],
                       color=c, label=r["status"] + (" (guard)" if r["status"] != "ok" else ""))
            if np.isfinite(pen):
                ax.annotate(f"{pen:.2f}", (r["impact_speed_mps"], r["stiffness"]), textcoords="offset points",
                            xytext=(5, 3), fontsize=7)
            if r["escaped"]:
                ax.scatter([r["impact_speed_mps"]], [r["stiffness"]], s=240, facecolors="none",
                           edgecolors="tab:red", lw=2, label="wrong number escaped")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("impact speed [m/s]")
        ax.set_ylabel("contact stiffness K [N/m^1.5]")
        _plain(ax, "x")
        ax.set_title(f"travel per step = {f:g} × min(r, h/2); label = penetration / (r + h/2)", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        _legend_once(ax)
    _save(fig, path)


def damping_chart(rows: list[dict], path: Path) -> None:
    rs = [r for r in rows if r["map"] == "damping"]
    if not rs:
        return
    models = list(dict.fromkeys(r["model"] for r in rs))
    fig, axes = plt.subplots(1, len(models), figsize=(4.6 * len(models), 4.2), squeeze=False, sharey=True)
    for ax, m in zip(axes[0], models):
        for e in sorted({r["restitution_requested"] for r in rs}):
            sub = sorted([r for r in rs if r["model"] == m and r["restitution_requested"] == e],
                         key=lambda r: r["impact_speed_mps"])
            v = [r["impact_speed_mps"] for r in sub]
            line, = ax.plot(v, [r["restitution_achieved"] for r in sub], "o-", label=f"requested e = {e:g}")
            ax.axhline(e, color=line.get_color(), ls=":", lw=1)
            for r in sub:
                if r["escaped"]:
                    ax.scatter([r["impact_speed_mps"]], [r["restitution_achieved"]], s=150, facecolors="none",
                               edgecolors="tab:red", lw=1.5)
        ax.set_xscale("log")
        ax.set_xlabel("impact speed [m/s] (v_k floor 1 m/s)")
        ax.set_ylabel("restitution achieved v_out/v_in [-]")
        _plain(ax)
        ax.set_title(f"{m} (red ring: |e_ach − e| > 0.05)", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
