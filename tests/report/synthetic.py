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
FLIGHT_ERROR = "NumericalError: dt 2e-4 s exceeds dt_crit 1e-4 s (6-DOF integrator)"

SUMMARY = {
    "deploy": {"max_area_m2": 101.25, "time_to_max_area_s": 0.3125, "period_s": None,
               "max_tension_n": 4321.0, "steps": 120000,
               "air": {"on": False, "density_kgpm3": 0.5258}},
    "collide": {"peak_accel_mps2": 12345.6, "peak_accel_axis_mps2": [-12000.0, 150.0, -2900.0],
                "passed_through": True, "dv_over_v": 0.0123, "momentum_error_rel": 2.5e-9},
    "shell": {"wing_1": {"peak_von_mises_pa": float(ENVELOPE_VM_PA.max()), "peak_time_s": 1.5e-3,
                         "peak_location_m": [-0.85, 0.1, 0.25],
                         "peak_max_principal_pa": float(ENVELOPE_P1_PA.max()), "dofs": 54},
              "dt_s": 1.0e-7, "dt_crit_s": 1.25e-7, "dofs": 54, "steps": 15000},
    # a section for a stage whose status is "failed" (e.g. left over): it must NOT be shown
    "flight": {"miss_distance_m": 987.654, "hit": False},
}


def fin_mesh():
    """A 2x2 quadrilateral fin in the plane y_b = 0.1 m (x_b chord, z_b span), gdim 3."""
    import ufl
    from dolfinx import mesh as dmesh
    from mpi4py import MPI

    xs, zs = np.linspace(-1.0, -0.8, 3), np.linspace(0.1, 0.3, 3)
    x = np.array([[a, 0.1, c] for c in zs for a in xs])
    cells = np.array([[j * 3 + i, j * 3 + i + 1, (j + 1) * 3 + i, (j + 1) * 3 + i + 1]
                      for j in range(2) for i in range(2)], dtype=np.int64)
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.Cell("quadrilateral", geometric_dimension=3), 1))
    return dmesh.create_mesh(MPI.COMM_SELF, cells, x, domain)


def write_cell_xdmf(path: Path, series: dict[str, list[tuple[float, np.ndarray]]]) -> None:
    """Write scalar DG0 fields the way the shell stage does (mesh once, then append-and-close
    per output time): ``series = {name: [(t [s], cell values (4,)), ...]}``."""
    from dolfinx import fem
    from dolfinx.io import XDMFFile
    from mpi4py import MPI

    msh = fin_mesh()
    V0 = fem.FunctionSpace(msh, ("DG", 0))
    # Cell order of the DG0 dofs = cell order of the input (serial, no reordering of 4 quads is
    # not guaranteed): place each value by its cell midpoint instead.
    mid = V0.tabulate_dof_coordinates()
    ref = np.array([[-0.95, 0.1, 0.15], [-0.85, 0.1, 0.15], [-0.95, 0.1, 0.25], [-0.85, 0.1, 0.25]])
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
    fin = run / "shell" / "wing_1"
    fin.mkdir(parents=True)
    ts = np.linspace(0.0, 3e-3, 7)
    write_history_csv(fin / "history.csv", {"t_s": ts, "max_von_mises_pa": 123.456e6 * np.sin(np.pi * ts / 3e-3)})
    if xdmf:
        write_cell_xdmf(fin / "envelope.xdmf", {"peak_von_mises_pa": [(0.0, ENVELOPE_VM_PA)],
                                                "peak_max_principal_pa": [(0.0, ENVELOPE_P1_PA)]})
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
