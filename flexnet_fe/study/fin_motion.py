"""The fins' normal displacement under a collision's loads, from the shell stage, sampled for the
collision kernel (``collide.model.FinMotion``; the one-way check, ``study.one_way``).

Each loaded fin is set up and run as the shell stage does (``shell.stage.setup_fin``, ``run_fin``:
same mesh, window, step and loads), with one addition: at every history sample (stride
``shell.history_interval``, set to the requested interval) the displacement's component along the
fin's normal n is taken at the nodes and interpolated onto a regular nu × nv grid over the fin's
contact polygon (root extension included: ``missile.shapes.pack_shapes``). The grid values are
linear on a Delaunay triangulation of the nodes' planform coordinates (exact for a linear field; the
shell's bilinear cells differ from it by O(h² w''), far below the 1–5 mm rope radius scale the
kernel reads it at), and a grid point outside the mesh (the root extension inside the body, the
rounded tip corners) takes its nearest node's value (≈ 0 at the clamped root). The samples are
then resampled linearly in time onto t0 + k·interval (t0: the fin's window start; the stage's
frames fall on steps, ≈ interval apart, plus each running peak's instant).
"""

from __future__ import annotations

import logging
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy import sparse
from scipy.spatial import Delaunay, cKDTree

from flexnet_fe.collide.model import FinMotion
from flexnet_fe.shell.forms import NDOF_NODE

LOG = logging.getLogger("flexnet.study.fin_motion")


def grid_of(poly: np.ndarray, nu: int, nv: int) -> np.ndarray:
    """(u0, du, v0, dv) [m] of an nu × nv grid whose corners are the bounding box of a fin's contact
    polygon ``poly`` (k, 2) [m] in its (u, v) planform frame."""
    (u0, v0), (u1, v1) = poly.min(axis=0), poly.max(axis=0)
    return np.array([u0, (u1 - u0) / (nu - 1), v0, (v1 - v0) / (nv - 1)])


def grid_points(grid: np.ndarray, nu: int, nv: int) -> np.ndarray:
    """(nu·nv, 2) [m] planform coordinates (u, v) of the grid points, point (i, j) at row i·nv + j."""
    u = grid[0] + grid[1] * np.arange(nu)
    v = grid[2] + grid[3] * np.arange(nv)
    return np.stack(np.meshgrid(u, v, indexing="ij"), axis=-1).reshape(-1, 2)


def interpolation(nodes_uv: np.ndarray, points_uv: np.ndarray) -> sparse.csr_matrix:
    """(m, n) matrix P with P @ f = the nodal values f (n,) at the points (m, 2) [m]: linear on the
    Delaunay triangulation of the nodes (n, 2) inside it, the nearest node's value outside."""
    tri = Delaunay(nodes_uv)
    simplex = tri.find_simplex(points_uv)
    inside = simplex >= 0
    rows, cols, vals = [], [], []
    t = tri.transform[simplex[inside]]
    b = np.einsum("kij,kj->ki", t[:, :2], points_uv[inside] - t[:, 2])
    bary = np.column_stack([b, 1.0 - b.sum(axis=1)])
    idx = np.flatnonzero(inside)
    rows.append(np.repeat(idx, 3))
    cols.append(tri.simplices[simplex[inside]].ravel())
    vals.append(bary.ravel())
    out = np.flatnonzero(~inside)
    if out.size:
        _, near = cKDTree(nodes_uv).query(points_uv[out])
        rows.append(out)
        cols.append(near)
        vals.append(np.ones(out.size))
    return sparse.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                             shape=(len(points_uv), len(nodes_uv)))


def resample(t: np.ndarray, w: np.ndarray, t0: float, interval: float) -> np.ndarray:
    """Samples w (k, m) at increasing times t (k,) [s], linear in time, at t0 + j·interval for
    every j with t0 + j·interval ≤ t[-1]: (nj, m)."""
    tj = t0 + interval * np.arange(int(np.floor((t[-1] - t0) / interval * (1 + 1e-12))) + 1)
    k = np.clip(np.searchsorted(t, tj, side="right") - 1, 0, len(t) - 2)
    c = np.clip((tj - t[k]) / (t[k + 1] - t[k]), 0.0, 1.0)[:, None]
    return (1.0 - c) * w[k] + c * w[k + 1]


class _Sampler:
    """Stands in for the stage's field writer: keeps (t, P @ (u · n)) at every frame."""

    def __init__(self, P: sparse.csr_matrix, normal: np.ndarray):
        self.P, self.normal = P, normal
        self.t: list[float] = []
        self.w: list[np.ndarray] = []

    def write(self, t: float, u_owned: np.ndarray) -> None:
        un = u_owned.reshape(-1, NDOF_NODE)[:, :3] @ self.normal
        if self.t and t <= self.t[-1]:  # (a running peak's frame repeats a step already taken)
            return
        self.t.append(t)
        self.w.append(self.P @ un)


def _fin_samples(job, shell, fin, poly, nu, nv, log):
    """(grid (4,), times (k,), w (k, nu·nv), RunResult) of one fin's run (``shell.stage.run_fin``)."""
    from flexnet_fe.progress import progress_bar
    from flexnet_fe.shell.stage import run_fin

    x = job.model.op.x_nodes - fin.origin
    off_plane = float(np.abs(x @ fin.n).max())
    if off_plane > 1e-9:
        raise ValueError(f"{fin.name}: shell nodes {off_plane:.3g} m off the fin's mid-plane")
    grid = grid_of(poly, nu, nv)
    sampler = _Sampler(interpolation(np.column_stack([x @ fin.e1, x @ fin.e2]), grid_points(grid, nu, nv)),
                       np.asarray(fin.n, dtype=float))
    ts = job.steps
    with progress_bar(ts.n_steps, f"fin motion {fin.name}") as bar:
        res = run_fin(replace(job, writer=sampler, steps=replace(ts, field_every=ts.every)), shell, bar, log)
    return grid, np.array(sampler.t), np.array(sampler.w), res


def fin_motion(case, collide_dir: Path, work_dir: Path, *, interval: float = 1e-6, nu: int = 41, nv: int = 41,
               log: logging.Logger = LOG) -> tuple[FinMotion, dict]:
    """(FinMotion of ``case``'s missile, {fin: (shell summary, history columns, missile fin)}) from
    the collision in ``collide_dir`` (``fin_contacts.npz``, ``history.csv``): every loaded fin run
    by the shell stage's functions under ``case.shell`` (its history every ``interval`` [s]),
    w sampled every ``interval`` on an nu × nv grid; unloaded fins rigid (nt = 0). Work files in
    ``work_dir``."""
    from mpi4py import MPI

    from flexnet_fe.io import read_history_csv
    from flexnet_fe.missile.build import build_missile
    from flexnet_fe.missile.shapes import pack_shapes
    from flexnet_fe.runs import FIN_CONTACTS, HISTORY
    from flexnet_fe.shell import stage as S

    missile = build_missile(case.missile)
    polys = pack_shapes(missile).fin_poly
    shell = case.shell.model_copy(update={"history_interval": interval, "peak_check": False,
                                          "strike_envelope": False})
    contacts = S.read_fin_contacts(Path(collide_dir) / FIN_CONTACTS)
    acc_t, acc = S.read_body_acceleration(Path(collide_dir) / HISTORY)
    end = S.stage_end_time(shell, contacts, acc_t)
    specs = S.select_fins(shell, S.fin_specs(missile.fins, _meshes(case, missile, work_dir)), contacts)
    nf = len(missile.fins)
    t0, nt, grids, ws, fins = np.zeros(nf), np.zeros(nf, np.int64), np.zeros((nf, 4)), [], {}
    for spec in specs:
        f = next(i for i, m in enumerate(missile.fins) if m.name == spec.name)
        job = S.setup_fin(shell, spec, contacts, acc_t, acc, work_dir, end, log, MPI.COMM_WORLD)
        grids[f], t, w, res = _fin_samples(job, shell, missile.fins[f], polys[f], nu, nv, log)
        t0[f] = t[0]
        samples = resample(t, w, t[0], interval)
        nt[f] = len(samples)
        ws.append((f, samples.reshape(-1, nu, nv)))
        fins[spec.name] = (S.finish_fin(job, res, shell), read_history_csv(job.out_dir / HISTORY), missile.fins[f])
    for f in range(nf):
        if nt[f] == 0:
            grids[f] = grid_of(polys[f], nu, nv)
    ws.sort(key=lambda p: p[0])
    w = np.concatenate([p[1] for p in ws]) if ws else np.zeros((0, nu, nv))
    return FinMotion(t0=t0, dt=float(interval), nt=nt, offset=np.concatenate([[0], np.cumsum(nt)]), grid=grids,
                     w=w), fins


def _meshes(case, missile, work_dir: Path) -> dict:
    """{fin: its Gmsh mesh path} of the missile's fins (``study.shell.fin_mesh``)."""
    from flexnet_fe.study.shell import fin_mesh

    return {f.name: fin_mesh(case.missile, f.name, Path(work_dir) / "meshes") for f in missile.fins}
