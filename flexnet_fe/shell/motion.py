"""The fins' normal displacement under a collision's loads, from the shell stage, sampled for the
collision kernel (``collide.model.FinMotion``): the staggered fin coupling (``shell.coupling``)
and the one-way check (``study.one_way``).

Each loaded fin is set up and run as the shell stage does (``shell.stage.setup_fin``, ``run_fin``:
same mesh, window, step and loads), with one addition: at every history sample (stride
``shell.history_interval``, set to the requested interval) the displacement's component along the
fin's normal n is taken at the nodes and interpolated onto a regular nu × nv grid over the fin's
contact polygon (root extension included: ``missile.shapes.pack_shapes``). The grid values are
the shell's own bilinear field (the cell each point lies in, located and pulled back as the load
transfer does: ``shell.transfer``), and a grid point outside the mesh (the root extension inside
the body, the rounded tip corners) takes its nearest node's value (≈ 0 at the clamped root). The samples are
then resampled linearly in time onto t0 + k·interval (t0: the fin's window start; the stage's
frames fall on steps, ≈ interval apart, plus each running peak's instant).
"""

from __future__ import annotations

import logging
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy import sparse
from scipy.spatial import cKDTree

from flexnet_fe.collide.model import FinMotion
from flexnet_fe.shell.forms import NDOF_NODE

LOG = logging.getLogger("flexnet.shell.motion")


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


def grid_interpolation(fg, points: np.ndarray) -> sparse.csr_matrix:
    """(m, n_nodes) matrix P mapping nodal values of a fin's P1 shell space (``fg``:
    :class:`shell.transfer.FinGeometry`; nodes = its DOF blocks, serial) to the points (m, 3) [m] in B
    (their normal part dropped): the bilinear field of the cell a point lies in (the load transfer's
    point location and pull-back, ``shell.transfer``), else the value of the in-plane nearest node."""
    from flexnet_fe.shell.recovery import shape_q1
    from flexnet_fe.shell.transfer import _in_plane, _locate, cell_grid

    p2 = _in_plane(fg, points)
    cell, X, mine, _ = _locate(fg, cell_grid(fg), p2)
    blocks = fg.V.dofmap.list.array.reshape(-1, 4)
    xn = fg.V.tabulate_dof_coordinates()
    rows_in, out = np.flatnonzero(mine), np.flatnonzero(~mine)
    near = cKDTree(_in_plane(fg, xn)).query(p2[out])[1] if len(out) else np.zeros(0, np.int64)
    rows = np.concatenate([np.repeat(rows_in, 4), out])
    cols = np.concatenate([blocks[cell[rows_in]].ravel(), near])
    vals = np.concatenate([shape_q1(X[rows_in, 0], X[rows_in, 1]).ravel(), np.ones(len(out))])
    return sparse.csr_matrix((vals, (rows, cols)), shape=(len(points), len(xn)))


def resample(t: np.ndarray, w: np.ndarray, interval: float) -> np.ndarray:
    """Samples w (k, m) at increasing times t (k,) [s], linear in time, at t[0] + j·interval for
    every j with t[0] + j·interval ≤ t[-1]: (nj, m)."""
    t0 = t[0]
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
        if self.t and t <= self.t[-1]:  # (a running peak's frame repeats a step already taken)
            return
        self.t.append(t)
        self.w.append(self.P @ (u_owned.reshape(-1, NDOF_NODE)[:, :3] @ self.normal))


def _fin_samples(job, shell, fin, grid, nu, nv, log):
    """(times (k,), w (k, nu·nv), RunResult) of one fin's run (``shell.stage.run_fin``) on its grid
    (``grid_of``)."""
    from flexnet_fe.progress import progress_bar
    from flexnet_fe.shell.stage import run_fin
    from flexnet_fe.shell.transfer import FinGeometry

    pl = job.model.fin.plane
    fg = FinGeometry(mesh=job.model.V.mesh, V=job.model.V, origin=pl.origin, e1=pl.e1, e2=pl.e2, n=pl.n)
    uv = grid_points(grid, nu, nv)
    pts = fin.origin + uv[:, :1] * np.asarray(fin.e1) + uv[:, 1:] * np.asarray(fin.e2)
    sampler = _Sampler(grid_interpolation(fg, pts), np.asarray(fin.n, dtype=float))
    ts = job.steps
    with progress_bar(ts.n_steps, f"fin motion {fin.name}") as bar:
        res = run_fin(replace(job, writer=sampler, steps=replace(ts, field_every=ts.every)), shell, bar, log)
    return np.array(sampler.t), np.array(sampler.w), res


def fin_motion(missile_cfg, shell_cfg, collide_dir: Path, work_dir: Path, *, interval: float = 1e-6, nu: int = 41,
               nv: int = 41, log: logging.Logger = LOG) -> tuple[FinMotion, dict]:
    """(FinMotion of the missile of ``missile_cfg``, {fin: (shell summary, history columns, missile
    fin)}) from the collision in ``collide_dir`` (``fin_contacts.npz``, ``history.csv``): every loaded
    fin run by the shell stage's functions under ``shell_cfg`` (its history every ``interval`` [s],
    without the peak check and the strike envelope), w sampled every ``interval`` on an nu × nv grid;
    unloaded fins rigid (nt = 0). Work files (meshes, the fins' histories) in ``work_dir``. Serial
    (each fin on this process alone: the collide stage runs on rank 0 of an mpirun job)."""
    from mpi4py import MPI

    from flexnet_fe.io import read_history_csv
    from flexnet_fe.missile.build import build_missile
    from flexnet_fe.missile.mesh import write_meshes
    from flexnet_fe.missile.shapes import pack_shapes
    from flexnet_fe.runs import FIN_CONTACTS, HISTORY
    from flexnet_fe.shell import stage as S

    missile = build_missile(missile_cfg)
    grids = np.array([grid_of(poly, nu, nv) for poly in pack_shapes(missile).fin_poly])
    shell = shell_cfg.model_copy(update={"history_interval": interval, "peak_check": False, "strike_envelope": False})
    contacts = S.read_fin_contacts(Path(collide_dir) / FIN_CONTACTS)
    acc_t, acc = S.read_body_acceleration(Path(collide_dir) / HISTORY)
    end = S.stage_end_time(shell, contacts, acc_t)
    specs = S.select_fins(shell, S.fin_specs(missile.fins, write_meshes(missile_cfg, Path(work_dir) / "meshes")),
                          contacts)
    nf = len(missile.fins)
    t0, nt, ws, fins = np.zeros(nf), np.zeros(nf, np.int64), [], {}
    for spec in specs:  # (in the missile's fin order: select_fins keeps it)
        f = next(i for i, m in enumerate(missile.fins) if m.name == spec.name)
        job = S.setup_fin(shell, spec, contacts, acc_t, acc, work_dir, end, log, MPI.COMM_SELF)
        t, w, res = _fin_samples(job, shell, missile.fins[f], grids[f], nu, nv, log)
        t0[f] = t[0]
        ws.append(resample(t, w, interval).reshape(-1, nu, nv))
        nt[f] = len(ws[-1])
        fins[spec.name] = (S.finish_fin(job, res, shell), read_history_csv(job.out_dir / HISTORY), missile.fins[f])
    w = np.concatenate(ws) if ws else np.zeros((0, nu, nv))
    return FinMotion(t0=t0, dt=float(interval), nt=nt, offset=np.concatenate([[0], np.cumsum(nt)]), grid=grids,
                     w=w), fins
