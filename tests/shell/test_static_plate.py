"""Clamped square plate under uniform load vs the thin-plate value, with the explicit solver's K."""

from __future__ import annotations

import numpy as np

from flexnet_fe.shell.forms import NDOF_NODE, ShellMaterial, Support
from flexnet_fe.shell.meshio import plate_mesh
from flexnet_fe.shell.model import build_model

from .conftest import A1, A2, ORIGIN, static_solve

# fenicsx-shells clamped demo data: E = 10920, ν = 0.3, t = 1e-3 (t/L = 1e-3), q = t³, unit square
MAT = ShellMaterial(thickness=1e-3, youngs_modulus=10920.0, poisson_ratio=0.3, density=1.0)
Q = MAT.thickness ** 3
ALL_CLAMPED = {g: Support.CLAMPED for g in ("root", "tip", "leading_edge", "trailing_edge")}
# Thin (Kirchhoff) plate, clamped square, centre deflection w = 0.00126532 q a⁴ / D
# (Timoshenko & Woinowsky-Krieger, Table 35). D = E t³ / (12 (1 − ν²)) = 1e-6 here, so
# w = 1.26532e-6. At t/L = 1e-3 the Reissner–Mindlin shear correction is O((t/L)²), negligible.
# Note: the issue quotes 1.285065e-6 from the fenicsx-shells demo; that number is 1.56 % above
# the thin-plate value it is said to equal, so we test against the closed form.
W_REF = 0.00126532 * Q * 1.0 ** 4 / MAT.bending_stiffness


def centre_deflection(n: int) -> float:
    fin = plate_mesh(n, n, 1.0, 1.0, origin=ORIGIN, a1=A1, a2=A2)
    m = build_model(fin, MAT, 1.0, supports=ALL_CLAMPED)
    nrm = fin.plane.n
    # uniform pressure q along +n: consistent nodal forces of a constant load = q × (row-sum of
    # the translational mass / ρt), i.e. ∫ N_i q dA
    area_weight = m.op.mass.reshape(-1, NDOF_NODE)[:, 0] / (MAT.density * MAT.thickness)
    f = np.zeros((len(area_weight), NDOF_NODE))
    f[:, :3] = Q * area_weight[:, None] * nrm[None, :]
    u = static_solve(m.op, f.ravel()).reshape(-1, NDOF_NODE)
    i = np.argmin(np.linalg.norm(m.op.x_nodes - (ORIGIN + 0.5 * A1 + 0.5 * A2), axis=1))
    return float(u[i, :3] @ nrm)


def test_clamped_plate_converges_to_thin_plate_value_without_locking():
    ns = np.array([8, 16, 32])
    err = np.array([abs(centre_deflection(n) / W_REF - 1.0) for n in ns])
    order = np.polyfit(np.log(1.0 / ns), np.log(err), 1)[0]  # err ∝ h^order
    print(f"errors {err}, observed order {order:.2f}")
    # Bilinear MITC4 deflections converge at O(h²); a locking element would stay far too stiff
    # (error of order 1 at t/L = 1e-3). The 32 × 32 error bound 0.2 % is ~3× the O(h²)
    # extrapolation from the coarser meshes (1.2 % at 8 × 8 → 0.07 %).
    assert err[-1] < 2e-3, err
    assert 1.8 < order < 2.3, (order, err)
