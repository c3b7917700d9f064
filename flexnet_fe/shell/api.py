"""Solve a fin or a plate under a given pressure or nodal-load history, outside the pipeline.

    from flexnet_fe.shell import api
    from flexnet_fe.shell.forms import ShellMaterial, Support

    mat = ShellMaterial(thickness=2e-3, youngs_modulus=70e9, poisson_ratio=0.3, density=2700.0)
    model = api.plate(40, 40, 0.2, 0.2, mat, supports=Support.SIMPLY_SUPPORTED)  # all 4 edges
    loads = api.pressure(model, times=[0, 2.5e-4, 5e-4], values=[0, 1e4, 0])    # [s], [Pa]
    res = api.solve(model, loads, end_time=2e-3)
    res.peak.value, res.peak.location, res.peak.error_estimate_rel, res.run.t, res.run.vm

A fin mesh from the missile mesher works the same way: ``api.fin(path, mat, supports=...)``.
Supports are :class:`~flexnet_fe.shell.forms.Support` (clamped, simply_supported (w = 0 only),
simply_supported_hard, pinned, free) per edge group ``root``, ``leading_edge``, ``tip``,
``trailing_edge`` (a single Support applies to all four). Loads act on the mid-surface; a
pressure is positive along the fin normal n.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import sparse
from scipy.sparse import linalg as sla

from flexnet_fe.shell.explicit import (Backend, LoadHistory, critical_step, max_eigenvalue,
                                       translational_mass)
from flexnet_fe.shell.forms import NDOF_NODE, ShellMaterial, Support
from flexnet_fe.shell.meshio import EDGE_GROUPS, load_fin_mesh, plate_mesh
from flexnet_fe.shell.model import ShellModel, build_model
from flexnet_fe.shell.recovery import Peak, locate_peak
from flexnet_fe.shell.solve import RunResult, recovery_for, run


def _supports(supports) -> dict[str, Support]:
    if isinstance(supports, (Support, str)):
        return {g: Support(supports) for g in EDGE_GROUPS}
    return {g: Support(s) for g, s in supports.items()}


def plate(nx: int, ny: int, lx: float, ly: float, material: ShellMaterial, *,
          supports=Support.SIMPLY_SUPPORTED, rotary_scale: float | str = "auto",
          origin=(0.0, 0.0, 0.0), a1=(1.0, 0.0, 0.0), a2=(0.0, 1.0, 0.0)) -> ShellModel:
    """A structured nx × ny quadrilateral plate lx × ly [m] (edges as in
    :func:`~flexnet_fe.shell.meshio.plate_mesh`) with its K and lumped M."""
    fin = plate_mesh(nx, ny, lx, ly, origin=origin, a1=a1, a2=a2)
    return build_model(fin, material, rotary_scale, supports=_supports(supports))


def fin(path: Path, material: ShellMaterial, *, supports=None,
        rotary_scale: float | str = "auto") -> ShellModel:
    """A fin from a Gmsh ``.msh`` file (default support: clamped root, other edges free)."""
    sup = {"root": Support.CLAMPED} if supports is None else _supports(supports)
    return build_model(load_fin_mesh(Path(path)), material, rotary_scale, supports=sup)


def area_weights(model: ShellModel) -> np.ndarray:
    """∫ N_i dA per owned node (n_nodes,) [m²] (the row sums of the consistent P1 mass / ρt,
    before any mass scaling)."""
    return model.node_area


def _history(model, times, nodal_columns) -> LoadHistory:
    times = np.asarray(times, dtype=float)
    if times.ndim != 1 or len(times) < 1 or np.any(np.diff(times) <= 0):
        raise ValueError("times must be a 1-D increasing array [s]")
    return LoadHistory(times=times, nodal=sparse.csc_matrix(nodal_columns),
                       accel_times=np.zeros(0), accel=np.zeros((0, 3)),
                       mass_c=translational_mass(model.op))


def pressure(model: ShellModel, times, values) -> LoadHistory:
    """Uniform pressure p(t) [Pa] along +n, linear between samples (times [s], values [Pa]),
    zero outside them: consistent nodal forces f_i = p ∫ N_i dA n."""
    values = np.asarray(values, dtype=float)
    f = np.zeros((model.op.n_owned // NDOF_NODE, NDOF_NODE))
    f[:, :3] = area_weights(model)[:, None] * model.fin.plane.n[None, :]
    return _history(model, times, np.outer(f.ravel(), values))


def patch(model: ShellModel, centre, size: tuple[float, float], times, forces, *,
          points: int = 64) -> LoadHistory:
    """Total force F(t) [N] along +n spread uniformly over a rectangle ``size`` = (along e1,
    along e2) [m] centred at ``centre`` [m] (serial): consistent nodal forces by a points ×
    points midpoint rule over the patch (exact as points → ∞; error O((h/points)²))."""
    from flexnet_fe.shell.transfer import FinGeometry, locate_in_cells

    pl = model.fin.plane
    g = (np.arange(points) + 0.5) / points - 0.5
    s1, s2 = np.meshgrid(g * size[0], g * size[1], indexing="ij")
    pts = (np.asarray(centre, float)[None] + s1.reshape(-1, 1) * pl.e1
           + s2.reshape(-1, 1) * pl.e2)
    fg = FinGeometry(mesh=model.V.mesh, V=model.V, origin=pl.origin, e1=pl.e1, e2=pl.e2, n=pl.n)
    f = locate_in_cells(fg, pts, np.full(len(pts), 1.0 / len(pts)), pl.n)
    return _history(model, times, np.outer(f, np.asarray(forces, dtype=float)))


def nodal(model: ShellModel, times, columns) -> LoadHistory:
    """Nodal forces/moments [N | N m] on the owned DOFs at the sample times, shape
    (n_owned·5, nt) (frame B for forces; θ1, θ2 moments in the fin basis)."""
    return _history(model, times, columns)


@dataclass(frozen=True)
class Result:
    run: RunResult
    peak: Peak | None
    """located peak of the recovered von Mises (serial)"""
    dt: float
    dt_crit: float


def solve(model: ShellModel, loads: LoadHistory, end_time: float, *, safety: float = 0.9,
          sample_interval: float | None = None, backend: Backend = Backend.AUTO,
          dt: float | None = None) -> Result:
    """Explicit run to ``end_time`` [s] at dt = safety × dt_crit (or the given ``dt``), stresses
    sampled every ``sample_interval`` [s] (default: every step)."""
    lam, _ = max_eigenvalue(model.op)
    dt_crit = critical_step(lam)
    dt = safety * dt_crit if dt is None else dt
    n = max(1, math.ceil(end_time / dt - 1e-9))
    every = 1 if sample_interval is None else max(1, round(sample_interval / dt))
    R = recovery_for(model)
    res = run(model, loads, R, dt=dt, n_steps=n, sample_every=every,
              frame_every=every * max(1, n // every + 1), backend=backend)
    pk = None
    if model.V.mesh.comm.size == 1 and res.peak_node >= 0:
        pk = locate_peak(R, res.u_peak, res.peak_node, model.V.tabulate_dof_coordinates(),
                         model.fin.plane.origin)
    return Result(run=res, peak=pk, dt=dt, dt_crit=dt_crit)


def static(model: ShellModel, f: np.ndarray) -> np.ndarray:
    """K u = f on the free DOFs (serial, direct solve); u (n_owned·5,) [m | rad]. Simple
    supports (w = 0) are imposed by eliminating w in the fin's local frame."""
    from flexnet_fe.shell.solve import LocalFrame

    op = model.op
    K = op.K
    ai, aj, av = K.getValuesCSR()
    K = sparse.csr_matrix((av, aj, ai), shape=K.getSize())
    lf = LocalFrame(model.fin.plane)
    T = sparse.kron(sparse.identity(op.n_owned // NDOF_NODE), sparse.csr_matrix(lf.T)).tocsr()
    Kl = (T @ K @ T.T).tocsr()
    free = op.minv > 0
    free.reshape(-1, NDOF_NODE)[:, 2] &= op.wfix == 0
    u = np.zeros(op.n_owned)
    fl = lf.to_local(np.asarray(f, float))
    u[free] = sla.spsolve(Kl[free][:, free].tocsc(), fl[free])
    return lf.to_body(u)
