"""Offscreen PyVista pictures of the stages' field files (no display needed).

``render_stress`` draws one fin's stress field from the shell stage's XDMF — its recovered nodal
(CG1 ``*_nodal_pa``) values where the file has them, else the DG0 cell values — (written by
dolfinx: a ``mesh`` grid plus one temporal collection per scalar field, cell-centred) seen
normal to the fin plane; ``render_net`` draws net snapshots from a ``.pvd`` collection of line
meshes (deploy / collide stages). XDMF files are read with :mod:`flexnet_fe.xdmf`
(h5py), not with VTK's XDMF reader (it segfaults on a missing .h5). Rendering uses EGL: ``VTK_DEFAULT_OPENGL_WINDOW`` and
``PYVISTA_OFF_SCREEN`` are set (if the caller has not set them) before pyvista is imported.

Measured here (VTK 9.7.2 wheel, Debian dolfinx 0.5.2): once ``dolfinx.cpp`` is imported,
a VTK offscreen ``screenshot`` aborts the process (``std::bad_alloc``) unless VTK's OpenGL
modules were loaded first; and VTK can crash outright on odd input. So the report renders in
a child process (:func:`render_stress_isolated`, ``python -m flexnet_fe.report.pictures``):
a crash there becomes a line in the report, never the end of the caller (a pipeline that has
run the shell stage in-process has dolfinx loaded).
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from flexnet_fe.errors import FlexnetError
from flexnet_fe.io import pvd_entries
from flexnet_fe.report.scenes import ABOVE_COLOUR
from flexnet_fe.report.units import PA_TO_MPA

ENVELOPE_FIELD = "peak_von_mises_pa"
"""The shell stage's envelope field: peak over time of the cell's von Mises stress [Pa]."""

VON_MISES_PREFIX = "von_mises_"
"""The shell stage's per-surface von Mises fields: ``von_mises_{top,mid,bottom}_pa`` [Pa]."""


@dataclass(frozen=True)
class Picture:
    """A rendered field picture and what it shows.

    png        the image written
    field      what the colours are (the field name, or ``max of a, b, c`` over surfaces)
    time_s     output time shown [s] (the file's own time value)
    max_pa     largest cell value of the field at that time [Pa]
    """

    png: Path
    field: str
    time_s: float
    max_pa: float


def offscreen_env() -> None:
    """Select EGL offscreen rendering unless the caller chose otherwise (before importing pyvista)."""
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")


def plane_normal(points: np.ndarray) -> np.ndarray:
    """Unit normal of the best-fit plane of ``points`` [m], shape (n, 3): the singular vector
    of least variance. Used as the camera direction so a flat fin is seen face-on."""
    centred = points - points.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    return vt[-1] / np.linalg.norm(vt[-1])


def read_cell_fields(xdmf: Path, time_s: float | None = None):
    """Read a dolfinx XDMF file's cell fields at the output time nearest ``time_s`` (default:
    the last) with :mod:`flexnet_fe.xdmf`.

    Returns ``(pyvista grid, {name: cell values (n_cells,)}, time shown [s])``. Only scalar
    cell fields at that same time are returned. Raises :class:`FlexnetError` when the file (or
    its .h5) cannot be read or holds no scalar cell field.
    """
    offscreen_env()
    import pyvista as pv

    from flexnet_fe.xdmf import list_fields, nearest_time_index, read_field, read_mesh

    mesh = read_mesh(xdmf)
    cell_fields = {n: f for n, f in list_fields(xdmf).items() if f.center == "Cell"}
    if not cell_fields:
        raise FlexnetError(f"{xdmf}: no cell field in the file")
    first = next(iter(cell_fields.values()))
    t = first.times[nearest_time_index(first.times, time_s)]
    fields = {}
    for name, f in cell_fields.items():
        if t in f.times:
            values = read_field(xdmf, f, f.times.index(t))
            if values.ndim == 1 and len(values) == len(mesh.cells):
                fields[name] = values
    if not fields:
        raise FlexnetError(f"{xdmf}: no scalar cell field with one value per cell")
    vtk_type = {"Triangle": pv.CellType.TRIANGLE, "Quadrilateral": pv.CellType.QUAD}[mesh.cell_type]
    grid = pv.UnstructuredGrid({vtk_type: mesh.cells}, mesh.points)
    return grid, fields, float(t)


def stress_field(fields: dict[str, np.ndarray]) -> tuple[str, np.ndarray]:
    """The von Mises field to draw: the envelope ``peak_von_mises_pa`` if present, else the
    cell-wise maximum over the surface fields ``von_mises_*`` (top, mid, bottom) [Pa]."""
    if ENVELOPE_FIELD in fields:
        return ENVELOPE_FIELD, fields[ENVELOPE_FIELD]
    names = sorted(n for n in fields if n.startswith(VON_MISES_PREFIX))
    if not names:
        raise FlexnetError(f"no von Mises field among {sorted(fields)}")
    if len(names) == 1:
        return names[0], fields[names[0]]
    return "max of " + ", ".join(names), np.max([fields[n] for n in names], axis=0)


def _nodal_counterpart(xdmf: Path, label: str, t: float, n_points: int) -> np.ndarray | None:
    """The recovered nodal field ``<label without _pa>_nodal_pa`` [Pa] (n_points,) of ``xdmf`` at
    time ``t`` (the envelope: its only time), or None when the file has none."""
    from flexnet_fe.xdmf import list_fields, nearest_time_index, read_field

    if not label.endswith("_pa"):
        return None
    f = list_fields(xdmf).get(label[:-3] + "_nodal_pa")
    if f is None or f.center != "Node":
        return None
    k = 0 if len(f.times) == 1 else (f.times.index(t) if t in f.times else nearest_time_index(f.times, t))
    values = read_field(xdmf, f, k)
    return values if values.ndim == 1 and len(values) == n_points and np.all(np.isfinite(values)) else None


def render_stress(xdmf: Path, png: Path, *, time_s: float | None = None, field: str | None = None,
                  title: str = "", window: tuple[int, int] = (900, 700), mark: list | None = None,
                  top_pa: float | None = None) -> Picture:
    """Draw a fin's von Mises stress [MPa] (or the named cell ``field``) from ``xdmf`` at the
    output time nearest ``time_s`` into ``png``, seen normal to the fin plane, undeformed mesh
    with its element edges. Coordinates are those of the file (frame B for the shell stage).
    ``mark = [x, y, z, label]`` marks a point [m] (the peak location) with a labelled dot.
    ``top_pa`` [Pa]: the colour scale ends there (values above it magenta), else at the field's
    maximum."""
    offscreen_env()
    import pyvista as pv

    xdmf = Path(xdmf)
    grid, fields, t = read_cell_fields(xdmf, time_s)
    if field is None:
        label, values = stress_field(fields)
    elif field in fields:
        label, values = field, fields[field]
    else:
        raise FlexnetError(f"{xdmf}: no cell field '{field}' (fields: {', '.join(sorted(fields))})")
    if not np.all(np.isfinite(values)):
        raise FlexnetError(f"{xdmf}: field '{label}' holds NaN or inf")
    mesh = grid.copy()
    mesh.cell_data.clear()
    bar = "stress [MPa]" if label.endswith("_pa") or label.startswith("max of") else label
    nodal = _nodal_counterpart(xdmf, label, t, mesh.n_points)
    if nodal is not None:  # the shell's recovered nodal stress: smooth, not one value per cell
        label, values = label[:-3] + "_nodal_pa", nodal
        mesh.point_data[bar] = values * PA_TO_MPA
    else:
        mesh.cell_data[bar] = values * (PA_TO_MPA if bar == "stress [MPa]" else 1.0)
    normal = plane_normal(np.asarray(mesh.points))
    png = Path(png)
    png.parent.mkdir(parents=True, exist_ok=True)
    pl = pv.Plotter(off_screen=True, window_size=list(window))
    try:
        top = top_pa is not None and 0.0 < top_pa < float(values.max())
        pl.add_mesh(mesh, scalars=bar, cmap="turbo", show_edges=True, edge_color="gray", edge_opacity=0.25,
                    clim=[0.0, top_pa * PA_TO_MPA] if top else None, above_color=ABOVE_COLOUR if top else None,
                    scalar_bar_args={"title": bar, "vertical": True, "fmt": "%.4g"})
        centre = np.asarray(mesh.center)
        size = float(np.linalg.norm(np.ptp(np.asarray(mesh.points), axis=0))) or 1.0
        up = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        pl.camera_position = [tuple(centre + 2.0 * size * normal), tuple(centre), tuple(up)]
        pl.reset_camera()
        heading = title or xdmf.name
        # the envelope's single time value is a placeholder, not an instant
        time_txt = "" if math.isnan(t) or label in (ENVELOPE_FIELD, ENVELOPE_FIELD[:-3] + "_nodal_pa") else f", t = {t * 1e3:.4g} ms"
        scale = f"; magenta above {top_pa * PA_TO_MPA:.4g} MPa" if top else ""
        pl.add_text(f"{heading}\n{label}{time_txt}\nmax {values.max() * PA_TO_MPA:.4g} MPa{scale}",
                    font_size=10, position="upper_left")
        if mark is not None:
            pl.add_point_labels(pv.PolyData(np.array([mark[:3]], dtype=float)), [str(mark[3])],
                                point_size=16, point_color="magenta", font_size=12, shape_opacity=0.7,
                                always_visible=True, render_points_as_spheres=True)
        pl.add_axes()
        pl.screenshot(str(png))
    finally:
        pl.close()
    return Picture(png=png, field=label, time_s=t, max_pa=float(values.max()))


def render_net(pvd: Path, png: Path, *, count: int = 6, scalars: str | None = "tension_n",
               title: str = "", window: tuple[int, int] = (1400, 800)) -> list[float]:
    """Draw ``count`` snapshots (evenly spread over the collection) of a net ``.pvd`` side by side
    into ``png``, seen along the world z axis (flight direction, frame W), colours = the cell
    array ``scalars`` (one range for all panels) if every snapshot has it.

    The camera follows the net: each panel is centred on its own snapshot (the net flies
    hundreds of metres along z during deployment, ≈ 370 m in ``radar_traction``), with one
    parallel-projection scale for all panels so that sizes compare; the panel text gives the
    centre's z. Returns the snapshot times shown [s]."""
    offscreen_env()
    import pyvista as pv

    entries = [e for e in pvd_entries(pvd) if e[1].is_file()]
    if not entries:
        raise FlexnetError(f"{pvd}: no snapshot files found")
    idx = np.unique(np.linspace(0, len(entries) - 1, min(count, len(entries))).round().astype(int))
    meshes = [(entries[i][0], pv.read(str(entries[i][1]))) for i in idx]
    colour = bool(scalars) and all(scalars in m.cell_data for _, m in meshes)
    clim = ([min(float(np.min(m.cell_data[scalars])) for _, m in meshes),
             max(float(np.max(m.cell_data[scalars])) for _, m in meshes)] if colour else None)
    half = max(0.5 * float(max(np.ptp(np.asarray(m.points)[:, 0]), np.ptp(np.asarray(m.points)[:, 1])))
               for _, m in meshes) * 1.08 or 1.0
    ncol = min(3, len(meshes))
    nrow = math.ceil(len(meshes) / ncol)
    png = Path(png)
    png.parent.mkdir(parents=True, exist_ok=True)
    pl = pv.Plotter(off_screen=True, shape=(nrow, ncol), window_size=list(window))
    try:
        for k, (t, mesh) in enumerate(meshes):
            pl.subplot(k // ncol, k % ncol)
            if colour:
                pl.add_mesh(mesh, scalars=scalars, cmap="viridis", clim=clim, line_width=1.5,
                            show_scalar_bar=(k == len(meshes) - 1),
                            scalar_bar_args={"title": f"{scalars} [N]" if scalars.endswith("_n") else scalars,
                                             "fmt": "%.3g"})
            else:
                pl.add_mesh(mesh, color="black", line_width=1.5)
            c = np.asarray(mesh.center)
            pl.add_text(f"{title} t = {t * 1e3:.4g} ms\ncentre z = {c[2]:.4g} m".strip(), font_size=9)
            pl.enable_parallel_projection()
            pl.camera_position = [tuple(c + np.array([0.0, 0.0, 10.0 * half])), tuple(c), (0.0, 1.0, 0.0)]
            pl.camera.parallel_scale = half
            pl.reset_camera_clipping_range()
        pl.screenshot(str(png))
    finally:
        pl.close()
    return [t for t, _ in meshes]


@dataclass(frozen=True)
class StressJob:
    """One stress picture to render: arguments of :func:`render_stress`."""

    xdmf: str
    png: str
    time_s: float | None = None
    title: str = ""
    mark: list | None = None
    """``[x, y, z, label]``: a point [m] to mark and its label (the summary's peak)."""


RENDER_TIMEOUT_S = 120.0
"""Wall-time limit per picture for the rendering child process [s]."""


def render_stress_isolated(jobs: list[StressJob]) -> list[Picture | str]:
    """Render ``jobs`` with :func:`render_stress` in one child process; per job the
    :class:`Picture` or the reason it failed (the child's exception, or how the child died)."""
    results = render_isolated([{"kind": "stress", "args": asdict(j)} for j in jobs])
    return [r if isinstance(r, str) else
            Picture(png=Path(r["png"]), field=r["field"], time_s=r["time_s"], max_pa=r["max_pa"])
            for r in results]


def _stress_job(xdmf: str, png: str, time_s: float | None = None, title: str = "",
                mark: list | None = None, top_pa: float | None = None) -> dict:
    pic = render_stress(Path(xdmf), Path(png), time_s=time_s, title=title, mark=mark, top_pa=top_pa)
    return {"png": str(pic.png), "field": pic.field, "time_s": pic.time_s, "max_pa": pic.max_pa}


def _kinds() -> dict:
    """Job kinds the child process runs: name → function(**args) returning a JSON-able value."""
    from flexnet_fe.report.scenes import render_animation, render_missile_stress, render_net_events

    return {"stress": _stress_job, "missile": render_missile_stress,
            "net_events": render_net_events, "animation": render_animation,
            "net_panels": _net_panels_job}


def _net_panels_job(pvd: str, png: str, count: int = 6, title: str = "") -> list[float]:
    return render_net(Path(pvd), Path(png), count=count, title=title)


def render_isolated(jobs: list[dict]) -> list[dict | str | list | float]:
    """Run picture ``jobs`` (``{"kind": name in _kinds(), "args": {...}}``) in one child
    process; per job its JSON result or, as a string, why it failed (the child's error, or how
    the child died: a VTK crash ends the child, not the caller)."""
    if not jobs:
        return []
    import tempfile

    with tempfile.TemporaryDirectory(prefix="flexnet-render-") as tmp:
        job_file, out_file = Path(tmp) / "jobs.json", Path(tmp) / "results.json"
        job_file.write_text(json.dumps(jobs))
        package_root = str(Path(__file__).resolve().parents[2])  # so the child imports this flexnet_fe
        env = dict(os.environ, VTK_DEFAULT_OPENGL_WINDOW=os.environ.get("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow"),
                   PYVISTA_OFF_SCREEN=os.environ.get("PYVISTA_OFF_SCREEN", "true"),
                   PYTHONPATH=os.pathsep.join(p for p in (package_root, os.environ.get("PYTHONPATH")) if p))
        limit = RENDER_TIMEOUT_S * len(jobs)
        try:
            proc = subprocess.run([sys.executable, "-m", "flexnet_fe.report.pictures", str(job_file), str(out_file)],
                                  env=env, capture_output=True, text=True, timeout=limit)
            died = None
            if proc.returncode < 0:
                died = f"renderer process killed by {signal.Signals(-proc.returncode).name}"
            elif proc.returncode > 0:
                tail = (proc.stderr.strip().splitlines() or ["no message"])[-1]
                died = f"renderer process exited with code {proc.returncode}: {tail}"
        except subprocess.TimeoutExpired:
            died = f"renderer process timed out after {limit:.0f} s"
        done = json.loads(out_file.read_text()) if out_file.is_file() else []
    out: list = []
    for k in range(len(jobs)):
        if k < len(done):
            out.append(done[k]["error"] if "error" in done[k] else done[k]["ok"])
        else:
            out.append(died or "renderer process gave no result")
    return out


def _child(job_file: str, out_file: str) -> None:
    """Child entry: run each job, rewriting the results file after each one so the results
    of the jobs before a crash survive."""
    offscreen_env()
    import pyvista  # noqa: F401  (load VTK before anything else, see the module doc)

    kinds = _kinds()
    results = []
    for job in json.loads(Path(job_file).read_text()):
        try:
            results.append({"ok": kinds[job["kind"]](**job["args"])})
        except (FlexnetError, OSError, ValueError, KeyError) as err:
            results.append({"error": f"{type(err).__name__}: {err}" if not isinstance(err, FlexnetError) else str(err)})
        Path(out_file).write_text(json.dumps(results))


if __name__ == "__main__":
    _child(*sys.argv[1:3])
