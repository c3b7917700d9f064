"""The report's own figures: matplotlib plots (shell stress histories with the allowable,
collision response with sensible units) made in-process, and the 3-D pictures (whole missile,
net events, animation, per-fin pictures, deploy net) rendered in ONE child process
(:func:`flexnet_fe.report.pictures.render_isolated`), plus the ParaView missile files.

:func:`assemble_figures` fills each stage view's ``figures`` / ``pictures`` and returns what
the top of the report shows (``missile``, ``net``, ``animation``, ``paraview``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from flexnet_fe.errors import FlexnetError
from flexnet_fe.io import read_history_csv
from flexnet_fe.report.rundir import RunData, fin_results
from flexnet_fe.report.units import PA_TO_MPA, S_TO_MS, TIME_AXIS, axis_unit
from flexnet_fe.report.verdict import Verdict
from flexnet_fe.runs import ENVELOPE_XDMF, FIELDS_XDMF, HISTORY, MISSILE_PVD, NET_PVD


@dataclass(frozen=True)
class Figure:
    """An image of the report: path relative to the run directory, caption."""

    src: str
    caption: str


def _rel(run: RunData, path: Path) -> str:
    return str(Path(path).relative_to(run.run_dir))


def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _read(run: RunData, path: Path, notes: list[str]) -> dict | None:
    if not path.is_file():
        return None
    try:
        return read_history_csv(path)
    except (OSError, ValueError) as err:
        notes.append(f"{_rel(run, path)}: unreadable ({err})")
        return None


def shell_history_plot(run: RunData, fins: list[str], verdict: Verdict, out_dir: Path,
                       notes: list[str]) -> str | None:
    """Peak von Mises and max principal stress over each fin vs time (``shell/<fin>/history.csv``),
    the allowable(s) as horizontal lines, each fin's summary peak marked. Relative png path."""
    curves = {}
    for fin in fins:
        h = _read(run, run.run_dir / "shell" / fin / HISTORY, notes)
        if h is None:
            continue
        if "t_s" in h and "max_von_mises_pa" in h:
            curves[fin] = h
        else:
            notes.append(f"shell/{fin}/history.csv: no t_s / max_von_mises_pa columns")
    if not curves:
        return None
    plt = _plt()
    by_name = {f.name: f for f in verdict.fins}
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.4), sharey=True)
    for ax, col, title in ((axes[0], "max_von_mises_pa", "von Mises"), (axes[1], "max_principal_pa", "max principal")):
        for fin, h in curves.items():
            if col not in h:
                continue
            line, = ax.plot(h["t_s"] * S_TO_MS, h[col] * PA_TO_MPA, lw=1.2, label=fin)
            fv = by_name.get(fin)
            peak = (fv.von_mises_pa if col == "max_von_mises_pa" else fv.max_principal_pa) if fv else None
            if fv and peak is not None and fv.time_s is not None and col == "max_von_mises_pa":
                ax.plot([fv.time_s * S_TO_MS], [peak * PA_TO_MPA], "o", color=line.get_color(), ms=6)
        for allow, source in sorted({(f.allowable_pa, f.allowable_source) for f in verdict.fins
                                     if f.allowable_pa is not None}):
            ax.axhline(allow * PA_TO_MPA, color="red", ls="--", lw=1.3)
            ax.annotate(f"allowable {allow * PA_TO_MPA:.4g} MPa", (0.01, allow * PA_TO_MPA),
                        xycoords=("axes fraction", "data"), color="red", fontsize=8, va="bottom")
        ax.set_xlabel(f"time t [{TIME_AXIS.label}]")
        ax.set_title(f"Largest {title} stress over each fin (dots: summary peaks)", fontsize=10)
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("stress [MPa]")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    path = out_dir / "shell_stress_history.png"
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return _rel(run, path)


ATTITUDE_COLUMNS = ("pitch_change_rad", "yaw_change_rad", "roll_change_rad", "attitude_change_rad")


def collide_plot(run: RunData, out_dir: Path, notes: list[str]) -> str | None:
    """CG acceleration magnitude (the summary's peak marked, and whether it is CFC-filtered)
    and attitude change, each axis in a unit that fits its size (mrad / µrad, not 'rad × 1e-5')."""
    h = _read(run, run.run_dir / "collide" / HISTORY, notes)
    if h is None or "t_s" not in h:
        return None
    plt = _plt()
    section = (run.summary or {}).get("collide") or {}
    t = h["t_s"] * TIME_AXIS.scale
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.2))
    acc = [c for c in h if c.startswith("accel_mag") and c.endswith("_mps2")]   # raw and filtered
    if acc:
        au = axis_unit("accel_mps2", max(float(np.nanmax(np.abs(h[c]), initial=0.0)) for c in acc))
        for c in acc:
            ax.plot(t, h[c] * au.scale, lw=1.0,
                    label="|a| (mean over each output interval)" if c == "accel_mag_mps2" else c)
        pk, pt = section.get("peak_accel_mps2"), section.get("peak_accel_time_s")
        if isinstance(pk, (int, float)) and isinstance(pt, (int, float)):
            cfc = section.get("cfc")
            ax.plot([pt * TIME_AXIS.scale], [pk * au.scale], "ro",
                    label=f"summary peak ({'CFC ' + str(cfc) if cfc is not None else 'not CFC-filtered'})")
        ax.set_ylabel(f"CG acceleration magnitude [{au.label}]")
        ax.legend(fontsize=8)
    ax.set_xlabel(f"time t [{TIME_AXIS.label}]")
    ax.set_title("Missile CG acceleration (body axes B)", fontsize=10)
    ax.grid(True, alpha=0.3)
    cols = [c for c in ATTITUDE_COLUMNS if c in h]
    if cols:
        bu = axis_unit("x_rad", max(float(np.nanmax(np.abs(h[c]), initial=0.0)) for c in cols))
        for c in cols:
            bx.plot(t, h[c] * bu.scale, label=c.replace("_change_rad", ""))
        bx.set_ylabel(f"attitude change [{bu.label}]")
        bx.legend(fontsize=8)
    bx.set_xlabel(f"time t [{TIME_AXIS.label}]")
    bx.set_title("Attitude change since t = 0 (rotation about world x, y, z)", fontsize=10)
    bx.grid(True, alpha=0.3)
    fig.tight_layout()
    path = out_dir / "collide_response.png"
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return _rel(run, path)


def contact_events(run: RunData) -> list[list]:
    """[[label, t [s]], ...] for first contact, mid-passage and exit, from the ``contacts`` (or
    ``contact_force_mean_n``) column of collide/history.csv; [] when neither exists."""
    try:
        h = read_history_csv(run.run_dir / "collide" / HISTORY)
    except (OSError, ValueError):
        return []
    col = "contacts" if "contacts" in h else "contact_force_mean_n" if "contact_force_mean_n" in h else None
    if col is None or "t_s" not in h:
        return []
    on = np.flatnonzero(np.asarray(h[col]) > 0)
    if not len(on):
        return []
    t0, t1 = float(h["t_s"][on[0]]), float(h["t_s"][on[-1]])
    return [["first contact", t0], ["mid-passage", 0.5 * (t0 + t1)], ["exit (last contact)", t1]]


def _fin_names(run: RunData, stage) -> list[str]:
    fins = list(fin_results(stage.section)) if stage.complete else []
    if stage.folder:
        fins += sorted(p.name for p in stage.folder.iterdir()
                       if p.is_dir() and p.name not in fins
                       and ((p / FIELDS_XDMF).exists() or (p / ENVELOPE_XDMF).exists()))
    return fins


def _fin_picture_job(run: RunData, fin: str, res: dict, out_dir: Path,
                     allowable_pa: float | None = None) -> tuple[dict | None, str]:
    fin_dir = run.run_dir / "shell" / fin
    title = f"fin {fin}" + (f" (allowable {allowable_pa * PA_TO_MPA:.4g} MPa)" if allowable_pa else "")
    envelope, fields = fin_dir / ENVELOPE_XDMF, fin_dir / FIELDS_XDMF
    png = str(out_dir / f"shell_{fin}_von_mises.png")
    loc, vm, t = res.get("peak_location_m"), res.get("peak_von_mises_pa"), res.get("peak_time_s")
    mark = ([*map(float, loc), f"peak {vm * PA_TO_MPA:.4g} MPa at {t * S_TO_MS:.4g} ms"]
            if isinstance(loc, list) and len(loc) == 3 and isinstance(vm, (int, float)) and isinstance(t, (int, float))
            else None)
    if envelope.is_file():
        # the colour scale ends at the structural peak: the zones at the loads, far above it, would
        # otherwise take the whole scale and leave the fin's structural field one dark colour
        top = float(vm) if isinstance(vm, (int, float)) and vm > 0 else None
        return ({"kind": "stress", "args": {"xdmf": str(envelope), "png": png, "title": title, "mark": mark,
                                            "top_pa": top}},
                "peak over time of the cell von Mises stress, St-Venant zones at the loads included "
                "(envelope.xdmf; the structural peak, the dot, is taken outside them"
                + (f"; the colour scale ends at it, {top * PA_TO_MPA:.4g} MPa, magenta above: values reached inside the zones)"
                   if top else ")"))
    if fields.is_file():
        return ({"kind": "stress", "args": {"xdmf": str(fields), "png": png, "time_s": t, "title": title,
                                            "mark": mark}},
                "von Mises stress at the field output time nearest the peak (fields.xdmf)")
    return None, "no envelope.xdmf or fields.xdmf for this fin"


def _fin_caption(run: RunData, fin: str, res: dict, what: str, result, notes: list[str]) -> tuple[str | None, str]:
    if isinstance(result, str):
        notes.append(f"stress picture of fin '{fin}': {result}")
        return None, f"could not render: {result}"
    env = "envelope" in what
    when = "" if env else f", t = {result['time_s'] * S_TO_MS:.4g} ms"
    caption = (f"{what}; field {result['field']}{when}; max in picture {result['max_pa'] * PA_TO_MPA:.4g} MPa; "
               "magenta dot: the summary's peak location. Undeformed mesh, body frame B [m], seen normal to the fin.")
    # The envelope holds every cell, the St-Venant zones around the loads included: its maximum is
    # the summary's peak with the load zones (the structural peak, outside them, is lower).
    key = "peak_von_mises_with_load_zones_pa" if "peak_von_mises_with_load_zones_pa" in res else "peak_von_mises_pa"
    vm = res.get(key)
    if env and isinstance(vm, (int, float)) and vm > 0 and not math.isclose(result["max_pa"], vm, rel_tol=1e-6):
        notes.append(f"fin '{fin}': envelope.xdmf maximum {result['max_pa']:.6g} Pa differs from summary.json "
                     f"{key} {vm:.6g} Pa")
    return _rel(run, Path(result["png"])), caption


def _paraview(run: RunData, fins: list[str], verdict: Verdict, out_dir: Path, notes: list[str]):
    from flexnet_fe.report.paraview import write_missile_files

    peak = max((f for f in verdict.fins if f.von_mises_pa is not None), key=lambda f: f.von_mises_pa, default=None)
    try:
        return write_missile_files(run.run_dir / "shell", fins, out_dir / "paraview", notes,
                                   peak.time_s if peak else None), peak
    except FlexnetError as err:
        notes.append(f"ParaView missile file not written: {err}")
        return None, peak


def assemble_figures(run: RunData, verdict: Verdict, stages: list[dict], out_dir: Path,
                     notes: list[str], pictures: bool = True) -> dict[str, Any]:
    """Make every figure (module doc); returns the top-of-report figures. ``pictures=False``
    skips the 3-D pictures (no child process; each is listed as not rendered)."""
    top: dict[str, Any] = {"missile": None, "net": None, "animation": None, "paraview": None}
    views = {v["info"].name: v for v in stages}
    jobs: list[dict] = []
    later: list = []          # (callback(result)) per job, in order
    shell = views.get("shell")
    if shell and (shell["info"].complete or shell["info"].folder is not None):
        _shell_jobs(run, shell, verdict, out_dir, notes, jobs, later, top)
    collide = views.get("collide")
    if collide and collide["info"].folder is not None:
        _collide_jobs(run, collide, out_dir, notes, jobs, later, top)
    deploy = views.get("deploy")
    if deploy and deploy["info"].folder is not None and (run.run_dir / "deploy" / NET_PVD).is_file():
        png = out_dir / "deploy_net.png"
        jobs.append({"kind": "net_panels", "args": {"pvd": str(run.run_dir / "deploy" / NET_PVD),
                                                    "png": str(png), "count": 6, "title": "deploy:"}})
        later.append(lambda r, v=deploy, png=png: _simple(run, r, v["figures"], png, notes, "deploy net",
                                                          "The net during deployment, seen along the flight direction "
                                                          "z (world frame W); each panel centred on the net (it flies "
                                                          "hundreds of metres), one scale for all panels; colour = rope "
                                                          "tension [N]."))
    from flexnet_fe.report.pictures import render_isolated

    results = render_isolated(jobs) if pictures else ["not rendered (pictures=False)"] * len(jobs)
    for callback, result in zip(later, results):
        callback(result)
    return top


def _simple(run: RunData, result, target: list, png: Path, notes: list[str], what: str, caption: str):
    if isinstance(result, str):
        notes.append(f"{what} picture: {result}")
        return None
    fig = Figure(_rel(run, png), caption)
    target.append(fig)
    return fig


def _shell_jobs(run, view, verdict, out_dir, notes, jobs, later, top) -> None:
    stage = view["info"]
    fins = _fin_names(run, stage)
    summary_fins = fin_results(stage.section) if stage.complete else {}
    plot = shell_history_plot(run, fins, verdict, out_dir, notes)
    if plot:
        view["figures"].append(Figure(plot, "Largest von Mises (left) and maximum principal (right) stress over "
                                            "each fin vs time, from shell/<fin>/history.csv; red dashed: allowable; "
                                            "dots: the summary's peaks."))
    allowables = {f.name: f.allowable_pa for f in verdict.fins}
    for fin in fins:
        res = summary_fins.get(fin, {})
        job, what = _fin_picture_job(run, fin, res, out_dir, allowables.get(fin))
        if job is None:
            view["pictures"].append((fin, None, what))
            continue
        jobs.append(job)
        later.append(lambda r, fin=fin, res=res, what=what: view["pictures"].append(
            (fin, *_fin_caption(run, fin, res, what, r, notes))))
    files, peak = _paraview(run, fins, verdict, out_dir, notes)
    if files is None:
        return
    top["paraview"] = {"xdmf": _rel(run, files.xdmf), "envelope": _rel(run, files.envelope) if files.envelope else None,
                       "script": _rel(run, files.script), "times_csv": _rel(run, files.times_csv),
                       "parts": files.parts, "n_times": len(files.times_s)}
    if files.envelope is None:
        return
    allow = {f.allowable_pa for f in verdict.fins if f.allowable_pa is not None}
    marks = [{"name": f.name, "location_m": f.location_m, "value_pa": f.von_mises_pa,
              "at_frame": peak is not None and f.name == peak.name}
             for f in verdict.fins if isinstance(f.location_m, list) and f.von_mises_pa is not None]
    png = out_dir / "missile_von_mises.png"
    label = f"{peak.name} at {peak.time_s * S_TO_MS:.4g} ms" if peak and peak.time_s is not None else "none"
    jobs.append({"kind": "missile", "args": {
        "missile_xdmf": str(files.xdmf), "envelope_xdmf": str(files.envelope), "png": str(png),
        "time_s": peak.time_s if peak else None, "allowable_pa": min(allow) if len(allow) >= 1 else None,
        "marks": marks, "title": "Whole missile (body + solved fins)", "peak_label": label}})

    def done(r):
        if isinstance(r, str):
            notes.append(f"whole-missile stress picture: {r}")
            return
        shown = r["frame_time_s"]
        extra = ("" if peak is None or peak.time_s is None or shown is None else
                 f" The saved output nearest the peak is at {shown * S_TO_MS:.4g} ms, "
                 f"{abs(shown - peak.time_s) * S_TO_MS:.3g} ms from it: the right panel can miss the peak "
                 "(the envelope on the left cannot)." if abs(shown - peak.time_s) > 1e-9 else
                 " The right panel is the peak's own output frame.")
        scale = (f"colour scale ends at the allowable {min(allow) * PA_TO_MPA:.4g} MPa, magenta = above it"
                 if allow else "no allowable known: colour scale ends at the envelope maximum")
        top["missile"] = Figure(_rel(run, png), "Von Mises stress on the whole missile, body frame B: left the "
                                                "envelope (peak over time per cell), right the field at the output "
                                                f"time nearest the largest peak, displacement ×50; {scale}; labels: "
                                                "each fin's peak location and value." + extra)
    later.append(done)


def _collide_jobs(run, view, out_dir, notes, jobs, later, top) -> None:
    plot = collide_plot(run, out_dir, notes)
    if plot:
        view["figures"].append(Figure(plot, "Missile CG acceleration magnitude and attitude change vs time, from "
                                            "collide/history.csv (axis units chosen to fit the values)."))
    net_pvd, mis_pvd = run.run_dir / "collide" / NET_PVD, run.run_dir / "collide" / MISSILE_PVD
    if not (net_pvd.is_file() and mis_pvd.is_file()):
        return
    events = contact_events(run)
    if events:
        png = out_dir / "collide_net_events.png"
        jobs.append({"kind": "net_events", "args": {"net_pvd": str(net_pvd), "missile_pvd": str(mis_pvd),
                                                    "png": str(png), "events": events}})
        text = ", ".join(f"{label} {t * S_TO_MS:.4g} ms" for label, t in events)
        later.append(lambda r: top.__setitem__("net", _simple(
            run, r, [], png, notes, "net events",
            f"The net and the missile (wireframe) at the snapshots nearest to {text} (contact times from "
            "collide/history.csv); side view in the world frame W, camera on the missile, net drawn within "
            "2 m of it, colour = rope tension [N].")))
    gif = out_dir / "collision.gif"
    jobs.append({"kind": "animation", "args": {"net_pvd": str(net_pvd), "missile_pvd": str(mis_pvd), "gif": str(gif)}})

    def anim(r):
        if isinstance(r, str):
            notes.append(f"collision animation: {r}")
            return
        top["animation"] = Figure(_rel(run, gif), f"{r} frames, one per collide snapshot (collide/net.pvd, "
                                                   "missile.pvd); fixed side camera, colour = rope tension [N].")
    later.append(anim)
