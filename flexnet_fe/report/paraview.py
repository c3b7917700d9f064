"""One missile file for ParaView (issue 12 item 3), built from the shell stage's per-fin files.

Writes into ``out_dir`` (``run_dir/report_files/paraview/``):

``missile.xdmf`` + ``missile.h5``
    One temporal collection; at each time one spatial collection with one block per fin
    (``wing_1`` ...) and ``body``, all in the missile body frame B [m]. Every fin block holds,
    on the same block, the point field ``displacement_m`` (3 components, [m]) and the cell
    fields ``von_mises_pa`` / ``max_principal_pa`` (maximum over the top, mid and bottom
    surfaces) and the six surface fields ``von_mises_{top,mid,bottom}_pa``,
    ``max_principal_{top,mid,bottom}_pa`` [Pa] (stable names: those the shell stage writes,
    plus the two maxima). The body is the static surface ``shell/meshes/body.msh`` with a zero
    ``displacement_m`` (the missile is rigid in B) and no stress fields.
``missile_envelope.xdmf`` (same ``.h5`` layout, own file ``missile_envelope.h5``)
    The peak over time per cell (``peak_von_mises_pa``, ``peak_max_principal_pa``) of every fin
    (from ``shell/<fin>/envelope.xdmf``) plus the body; no time.
``missile_times.csv``
    Each merged output time [s] and, per fin, the time of the fin's own output shown there
    (fins run with their own stable step, so their output times drift apart by a few µs per
    output; :func:`merge_outputs` groups them into frames).
``open_missile.py``
    A ``pvpython`` / ``paraview --script`` script that opens ``missile.xdmf`` coloured by
    ``von_mises_pa`` (range 0 … envelope maximum), warped by the displacement, at the time of
    the largest peak.

Read back with ``pyvista.XdmfReader`` in the tests (VTK's XDMF-2 reader, the one ParaView
calls "XDMF Reader"). Data is copied, not linked: the file stays valid if the shell folders move.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexnet_fe.errors import FlexnetError
from flexnet_fe.xdmf import list_fields, nearest_time_index, read_field, read_mesh
from flexnet_fe.runs import BODY_MSH, ENVELOPE_XDMF, FIELDS_XDMF, SHELL_MESHES

MERGE_FRACTION = 0.5
"""Output times of different fins closer than this fraction of the smallest median output
interval are one merged frame (so no fin is shown more than half an interval away)."""

DISPLACEMENT = "displacement_m"
SURFACE_STRESS = tuple(f"{m}_{s}_pa" for m in ("von_mises", "max_principal") for s in ("top", "mid", "bottom"))
"""The per-surface DG0 stress fields [Pa] a fin file may hold; every ``*_pa`` field of the fin's
file is carried over (today's shell stage writes von Mises per surface as DG0 and recovered nodal
values as CG1 ``*_nodal_pa``)."""
MAX_FIELDS = {"von_mises_pa": "von_mises_", "max_principal_pa": "max_principal_"}
"""Cell maxima over the surfaces added to each fin block: name → prefix of the surface fields."""
ENVELOPE_FIELDS = ("peak_von_mises_pa", "peak_max_principal_pa")

XDMF_CELL = {"Triangle": "Triangle", "Quadrilateral": "Quadrilateral"}


@dataclass(frozen=True)
class Part:
    """One block: points [m] (n, 3), cells (m, k) 0-based, XDMF topology type."""

    name: str
    points: np.ndarray
    cells: np.ndarray
    cell_type: str


@dataclass(frozen=True)
class MissileFiles:
    """What :func:`write_missile_files` wrote (paths) and what it holds."""

    xdmf: Path
    envelope: Path | None
    script: Path
    times_csv: Path
    times_s: tuple[float, ...]
    parts: tuple[str, ...]
    peak_time_s: float | None


def read_body(msh: Path) -> Part:
    """The body surface from the missile mesher's ``body.msh`` (gmsh file, frame B [m])."""
    from flexnet_fe.msh import read_msh_nodes_and_cells

    if not Path(msh).is_file():
        raise FlexnetError(f"{msh}: no such file (the body surface mesh)")
    x, cells = read_msh_nodes_and_cells(Path(msh))
    tri = [c for name, c in cells.items() if name.startswith("Triangle")]
    quad = [c for name, c in cells.items() if name.startswith("Quadrilateral")]
    if tri and not quad:
        return Part("body", x, np.vstack(tri), "Triangle")
    if quad and not tri:
        return Part("body", x, np.vstack(quad), "Quadrilateral")
    # mixed: split quads into triangles (one topology per block)
    split = [q[:, [0, 1, 2]] for q in quad] + [q[:, [0, 2, 3]] for q in quad]
    return Part("body", x, np.vstack(tri + split), "Triangle")


def merge_outputs(per_fin: dict[str, tuple[float, ...]]) -> list[tuple[float, dict[str, int]]]:
    """Group the fins' output times [s] into merged frames: walking the union in time order, a
    time joins the current group when it lies within MERGE_FRACTION × the smallest typical
    (median) output interval of the group's first time AND its fin has no output in the group
    yet (a fin's own frames, e.g. its peak-time frame, are never merged away). Returns
    ``[(group time = its earliest time, {fin: output index of every fin})]``; a fin without an
    output in a group shows its output nearest to the group time."""
    medians = [float(np.median(np.diff(sorted(t)))) for t in per_fin.values() if len(t) > 1]
    tol = MERGE_FRACTION * min((m for m in medians if m > 0), default=0.0)
    events = sorted((float(t), name, k) for name, ts in per_fin.items() for k, t in enumerate(ts))
    groups: list[tuple[float, dict[str, int]]] = []
    for t, name, k in events:
        if groups and t - groups[-1][0] <= tol and name not in groups[-1][1]:
            groups[-1][1][name] = k
        else:
            groups.append((t, {name: k}))
    for t, members in groups:
        for name, ts in per_fin.items():
            if name not in members:
                members[name] = int(np.argmin(np.abs(np.asarray(ts) - t)))
    return groups


class _H5:
    """Datasets written to one .h5 and referenced from the XDMF text."""

    def __init__(self, path: Path):
        import h5py

        self.path = path
        self.f = h5py.File(path, "w")

    def item(self, key: str, data: np.ndarray) -> str:
        data = np.ascontiguousarray(data)
        if key not in self.f:
            self.f.create_dataset(key, data=data)
        kind = "Int" if np.issubdtype(data.dtype, np.integer) else "Float"
        prec = data.dtype.itemsize
        dims = " ".join(str(d) for d in data.shape)
        return (f'<DataItem Dimensions="{dims}" NumberType="{kind}" Precision="{prec}" Format="HDF">'
                f"{self.path.name}:/{key}</DataItem>")

    def close(self):
        self.f.close()


def _grid(h5: _H5, part: Part, attributes: list[tuple[str, str, np.ndarray]]) -> str:
    """A Uniform grid of ``part`` with its attributes (name, 'Node'|'Cell', values)."""
    lines = [f'<Grid Name="{part.name}" GridType="Uniform">',
             f'<Topology TopologyType="{XDMF_CELL[part.cell_type]}" NumberOfElements="{len(part.cells)}">',
             h5.item(f"mesh/{part.name}/cells", part.cells.astype(np.int64)), "</Topology>",
             '<Geometry GeometryType="XYZ">', h5.item(f"mesh/{part.name}/points", part.points), "</Geometry>"]
    for name, center, values, key in attributes:
        kind = "Vector" if values.ndim == 2 else "Scalar"
        lines += [f'<Attribute Name="{name}" AttributeType="{kind}" Center="{center}">',
                  h5.item(key, values.astype(np.float64)), "</Attribute>"]
    lines.append("</Grid>")
    return "\n".join(lines)


def _document(body: str) -> str:
    return ('<?xml version="1.0"?>\n<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>\n'
            '<Xdmf Version="2.0" xmlns:xi="http://www.w3.org/2001/XInclude">\n<Domain>\n'
            f"{body}\n</Domain>\n</Xdmf>\n")


@dataclass(frozen=True)
class _Fin:
    part: Part
    fields: dict          # name → XdmfField
    times: tuple[float, ...]
    path: Path


def _stress_fields(fields: dict) -> tuple[str, ...]:
    """The fin file's stress fields [Pa] (``*_pa``, cell or node centred) in a stable order."""
    return tuple(sorted(n for n in fields if n.endswith("_pa")))


def _read_fin(path: Path, name: str) -> _Fin:
    mesh = read_mesh(path)
    fields = list_fields(path)
    vm_cells = [n for n in _stress_fields(fields) if n.startswith("von_mises_") and fields[n].center == "Cell"]
    if DISPLACEMENT not in fields or not vm_cells:
        raise FlexnetError(f"{path}: needs {DISPLACEMENT} and at least one cell field von_mises_*_pa "
                           f"(has {', '.join(sorted(fields)) or 'none'})")
    return _Fin(Part(name, mesh.points, mesh.cells, mesh.cell_type), fields,
                fields[vm_cells[0]].times, path)


def _fin_attributes(fin: _Fin, index: int, key: str) -> list:
    """The fin block's fields at its output ``index`` (see the module doc): displacement, every
    stress field of the fin's file with its own centring, and the cell maxima over the surfaces
    (``MAX_FIELDS``) of the fields present."""
    att = []
    values = {}
    stress = _stress_fields(fin.fields)
    for name in (DISPLACEMENT, *stress):
        f = fin.fields[name]
        k = f.times.index(fin.times[index]) if fin.times[index] in f.times else nearest_time_index(f.times, fin.times[index])
        values[name] = read_field(fin.path, f, k)
    att.append((DISPLACEMENT, "Node", values[DISPLACEMENT], f"{key}/{DISPLACEMENT}"))
    for name, prefix in MAX_FIELDS.items():
        surf = [n for n in stress if n.startswith(prefix) and fin.fields[n].center == "Cell"]
        if surf:
            att.append((name, "Cell", np.max([values[n] for n in surf], axis=0), f"{key}/{name}"))
    att += [(n, fin.fields[n].center, values[n], f"{key}/{n}") for n in stress]
    return att


def write_missile_files(shell_dir: Path, fins: list[str], out_dir: Path, notes: list[str],
                        peak_time_s: float | None = None) -> MissileFiles:
    """Write the files of the module doc from ``shell_dir/<fin>/fields.xdmf`` (+ envelope) and
    ``shell_dir/meshes/body.msh``. A fin whose files cannot be read, or a missing body mesh, is
    a note and is left out; no readable fin at all is a :class:`FlexnetError`."""
    shell_dir, out_dir = Path(shell_dir), Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    read: list[_Fin] = []
    for name in fins:
        try:
            read.append(_read_fin(shell_dir / name / FIELDS_XDMF, name))
        except FlexnetError as err:
            notes.append(f"ParaView missile file: fin {name} left out ({err})")
    if not read:
        raise FlexnetError(f"{shell_dir}: no fin fields.xdmf readable: no missile file")
    try:
        body = read_body(shell_dir / SHELL_MESHES / BODY_MSH)
    except (FlexnetError, ValueError, OSError) as err:
        notes.append(f"ParaView missile file: no body ({err})")
        body = None
    groups = merge_outputs({f.part.name: f.times for f in read})
    times = [t for t, _ in groups]
    xdmf = out_dir / "missile.xdmf"
    h5 = _H5(out_dir / "missile.h5")
    chosen: dict[str, list[float]] = {f.part.name: [] for f in read}
    try:
        grids = []
        for k, (t, members) in enumerate(groups):
            blocks = []
            for fin in read:
                i = members[fin.part.name]
                chosen[fin.part.name].append(fin.times[i])
                blocks.append(_grid(h5, fin.part, _fin_attributes(fin, i, f"data/{fin.part.name}/{i}")))
            if body is not None:
                blocks.append(_grid(h5, body, [(DISPLACEMENT, "Node", np.zeros_like(body.points),
                                                f"data/body/{DISPLACEMENT}")]))
            grids.append(f'<Grid Name="missile_{k}" GridType="Collection" CollectionType="Spatial">\n'
                         f'<Time Value="{t!r}"/>\n' + "\n".join(blocks) + "\n</Grid>")
        xdmf.write_text(_document('<Grid Name="missile" GridType="Collection" CollectionType="Temporal">\n'
                                  + "\n".join(grids) + "\n</Grid>"))
    finally:
        h5.close()
    times_csv = out_dir / "missile_times.csv"
    with open(times_csv, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t_s"] + [f"{n}_output_t_s" for n in chosen])
        for k, t in enumerate(times):
            w.writerow([repr(t)] + [repr(chosen[n][k]) for n in chosen])
    envelope, vmax = _write_envelope(shell_dir, read, body, out_dir, notes)
    script = write_paraview_script(out_dir, vmax, peak_time_s)
    return MissileFiles(xdmf, envelope, script, times_csv, tuple(times),
                        tuple([f.part.name for f in read] + (["body"] if body is not None else [])), peak_time_s)


def _write_envelope(shell_dir: Path, fins: list[_Fin], body: Part | None, out_dir: Path,
                    notes: list[str]) -> tuple[Path | None, float]:
    """``missile_envelope.xdmf``; returns (path or None, largest peak von Mises [Pa])."""
    blocks_data = []
    for fin in fins:
        path = shell_dir / fin.part.name / ENVELOPE_XDMF
        try:
            mesh, fields = read_mesh(path), list_fields(path)
            values = {n: read_field(path, fields[n], 0) for n in ENVELOPE_FIELDS}
        except (FlexnetError, KeyError) as err:
            notes.append(f"ParaView envelope file: fin {fin.part.name} left out ({err})")
            continue
        blocks_data.append((Part(fin.part.name, mesh.points, mesh.cells, mesh.cell_type), values))
    if not blocks_data:
        return None, 0.0
    path = out_dir / "missile_envelope.xdmf"
    h5 = _H5(out_dir / "missile_envelope.h5")
    try:
        blocks = [_grid(h5, part, [(n, "Cell", v, f"data/{part.name}/{n}") for n, v in vals.items()])
                  for part, vals in blocks_data]
        if body is not None:
            blocks.append(_grid(h5, body, []))
        # one placeholder time (0) so that readers which need a time step (pyvista) accept it
        path.write_text(_document('<Grid Name="missile_envelope" GridType="Collection" CollectionType="Spatial">\n'
                                  '<Time Value="0.0"/>\n' + "\n".join(blocks) + "\n</Grid>"))
    finally:
        h5.close()
    return path, max(float(np.max(v["peak_von_mises_pa"], initial=0.0)) for _, v in blocks_data)


SCRIPT = '''"""Open the missile's stress field in ParaView (written by flexnet_fe's report builder).

    paraview --script={name}        (GUI)
    pvpython {name} [out.png]      (no GUI: saves a picture, default missile_von_mises.png)

Colours: cell von Mises stress [Pa], maximum over the top, mid and bottom surfaces
(von_mises_pa), range 0 ... {vmax:.6g} Pa (the envelope maximum); fins warped by the
displacement x {warp:g}; time set to the largest peak ({peak}). Frame: missile body frame B [m].
"""
import os
import sys

import paraview
from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetAnimationScene, GetColorTransferFunction,
                             Render, SaveScreenshot, Show, Text, WarpByVector, XDMFReader)

HERE = os.path.dirname(os.path.abspath(__file__))
reader = XDMFReader(registrationName="missile", FileNames=[os.path.join(HERE, "missile.xdmf")])
warp = WarpByVector(registrationName="deformed x{warp:g}", Input=reader)
warp.Vectors = ["POINTS", "displacement_m"]
warp.ScaleFactor = {warp!r}
view = GetActiveViewOrCreate("RenderView")
display = Show(warp, view)
ColorBy(display, ("CELLS", "von_mises_pa"))
lut = GetColorTransferFunction("von_mises_pa")
lut.ApplyPreset("Turbo", True)
lut.RescaleTransferFunction(0.0, {vmax!r})
display.SetScalarBarVisibility(view, True)
scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
{set_time}
# oblique view from above (the horizontal fins face-on, the vertical ones at an angle), z up
x0, x1, y0, y1, z0, z1 = warp.GetDataInformation().GetBounds()
centre = [(x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2]
size = max(x1 - x0, y1 - y0, z1 - z0)
view.CameraFocalPoint = centre
view.CameraPosition = [centre[0] + 0.6 * size, centre[1] - 0.6 * size, centre[2] + 1.3 * size]
view.CameraViewUp = [0.0, 0.0, 1.0]
view.ResetCamera()
label = Text(registrationName="label")
label.Text = "von Mises stress [Pa], max over top/mid/bottom; {peak}; displacement x{warp:g}; frame B [m]"
label_display = Show(label, view)
label_display.FontSize = 10
label_display.WindowLocation = "Upper Left Corner"
Render(view)
if not getattr(paraview, "fromGUI", False):  # pvpython / pvbatch: save a picture
    SaveScreenshot(sys.argv[1] if len(sys.argv) > 1 else "missile_von_mises.png", view,
                   ImageResolution=[1600, 900])
'''

WARP_SCALE = 50.0
"""Displacement magnification in the ParaView script (fin deflections are a few mm on a
metre-sized missile)."""


def write_paraview_script(out_dir: Path, vmax_pa: float, peak_time_s: float | None) -> Path:
    """``open_missile.py`` (see the module doc); colour range 0 … ``vmax_pa`` [Pa]."""
    set_time = (f"scene.AnimationTime = {peak_time_s!r}" if peak_time_s is not None
                else "scene.GoToLast()")
    text = SCRIPT.format(name="open_missile.py", vmax=vmax_pa, warp=WARP_SCALE,
                         peak=f"t = {peak_time_s:.6g} s" if peak_time_s is not None else "last output",
                         set_time=set_time)
    path = out_dir / "open_missile.py"
    path.write_text(text)
    return path
