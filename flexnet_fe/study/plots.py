"""Charts of the studies (matplotlib, Agg): accuracy against CPU time with the Pareto front and
the shipped default, and the stability maps."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from flexnet_fe.study.common import ERR_RESOLUTION, HEADLINE_TOLERANCE, pareto_mask  # noqa: E402

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


def accuracy_chart(stage: str, rows: list[dict], path: Path, title: str) -> None:
    """One panel per headline: relative error vs CPU time [s], log-log."""
    cols = [k for k in rows[0] if k.startswith("err_")]
    wide = len(cols) > 1
    fig, axes = plt.subplots(1, len(cols), figsize=(5.2 * len(cols) if wide else 8.0, 4.6 if wide else 5.4),
                             squeeze=False)
    ok = [r for r in rows if r["status"] == "ok"]
    cost = np.array([r["cpu_s"] for r in ok], dtype=float)
    for ax, col in zip(axes[0], cols):
        err = np.array([max(r[col], ERR_FLOOR) for r in ok], dtype=float)
        front = pareto_mask(cost, err)
        order = np.argsort(cost[front])
        ax.step(cost[front][order], err[front][order], where="post", color="0.5", lw=1.2)
        ax.scatter(cost[front], err[front], s=260, facecolors="none", edgecolors="0.4", lw=1.2,
                   label="on the Pareto front (CPU ±15 %, errors < 0.01 % equal)")
        ax.axhspan(ERR_FLOOR / 2, ERR_RESOLUTION, color="0.9", zorder=0, label="error < 0.01 % (not resolved)")
        for k, (r, c, e) in enumerate(zip(ok, cost, err)):
            style = (dict(marker="*", s=220, color="tab:red", zorder=5, label="shipped default")
                     if r["is_default"] else dict(marker="s", s=60, color="k", zorder=4, label="reference")
                     if r["is_reference"] else dict(marker="o", s=36, color="tab:blue", zorder=3, label="variant"))
            ax.scatter([c], [e], **style)
            ax.annotate(_label(r), (c, e), textcoords="offset points", xytext=(4, 4 - 9 * (k % 4)), fontsize=7)
        ax.axhline(HEADLINE_TOLERANCE, color="tab:orange", ls="--", lw=1, label="2 % bar")
        ax.set_xscale("log")
        ax.set_yscale("log")
        _plain(ax, "x")
        ax.set_xlabel("CPU time of the stage [s]")
        ax.set_ylabel(f"relative error of {UNITS.get(col[4:], col[4:])} [-]")
        ax.grid(True, which="both", alpha=0.3)
    h, lab = axes[0][0].get_legend_handles_labels()
    uniq = dict(zip(lab, h))
    fig.legend(uniq.values(), uniq.keys(), fontsize=8, loc="lower center", ncol=6 if wide else 3, frameon=False)
    fig.suptitle(f"{title} (errors of 0 drawn at {ERR_FLOOR:g})", fontsize=10)
    fig.tight_layout(rect=(0, 0.09 if wide else 0.13, 1, 1))
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
