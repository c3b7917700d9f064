"""A fin's shell model: function space, material, K and lumped M (what never changes)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from dolfinx import fem

from flexnet_fe.shell.explicit import ShellOperator, assemble_operator
from flexnet_fe.shell.forms import (NDOF_NODE, NORMAL_FIXED, ShellMaterial, Support, edge_blocks,
                                   edge_dofs, shell_space, stiffness_forms)
from flexnet_fe.shell.mass import (auto_rotary_scale, lumped_mass, min_edge_length,
                                  selective_mass_scaling)
from flexnet_fe.shell.meshio import FinMesh


@dataclass(frozen=True)
class ShellModel:
    fin: FinMesh
    V: fem.FunctionSpace
    """blocked P1 space, 5 DOFs per node"""
    material: ShellMaterial
    rotary_scale: float
    """rotary-inertia factor s actually used [-]"""
    h_min: float
    """shortest element edge [m]"""
    op: ShellOperator
    node_area: np.ndarray
    """∫ N_i dA per owned node (n_nodes,) [m²]: the unscaled translational lumped mass / ρt
    (pressure loads; the mass itself may carry the selective scaling's added mass)"""
    mass_scaling: dict
    """what the selective mass scaling did (:func:`~flexnet_fe.shell.mass.selective_mass_scaling`,
    with its ``ratio``)"""


def build_model(fin: FinMesh, material: ShellMaterial, rotary_scale: float | str = "auto", *,
                supports: dict[str, Support] | None = None, mass_scaling: float = 1.0) -> ShellModel:
    """Assemble K (once) and the lumped mass of a fin. ``supports``: edge group → support
    (default: the ``root`` clamped to the missile body). ``rotary_scale``: a factor >= 1 or
    ``"auto"`` (:func:`~flexnet_fe.shell.mass.auto_rotary_scale`). ``mass_scaling``: the step
    ratio of :func:`~flexnet_fe.shell.mass.selective_mass_scaling` (1: none)."""
    supports = {"root": Support.CLAMPED} if supports is None else supports
    V = shell_space(fin.mesh)
    h = min_edge_length(fin.mesh)
    if rotary_scale == "auto":
        s = auto_rotary_scale(h, material)
    elif isinstance(rotary_scale, (int, float)) and rotary_scale >= 1.0:
        s = float(rotary_scale)
    else:
        raise ValueError(f"rotary_scale must be 'auto' or a number >= 1, got {rotary_scale!r}")
    unknown = [g for g in supports if g not in fin.edge_tags]
    if unknown:
        raise ValueError(f"fin mesh has no edge group(s) {unknown}; has {sorted(fin.edge_tags)}")
    supports = {g: Support(sup) for g, sup in supports.items()}
    fixed = [edge_dofs(V, fin.facet_tags, fin.edge_tags[g], sup, fin.plane)
             for g, sup in supports.items()]
    cl = np.unique(np.concatenate(fixed)) if fixed else np.zeros(0, dtype=np.int64)
    wfix = [edge_blocks(V, fin.facet_tags, fin.edge_tags[g]) for g, sup in supports.items()
            if sup in NORMAL_FIXED]
    wfix = np.unique(np.concatenate(wfix)) if wfix else np.zeros(0, dtype=np.int64)
    m = lumped_mass(V, material, s)
    area = m.getArray(readonly=True)[0:V.dofmap.index_map.size_local * NDOF_NODE:NDOF_NODE] / (
        material.density * material.thickness)
    scaled = {"ratio": float(mass_scaling), **selective_mass_scaling(V, m, mass_scaling)}
    op = assemble_operator(stiffness_forms(V, fin.plane, material), V, m, cl,
                           normal_fixed=wfix, normal=fin.plane.n)
    return ShellModel(fin=fin, V=V, material=material, rotary_scale=s, h_min=h, op=op,
                      node_area=area.copy(), mass_scaling=scaled)
