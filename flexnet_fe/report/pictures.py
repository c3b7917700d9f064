"""Offscreen PyVista pictures of the stages' field files (no display needed).

``render_stress`` draws one fin's DG0 stress field from the shell stage's XDMF (written by
dolfinx: a ``mesh`` grid plus one temporal collection per scalar field, cell-centred) seen
normal to the fin plane; ``render_net`` draws net snapshots from a ``.pvd`` collection of line
meshes (deploy / collide stages). XDMF files are read with :mod:`flexnet_fe.report.xdmf`
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
    the last) with :mod:`flexnet_fe.report.xdmf`.

    Returns ``(pyvista grid, {name: cell values (n_cells,)}, time shown [s])``. Only scalar
    cell fields at that same time are returned. Raises :class:`FlexnetError` when the file (or
    its .h5) cannot be read or holds no scalar cell field.
    """
    offscreen_env()
    import pyvista as pv

    from flexnet_fe.report.xdmf import list_fields, nearest_time_index, read_field, read_mesh

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


def render_stress(xdmf: Path, png: Path, *, time_s: float | None = None, field: str | None = None,
                  title: str = "", window: tuple[int, int] = (900, 700)) -> Picture:
    """Draw a fin's von Mises stress [MPa] (or the named cell ``field``) from ``xdmf`` at the
    output time nearest ``time_s`` into ``png``, seen normal to the fin plane, undeformed mesh
    with its element edges. Coordinates are those of the file (frame B for the shell stage)."""
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
    mesh.cell_data[bar] = values * (PA_TO_MPA if bar == "stress [MPa]" else 1.0)
    normal = plane_normal(np.asarray(mesh.points))
    png = Path(png)
    png.parent.mkdir(parents=True, exist_ok=True)
    pl = pv.Plotter(off_screen=True, window_size=list(window))
    try:
        pl.add_mesh(mesh, scalars=bar, cmap="turbo", show_edges=True, edge_color="gray",
                    scalar_bar_args={"title": bar, "vertical": True, "fmt": "%.4g"})
        centre = np.asarray(mesh.center)
        size = float(np.linalg.norm(np.ptp(np.asarray(mesh.points), axis=0))) or 1.0
        up = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        pl.camera_position = [tuple(centre + 2.0 * size * normal), tuple(centre), tuple(up)]
        pl.reset_camera()
        heading = title or xdmf.name
        # the envelope's single time value is a placeholder, not an instant
        time_txt = "" if math.isnan(t) or label == ENVELOPE_FIELD else f", t = {t * 1e3:.4g} ms"
        pl.add_text(f"{heading}\n{label}{time_txt}\nmax {values.max() * PA_TO_MPA:.4g} MPa",
                    font_size=10, position="upper_left")
        pl.add_axes()
        pl.screenshot(str(png))
    finally:
        pl.close()
    return Picture(png=png, field=label, time_s=t, max_pa=float(values.max()))


def pvd_entries(pvd: Path) -> list[tuple[float, Path]]:
    """(time [s], data file) of every dataset of a ParaView ``.pvd`` collection, by time."""
    import xml.etree.ElementTree as ET

    pvd = Path(pvd)
    try:
        root = ET.parse(pvd).getroot()
    except (OSError, ET.ParseError) as err:
        raise FlexnetError(f"{pvd}: cannot read the collection ({err})") from None
    out = [(float(ds.get("timestep", "nan")), pvd.parent / ds.get("file", ""))
           for ds in root.iter("DataSet")]
    return sorted(out, key=lambda e: e[0])


def render_net(pvd: Path, png: Path, *, count: int = 6, scalars: str | None = "tension_n",
               title: str = "", window: tuple[int, int] = (1400, 800)) -> list[float]:
    """Draw ``count`` snapshots (evenly spread over the collection) of a net ``.pvd`` side by side
    into ``png``, seen along the world z axis (flight direction, frame W), all at the same scale
    (one shared camera) and colour range; colours = the cell array ``scalars`` if every snapshot
    has it. Returns the snapshot times shown [s]."""
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
    pts = np.vstack([np.asarray(m.points) for _, m in meshes])
    bounds = [v for lo, hi in zip(pts.min(axis=0), pts.max(axis=0)) for v in (lo, hi)]
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
                            scalar_bar_args={"title": scalars, "fmt": "%.3g"})
            else:
                pl.add_mesh(mesh, color="black", line_width=1.5)
            pl.add_text(f"{title} t = {t * 1e3:.4g} ms".strip(), font_size=9)
        pl.link_views()
        pl.view_xy()
        pl.reset_camera(bounds=bounds)
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


RENDER_TIMEOUT_S = 120.0
"""Wall-time limit per picture for the rendering child process [s]."""


def render_stress_isolated(jobs: list[StressJob]) -> list[Picture | str]:
    """Render ``jobs`` with :func:`render_stress` in one child process; per job the
    :class:`Picture` or the reason it failed (the child's exception, or how the child died)."""
    if not jobs:
        return []
    import tempfile

    with tempfile.TemporaryDirectory(prefix="flexnet-render-") as tmp:
        job_file, out_file = Path(tmp) / "jobs.json", Path(tmp) / "results.json"
        job_file.write_text(json.dumps([asdict(j) for j in jobs]))
        package_root = str(Path(__file__).resolve().parents[2])  # so the child imports this flexnet_fe
        env = dict(os.environ, VTK_DEFAULT_OPENGL_WINDOW=os.environ.get("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow"),
                   PYVISTA_OFF_SCREEN=os.environ.get("PYVISTA_OFF_SCREEN", "true"),
                   PYTHONPATH=os.pathsep.join(p for p in (package_root, os.environ.get("PYTHONPATH")) if p))
        try:
            proc = subprocess.run([sys.executable, "-m", "flexnet_fe.report.pictures", str(job_file), str(out_file)],
                                  env=env, capture_output=True, text=True, timeout=RENDER_TIMEOUT_S * len(jobs))
            died = None
            if proc.returncode < 0:
                died = f"renderer process killed by {signal.Signals(-proc.returncode).name}"
            elif proc.returncode > 0:
                tail = (proc.stderr.strip().splitlines() or ["no message"])[-1]
                died = f"renderer process exited with code {proc.returncode}: {tail}"
        except subprocess.TimeoutExpired:
            died = f"renderer process timed out after {RENDER_TIMEOUT_S * len(jobs):.0f} s"
        done = json.loads(out_file.read_text()) if out_file.is_file() else []
    out: list[Picture | str] = []
    for k, job in enumerate(jobs):
        if k < len(done):
            r = done[k]
            out.append(r["error"] if "error" in r else
                       Picture(png=Path(r["png"]), field=r["field"], time_s=r["time_s"], max_pa=r["max_pa"]))
        else:
            out.append(died or "renderer process gave no result")
    return out


def _child(job_file: str, out_file: str) -> None:
    """Child entry: render each job, rewriting the results file after each one so the results
    of the jobs before a crash survive."""
    offscreen_env()
    import pyvista  # noqa: F401  (load VTK before anything else, see the module doc)

    results = []
    for job in json.loads(Path(job_file).read_text()):
        try:
            pic = render_stress(Path(job["xdmf"]), Path(job["png"]), time_s=job["time_s"], title=job["title"])
            results.append({"png": str(pic.png), "field": pic.field, "time_s": pic.time_s, "max_pa": pic.max_pa})
        except FlexnetError as err:
            results.append({"error": str(err)})
        Path(out_file).write_text(json.dumps(results))


if __name__ == "__main__":
    _child(*sys.argv[1:3])
