"""Optional link shell → flight: damage fractions from the fins' peak stresses.

The shell stage writes, per fin, ``<shell_dir>/<fin>/envelope.xdmf`` (+ ``.h5``): the peak-over-
time von Mises stress of every cell (scalar DG0 field ``peak_von_mises_pa``). Here a cell whose
peak exceeds an allowable stress counts as lost aerodynamic area:

    f_fin = Σ_{cells: σ_vm,peak > σ_allow} A_cell / Σ_cells A_cell

    wing_damage          = mean of f over the missile's wings   (a wing the shell stage did not
    rudder_effectiveness = 1 − mean of f over its rudders        solve counts as undamaged)

Modelling assumption (not from the paper, which sets the damage by hand): the force and moment
derivatives a fin set contributes scale with its remaining (not overstressed) area.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from flexnet_fe.errors import FlexnetError

FIELD = "peak_von_mises_pa"
WING_PREFIX = "wing_"
RUDDER_PREFIX = "rudder_"


def cell_areas(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Areas [m²], shape (n,), of triangles (k = 3) or planar quadrilaterals in VTK/XDMF order
    (k = 4, split into (0, 1, 2) and (0, 2, 3)); points [m], shape (m, 2 or 3); cells (n, k)."""
    p = np.zeros((len(points), 3))
    p[:, : points.shape[1]] = points
    def tri(a, b, c):
        return 0.5 * np.linalg.norm(np.cross(p[b] - p[a], p[c] - p[a]), axis=1)
    if cells.shape[1] == 3:
        return tri(cells[:, 0], cells[:, 1], cells[:, 2])
    if cells.shape[1] == 4:
        return tri(cells[:, 0], cells[:, 1], cells[:, 2]) + tri(cells[:, 0], cells[:, 2], cells[:, 3])
    raise FlexnetError(f"cells with {cells.shape[1]} nodes: only triangles and quadrilaterals are supported")


def _h5_item(xdmf: Path, item: ET.Element) -> np.ndarray:
    file, _, dataset = item.text.strip().partition(":")
    with h5py.File(xdmf.parent / file, "r") as h5:
        return np.asarray(h5[dataset])


def read_cell_field(xdmf: Path, name: str = FIELD) -> tuple[np.ndarray, np.ndarray]:
    """(cell areas [m²] (n,), last written values of cell field ``name`` (n,)) from a dolfinx
    XDMF file with one mesh (serial layout, as the shell stage writes it)."""
    xdmf = Path(xdmf)
    if not xdmf.is_file():
        raise FlexnetError(f"{xdmf}: no such file (shell stage output)")
    root = ET.parse(xdmf).getroot()
    mesh = root.find(".//Grid[@GridType='Uniform']")
    cells = _h5_item(xdmf, mesh.find("Topology/DataItem")).astype(np.int64)
    points = _h5_item(xdmf, mesh.find("Geometry/DataItem"))
    attrs = [a for a in root.iter("Attribute") if a.get("Name") == name]
    if not attrs:
        raise FlexnetError(f"{xdmf}: no cell field '{name}'")
    if attrs[-1].get("Center") != "Cell":
        raise FlexnetError(f"{xdmf}: field '{name}' is not a cell field")
    values = _h5_item(xdmf, attrs[-1].find("DataItem")).reshape(-1)
    if len(values) != len(cells):
        raise FlexnetError(f"{xdmf}: {len(values)} values for {len(cells)} cells")
    return cell_areas(points, cells), values


def overstressed_fraction(areas: np.ndarray, peak: np.ndarray, allowable: float) -> float:
    """Share of the area [-] whose peak stress [Pa] exceeds ``allowable`` [Pa]."""
    return float(areas[peak > allowable].sum() / areas.sum())


@dataclass(frozen=True)
class ShellDamage:
    """Damage fractions derived from the shell stage."""

    per_fin: dict[str, float]
    """overstressed area share of each fin the shell stage solved [-]"""
    wing_damage: float
    rudder_effectiveness: float


def damage_from_shell(shell_dir: Path, allowable: float, n_wings: int = 4, n_rudders: int = 4) -> ShellDamage:
    """Damage of the flight stage from ``<shell_dir>/<fin>/envelope.xdmf`` (fins named
    ``wing_i`` / ``rudder_i`` as in ``flexnet_fe.missile``; cruciform sets of 4 by default)."""
    shell_dir = Path(shell_dir)
    per_fin = {}
    for env in sorted(shell_dir.glob("*/envelope.xdmf")):
        name = env.parent.name
        if not name.startswith((WING_PREFIX, RUDDER_PREFIX)):
            raise FlexnetError(f"{env}: fin '{name}' is neither a wing_ nor a rudder_")
        per_fin[name] = overstressed_fraction(*read_cell_field(env), allowable)
    if not per_fin:
        raise FlexnetError(f"{shell_dir}: no <fin>/envelope.xdmf from the shell stage")
    wings = [f for n, f in per_fin.items() if n.startswith(WING_PREFIX)]
    rudders = [f for n, f in per_fin.items() if n.startswith(RUDDER_PREFIX)]
    if len(wings) > n_wings or len(rudders) > n_rudders:
        raise FlexnetError(f"{shell_dir}: more fins ({len(wings)} wings, {len(rudders)} rudders) than "
                           f"the missile has ({n_wings}, {n_rudders})")
    return ShellDamage(per_fin, sum(wings) / n_wings, 1.0 - sum(rudders) / n_rudders)
