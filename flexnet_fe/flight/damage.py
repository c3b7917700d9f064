"""Link shell → flight: the damage law, fin stress → share of each fin's aerodynamic area lost.

The shell stage writes, per fin, ``<shell_dir>/<fin>/envelope.xdmf`` (+ ``.h5``): the peak-over-
time von Mises stress of every cell (scalar DG0 field ``peak_von_mises_pa``), and in the run's
``summary.json`` (section ``shell``, per fin) the fin allowable ``allowable_pa`` — the fin
material's yield strength σ_y (``[missile.material]``, its one home). A cell is lost by the law of
``[flight.damage_law]`` (``flexnet_fe.flight.config.DamageLaw``):

    overstressed_area:  σ_vm,peak > k σ_y
    failure_strain:     ε(σ_vm,peak) > ε_f,  ε(σ) = σ/E (σ ≤ σ_y),  σ²/(E σ_y) (σ > σ_y)

The second is Neuber's rule (H. Neuber, J. Appl. Mech. 28, 1961: σ ε = σ_e²/E at a notch) for an
elastic–perfectly-plastic material: the linear-elastic shell peak σ_e stands for the strain
energy density the real, yielding fin must absorb. Assumptions, stated: (1) the shell solution is
linear elastic, so σ_e is the elastic peak, not the real stress; (2) a cell past ε_f breaks off
and its area stops lifting; a cell that yields without breaking keeps its lift (its permanent set
is not modelled); (3) a fin's lift, carry-over and roll damping scale with its remaining area
(``flexnet_fe.flight.airframe.damaged``), its centre of pressure stays.

    f_fin = Σ_{lost cells} A_cell / Σ_cells A_cell,   remaining_fin = 1 − f_fin

A fin the shell stage did not solve counts as undamaged.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexnet_fe.errors import FlexnetError
from flexnet_fe.flight.config import DamageLaw, DamageLawConfig
from flexnet_fe.io import read_json
from flexnet_fe.xdmf import list_fields, nearest_time_index, read_field, read_mesh
from flexnet_fe.runs import ENVELOPE_XDMF, SUMMARY

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


def read_cell_field(xdmf: Path, name: str = FIELD) -> tuple[np.ndarray, np.ndarray]:
    """(cell areas [m²] (n,), last written values of cell field ``name`` (n,)) from a dolfinx
    XDMF file with one mesh (serial layout, as the shell stage writes it), read with the
    package's one XDMF reader (``flexnet_fe.xdmf``, also used by the report)."""
    xdmf = Path(xdmf)
    if not xdmf.is_file():
        raise FlexnetError(f"{xdmf}: no such file (shell stage output)")
    mesh = read_mesh(xdmf)
    field = list_fields(xdmf).get(name)
    if field is None:
        raise FlexnetError(f"{xdmf}: no cell field '{name}'")
    if field.center != "Cell":
        raise FlexnetError(f"{xdmf}: field '{name}' is not a cell field")
    values = read_field(xdmf, field, nearest_time_index(field.times, None)).reshape(-1)
    if len(values) != len(mesh.cells):
        raise FlexnetError(f"{xdmf}: {len(values)} values for {len(mesh.cells)} cells")
    return cell_areas(mesh.points, mesh.cells), values


def neuber_strain(stress: np.ndarray, youngs_modulus: float, yield_strength: float) -> np.ndarray:
    """Elastic–perfectly-plastic strain [-] of a linear-elastic stress σ_e [Pa] by Neuber's rule:
    σ_e/E below yield, σ_e²/(E σ_y) above (continuous at σ_y)."""
    s = np.asarray(stress, dtype=float)
    return np.where(s <= yield_strength, s / youngs_modulus, s * s / (youngs_modulus * yield_strength))


def lost_cells(peak: np.ndarray, law: DamageLawConfig, allowable: float, youngs_modulus: float) -> np.ndarray:
    """Boolean mask of the cells the damage law removes (peak von Mises [Pa], shape (n,))."""
    if law.law is DamageLaw.overstressed_area:
        return peak > law.threshold_factor * allowable
    if law.law is DamageLaw.failure_strain:
        return neuber_strain(peak, youngs_modulus, allowable) > law.failure_strain
    raise ValueError(f"unknown damage law {law.law!r}")


@dataclass(frozen=True)
class FinDamage:
    """Remaining share of each fin's lift [-], shape (8,), order wing_1..4, rudder_1..4."""

    remaining: np.ndarray
    NAMES = tuple(f"wing_{i}" for i in range(1, 5)) + tuple(f"rudder_{i}" for i in range(1, 5))

    @classmethod
    def uniform(cls, wing_damage: float, rudder_effectiveness: float) -> "FinDamage":
        return cls(np.array([1.0 - wing_damage] * 4 + [rudder_effectiveness] * 4))

    @property
    def wing_damage(self) -> float:
        """mean share of wing lift lost [-]"""
        return float(1.0 - self.remaining[:4].mean())

    @property
    def rudder_effectiveness(self) -> float:
        """mean share of rudder kept [-]"""
        return float(self.remaining[4:].mean())


def shell_allowables(shell_dir: Path) -> dict[str, float]:
    """Per fin ``allowable_pa`` from the run's summary.json (section ``shell``), where present."""
    path = Path(shell_dir).parent / SUMMARY
    if not path.is_file():
        return {}
    shell = read_json(path).get("shell", {})
    return {k: float(v["allowable_pa"]) for k, v in shell.items() if isinstance(v, dict) and "allowable_pa" in v}


def damage_from_shell(shell_dir: Path, law: DamageLawConfig, material) -> tuple[FinDamage, dict]:
    """(FinDamage, summary of the link) from ``<shell_dir>/<fin>/envelope.xdmf``. The allowable is
    the shell summary's ``allowable_pa`` of the fin, or — for a shell stage that does not write it
    — the fin material's yield strength (``material``: ``flexnet_fe.missile.config.FinMaterial``,
    also the source of E)."""
    shell_dir = Path(shell_dir)
    allow = shell_allowables(shell_dir)
    lost, used = {}, {}
    for env in sorted(shell_dir.glob(f"*/{ENVELOPE_XDMF}")):
        name = env.parent.name
        if name not in FinDamage.NAMES:
            raise FlexnetError(f"{env}: fin '{name}' is not one of {', '.join(FinDamage.NAMES)}")
        used[name] = allow.get(name, material.yield_strength)
        areas, peak = read_cell_field(env)
        lost[name] = float(areas[lost_cells(peak, law, used[name], material.youngs_modulus)].sum() / areas.sum())
    if not lost:
        raise FlexnetError(f"{shell_dir}: no <fin>/envelope.xdmf from the shell stage")
    rem = np.array([1.0 - lost.get(n, 0.0) for n in FinDamage.NAMES])
    link = {"law": law.law.value, "threshold_factor": law.threshold_factor, "failure_strain": law.failure_strain,
            "allowable_pa": used, "allowable_from": "shell summary" if allow else "fin material (shell summary has none)",
            "lost_area_fraction": lost, "remaining": dict(zip(FinDamage.NAMES, map(float, rem)))}
    return FinDamage(rem), link
