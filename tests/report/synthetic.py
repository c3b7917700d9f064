"""Synthetic run directories (DESIGN.md §3 contract) for the report tests, written into tmp_path."""

from __future__ import annotations

import os
from html.parser import HTMLParser
from pathlib import Path

import numpy as np

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

from flexnet_fe.io import atomic_write_json, write_history_csv  # noqa: E402

YIELD_PA = 503e6
# wing_1 envelope: one value per cell of the 2x2 quad fin; the largest is the summary peak.
ENVELOPE_VM_PA = np.array([10e6, 50e6, 123.456e6, 80e6])
ENVELOPE_P1_PA = np.array([12e6, 55e6, 130.0e6, 85e6])
RUDDER_VM_PA = np.array([450e6, 100e6, 200e6, 300e6])
RUDDER_ALLOWABLE_PA = 400e6
"""rudder_2 carries its own allowable_pa in the summary (wing_1 falls back to the yield strength)."""
FORCED_WARNING = "forced <warning> of the synthetic collide stage"
FIELD_TIMES_S = (0.0, 1.0e-3, 2.0e-3)
"""Output times of the synthetic fins' fields.xdmf [s]."""
DISP_RATE = 2.0
"""Synthetic displacement u = (0, 0, DISP_RATE · t · (x + 1)) [m] (t [s], x [m])."""
FLIGHT_ERROR = "NumericalError: dt 2e-4 s exceeds dt_crit 1e-4 s (6-DOF integrator)"

SUMMARY = {
    "deploy": {"max_area_m2": 101.25, "time_to_max_area_s": 0.3125, "period_s": None,
               "max_tension_n": 4321.0, "steps": 120000,
               "air": {"on": False, "density_kgpm3": 0.5258}},
    "collide": {"peak_accel_mps2": 12345.6, "peak_accel_axis_mps2": [-12000.0, 150.0, -2900.0],
                "peak_accel_time_s": 1.0e-3,
                "passed_through": True, "dv_over_v": 0.0123, "momentum_error_rel": 2.5e-9,
                "energy_error_rel": 0.2, "tunnelling": True, "segment_crossings_unresolved": 7,
                "fin_impulse_ns": {"wing_1": 1.5, "rudder_1": 0.25},
                "warnings": [FORCED_WARNING]},
    "shell": {"wing_1": {"peak_von_mises_pa": float(ENVELOPE_VM_PA.max()), "peak_time_s": 1.5e-3,
                         "peak_location_m": [-0.85, 0.1, 0.25],
                         "peak_max_principal_pa": float(ENVELOPE_P1_PA.max()), "dofs": 54,
                         "peak_error_estimate_rel": 0.03},
              "rudder_2": {"peak_von_mises_pa": float(RUDDER_VM_PA.max()), "peak_time_s": 2.0e-3,
                           "peak_location_m": [-1.95, 0.1, 0.15], "peak_max_principal_pa": float(1.1 * RUDDER_VM_PA.max()),
                           "allowable_pa": RUDDER_ALLOWABLE_PA, "peak_error_estimate_rel": 0.2},
              "dt_s": 1.0e-7, "dt_crit_s": 1.25e-7, "dofs": 54, "steps": 15000},
    # a section for a stage whose status is "failed" (e.g. left over): it must NOT be shown
    "flight": {"miss_distance_m": 987.654, "hit": False},
}


def fin_mesh(dx: float = 0.0):
    """A 2x2 quadrilateral fin in the plane y_b = 0.1 m (x_b chord from -1 + dx to -0.8 + dx,
    z_b span 0.1 to 0.3), gdim 3."""
    import ufl
    from dolfinx import mesh as dmesh
    from mpi4py import MPI

    xs, zs = np.linspace(-1.0, -0.8, 3) + dx, np.linspace(0.1, 0.3, 3)
    x = np.array([[a, 0.1, c] for c in zs for a in xs])
    cells = np.array([[j * 3 + i, j * 3 + i + 1, (j + 1) * 3 + i, (j + 1) * 3 + i + 1]
                      for j in range(2) for i in range(2)], dtype=np.int64)
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.Cell("quadrilateral", geometric_dimension=3), 1))
    return dmesh.create_mesh(MPI.COMM_SELF, cells, x, domain)


def write_cell_xdmf(path: Path, series: dict[str, list[tuple[float, np.ndarray]]], *, dx: float = 0.0,
                    displacement: bool = False) -> None:
    """Write scalar DG0 fields the way the shell stage does (mesh once, then append-and-close
    per output time): ``series = {name: [(t [s], cell values (4,)), ...]}``; with
    ``displacement`` also the CG1 vector ``displacement_m`` = (0, 0, DISP_RATE t (x + 1)) at
    each time."""
    from dolfinx import fem
    from dolfinx.io import XDMFFile
    from mpi4py import MPI

    msh = fin_mesh(dx)
    V0 = fem.FunctionSpace(msh, ("DG", 0))
    V1 = fem.VectorFunctionSpace(msh, ("Lagrange", 1))
    # Cell order of the DG0 dofs = cell order of the input (serial, no reordering of 4 quads is
    # not guaranteed): place each value by its cell midpoint instead.
    mid = V0.tabulate_dof_coordinates()
    ref = np.array([[-0.95, 0.1, 0.15], [-0.85, 0.1, 0.15], [-0.95, 0.1, 0.25], [-0.85, 0.1, 0.25]])
    ref[:, 0] += dx
    order = [int(np.argmin(np.linalg.norm(ref - m, axis=1))) for m in mid]
    with XDMFFile(MPI.COMM_SELF, str(path), "w") as f:
        f.write_mesh(msh)
    times = sorted({t for s in series.values() for t, _ in s})
    for t in times:
        with XDMFFile(MPI.COMM_SELF, str(path), "a") as f:
            for name, s in series.items():
                for ts, values in s:
                    if ts == t:
                        fn = fem.Function(V0, name=name)
                        fn.x.array[:] = np.asarray(values)[order]
                        f.write_function(fn, t)
            if displacement:
                u = fem.Function(V1, name="displacement_m")
                u.interpolate(lambda x, t=t: np.vstack([0 * x[0], 0 * x[0], DISP_RATE * t * (x[0] + 1.0)]))
                f.write_function(u, t)


SURFACE_FIELDS = tuple(f"{m}_{s}_pa" for m in ("von_mises", "max_principal") for s in ("top", "mid", "bottom"))


def fin_field_series(peak_vm: np.ndarray) -> dict:
    """Six surface fields at FIELD_TIMES_S: von Mises top = peak_vm · t / t_last, the other
    surfaces half of it (so the max over surfaces is the top), principal = 1.1 × von Mises."""
    out = {}
    for name in SURFACE_FIELDS:
        f = (1.0 if "top" in name else 0.5) * (1.1 if name.startswith("max_principal") else 1.0)
        out[name] = [(t, f * peak_vm * t / FIELD_TIMES_S[-1]) for t in FIELD_TIMES_S]
    return out


def write_body_msh(path: Path, radius: float = 0.1, length: float = 2.2, n: int = 8) -> None:
    """A gmsh 2.2 ASCII file of a triangulated open cylinder about the x axis (x from -length
    to 0): the stand-in of the missile mesher's body.msh."""
    ang = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    pts = [(x, radius * np.cos(a), radius * np.sin(a)) for x in (0.0, -length) for a in ang]
    tris = []
    for j in range(n):
        a, b, c, d = j, (j + 1) % n, n + (j + 1) % n, n + j
        tris += [(a, b, c), (a, c, d)]
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$Nodes", str(len(pts))]
    lines += [f"{k + 1} {x!r} {y!r} {z!r}" for k, (x, y, z) in enumerate(pts)]
    lines += ["$EndNodes", "$Elements", str(len(tris))]
    lines += [f"{k + 1} 2 2 1 1 {a + 1} {b + 1} {c + 1}" for k, (a, b, c) in enumerate(tris)]
    lines += ["$EndElements", ""]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines))


def write_lines_pvd(folder: Path, name: str, frames: list[tuple[float, np.ndarray, np.ndarray]],
                    tension: bool) -> None:
    """``folder/<name>.pvd`` + ``snapshots/<name>_k.vtu`` line meshes: frames of
    (t [s], points [m] (n, 3), lines (m, 2)); cell data ``tension_n`` = line index if ``tension``."""
    import pyvista as pv

    (folder / "snapshots").mkdir(parents=True, exist_ok=True)
    rows = []
    for k, (t, x, lines) in enumerate(frames):
        cells = np.hstack([np.full((len(lines), 1), 2), lines]).ravel()
        grid = pv.UnstructuredGrid(cells, np.full(len(lines), pv.CellType.LINE, dtype=np.uint8), x.astype(float))
        if tension:
            grid.cell_data["tension_n"] = np.arange(len(lines), dtype=float)
        grid.save(str(folder / "snapshots" / f"{name}_{k:04d}.vtu"))
        rows.append(f'<DataSet timestep="{t!r}" part="0" file="snapshots/{name}_{k:04d}.vtu"/>')
    (folder / f"{name}.pvd").write_text('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
                                        "<Collection>\n" + "\n".join(rows) + "\n</Collection>\n</VTKFile>\n")


def grid_net(z: float, half: float = 1.0, n: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """A flat n × n node net in the plane z (world), side 2·half [m]: (points, lines)."""
    g = np.linspace(-half, half, n)
    x = np.array([[a, b, z] for b in g for a in g])
    lines = [(j * n + i, j * n + i + 1) for j in range(n) for i in range(n - 1)]
    lines += [(j * n + i, (j + 1) * n + i) for j in range(n - 1) for i in range(n)]
    return x, np.array(lines)


COLLIDE_T_S = np.linspace(0.0, 2e-3, 9)
"""Synthetic collide history times [s]; contact from the 3rd to the 7th sample."""


def write_collide_files(stage: Path) -> None:
    """collide/history.csv (acceleration, attitude, contacts, energy terms with a stage balance)
    and net.pvd / missile.pvd (4 frames: the missile (a segment along +z) passes a flat net)."""
    t = COLLIDE_T_S
    contacts = np.where((np.arange(len(t)) >= 2) & (np.arange(len(t)) <= 6), 3.0, 0.0)
    ke = 100.0 - 20.0 * t / t[-1]
    write_history_csv(stage / "history.csv", {
        "t_s": t, "accel_mag_mps2": 1e4 * contacts / 3.0, "pitch_change_rad": 3e-5 * t / t[-1],
        "yaw_change_rad": -1e-5 * t / t[-1], "contacts": contacts,
        "net_kinetic_j": ke, "net_elastic_j": 15.0 * t / t[-1], "dissipated_j": 5.0 * t / t[-1],
        "energy_error_j": np.zeros_like(t)})
    frames_net, frames_mis = [], []
    for k, tk in enumerate(np.linspace(0.0, 2e-3, 4)):
        frames_net.append((tk, *grid_net(0.0)))
        apex = -0.5 + 1.0 * k
        frames_mis.append((tk, np.array([[0.0, 0.0, apex], [0.0, 0.0, apex - 1.0], [0.1, 0.0, apex - 0.8]]),
                           np.array([[0, 1], [1, 2]])))
    write_lines_pvd(stage, "net", frames_net, tension=True)
    write_lines_pvd(stage, "missile", frames_mis, tension=False)


def tiny_png(path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(2, 1.5))
    ax.plot([0, 1], [0, 1])
    fig.savefig(path, dpi=40)
    plt.close(fig)


def make_run(run: Path, *, xdmf: bool = True, missile: bool = True) -> Path:
    """A complete synthetic run: deploy, collide, shell done; flight failed."""
    run.mkdir(parents=True, exist_ok=True)
    case = {"case": {"name": "synthetic_case", "description": "synthetic run <for> the report tests",
                     "stages": ["deploy", "collide", "shell", "flight"]},
            "atmosphere": {"altitude": 8000.0},
            "net": {"kind": "traction", "rope_diameter": 0.004}}
    if missile:
        case["missile"] = {"preset": "radar", "name": "radar",
                           "material": {"name": "Al 7075-T6", "yield_strength": YIELD_PA}}
    atomic_write_json(run / "resolved.json", {"case": case, "case_hash": "h123", "versions": {"flexnet_fe": "0.1.0"}})
    atomic_write_json(run / "status.json", {"case": "synthetic_case", "case_hash": "h123", "stages": {
        "deploy": {"state": "done", "wall_s": 12.5}, "collide": {"state": "done", "wall_s": 30.0},
        "shell": {"state": "done", "wall_s": 100.0},
        "flight": {"state": "failed", "error": FLIGHT_ERROR, "wall_s": 1.0}}})
    atomic_write_json(run / "summary.json", SUMMARY)
    t = np.linspace(0.0, 1.0, 11)
    write_history_csv(run / "deploy" / "history.csv", {"t_s": t, "area_m2": 25.0 + 76.25 * t})
    tiny_png(run / "deploy" / "deploy.png")
    tiny_png(run / "collide" / "collide_accel.png")
    (run / "flight").mkdir()
    (run / "flight" / "log.txt").write_text("INFO start\nERROR stage flight failed: " + FLIGHT_ERROR + "\n")
    write_collide_files(run / "collide")
    shell = run / "shell"
    for name, dx, env_vm, env_p1 in (("wing_1", 0.0, ENVELOPE_VM_PA, ENVELOPE_P1_PA),
                                     ("rudder_2", -1.0, RUDDER_VM_PA, 1.1 * RUDDER_VM_PA)):
        fin = shell / name
        fin.mkdir(parents=True)
        ts = np.linspace(0.0, 3e-3, 7)
        write_history_csv(fin / "history.csv", {
            "t_s": ts, "max_von_mises_pa": env_vm.max() * np.sin(np.pi * ts / 3e-3),
            "max_principal_pa": env_p1.max() * np.sin(np.pi * ts / 3e-3),
            "kinetic_energy_j": 2.0 * ts / 3e-3, "strain_energy_j": 1.0 * ts / 3e-3, "external_work_j": 3.0 * ts / 3e-3})
        if xdmf:
            write_cell_xdmf(fin / "envelope.xdmf", {"peak_von_mises_pa": [(0.0, env_vm)],
                                                    "peak_max_principal_pa": [(0.0, env_p1)]}, dx=dx)
            write_cell_xdmf(fin / "fields.xdmf", fin_field_series(env_vm), dx=dx, displacement=True)
    if xdmf:
        write_body_msh(shell / "meshes" / "body.msh")
    return run


class TreeChecker(HTMLParser):
    """Checks that every opened element is closed in order (void elements excepted) and
    collects the text of each table cell, row by row, per table id."""

    VOID = {"meta", "img", "br", "hr", "link", "input"}

    def __init__(self):
        super().__init__()
        self.stack: list[str] = []
        self.errors: list[str] = []
        self.tables: dict[str, list[list[str]]] = {}
        self._table: list[str] = []
        self._cell: list[str] | None = None
        self.images: list[str] = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.images.append(a.get("src", ""))
        if tag in self.VOID:
            return
        self.stack.append(tag)
        if tag == "table":
            key = a.get("id") or f"_{len(self.tables)}"
            self._table.append(key)
            self.tables[key] = []
        elif tag == "tr" and self._table:
            self.tables[self._table[-1]].append([])
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag):
        if tag in self.VOID:
            return
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes <{self.stack[-1] if self.stack else None}>")
            return
        self.stack.pop()
        if tag == "table":
            self._table.pop()
        elif tag in ("td", "th") and self._cell is not None and self._table:
            self.tables[self._table[-1]][-1].append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def parse_html(text: str) -> TreeChecker:
    p = TreeChecker()
    p.feed(text)
    p.close()
    assert not p.errors, p.errors
    assert p.stack == [], f"unclosed elements: {p.stack}"
    return p
