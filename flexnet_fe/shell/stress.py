"""Surface stresses of the flat shell (membrane + bending) at cell centres.

σ(z) = C (ε + z κ) (plane stress) at z = +t/2 (top, +n side), 0 (middle), −t/2 (bottom);
von Mises σ_vm = √(σ11² + σ22² − σ11σ22 + 3σ12²) and maximum principal
σ_1 = (σ11+σ22)/2 + √(((σ11−σ22)/2)² + σ12²). Transverse shear stress is not included (it is
zero at the surfaces where the bending stress peaks).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ufl
from dolfinx import fem

from flexnet_fe.shell.forms import form_constants, kinematics, plane_stress
from flexnet_fe.shell.model import ShellModel

SURFACES = ("top", "mid", "bottom")
MEASURES = ("von_mises", "max_principal")
FIELD_NAMES = tuple(f"{m}_{s}_pa" for m in MEASURES for s in SURFACES)
"""Names of the 6 scalar stress fields, in the column order of :meth:`StressEvaluator.evaluate`."""


def von_mises(s):
    """Plane-stress von Mises stress of a 2×2 UFL stress [Pa]."""
    return ufl.sqrt(s[0, 0] ** 2 + s[1, 1] ** 2 - s[0, 0] * s[1, 1] + 3.0 * s[0, 1] ** 2)


def max_principal(s):
    """Largest principal value of a 2×2 UFL stress [Pa]."""
    return 0.5 * (s[0, 0] + s[1, 1]) + ufl.sqrt(0.25 * (s[0, 0] - s[1, 1]) ** 2 + s[0, 1] ** 2)


@dataclass(frozen=True)
class StressEvaluator:
    """Evaluates the 6 stress measures of the current shell field at all local cells."""

    U: fem.Function
    """the shell field the solver copies its state into"""
    S: fem.Function
    """DG0 vector function with 6 components (FIELD_NAMES order)"""
    expr: fem.Expression
    midpoints: np.ndarray
    """cell-centre coordinates of the S blocks [m] in frame B, shape (n_local_cells, 3)"""
    n_owned_cells: int

    def evaluate(self, u_owned: np.ndarray) -> np.ndarray:
        """Stresses for owned DOF values ``u_owned``; returns (n_owned_cells, 6) [Pa]."""
        n = u_owned.size
        self.U.x.array[:n] = u_owned
        self.U.x.scatter_forward()
        self.S.interpolate(self.expr)
        return self.S.x.array.reshape(-1, len(FIELD_NAMES))[: self.n_owned_cells]


def stress_evaluator(model: ShellModel) -> StressEvaluator:
    mesh = model.V.mesh
    U = fem.Function(model.V)
    c = form_constants(mesh, model.fin.plane, model.material)
    k = kinematics(U, c)
    comps = []
    for meas in (von_mises, max_principal):
        for z in (0.5, 0.0, -0.5):  # top, mid, bottom: z = ±t/2, 0
            comps.append(meas(plane_stress(k.membrane + z * c.thickness * k.curvature, c)))
    S0 = fem.VectorFunctionSpace(mesh, ("DG", 0), dim=len(FIELD_NAMES))
    S = fem.Function(S0)
    expr = fem.Expression(ufl.as_vector(comps), S0.element.interpolation_points())
    n_owned = S0.dofmap.index_map.size_local
    mid = S0.tabulate_dof_coordinates()[:n_owned]
    return StressEvaluator(U=U, S=S, expr=expr, midpoints=mid, n_owned_cells=n_owned)
