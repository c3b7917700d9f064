"""Run the explicit shell solver over a time interval with stress sampling and output frames.

:func:`run` drives either backend (:class:`~flexnet_fe.shell.explicit.Backend`) and returns the
same :class:`RunResult`: the sampled history, the per-node envelope and the peak state. The
compiled backend calls the numba kernel once per output frame (many steps per call); the PETSc
backend (MPI) steps in Python with one ``Mat.mult`` per step and samples with the same compiled
recovery, completed across processes by a reverse scatter.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy import sparse
from dolfinx import fem, la
from mpi4py import MPI

from flexnet_fe.shell import kernel as kn
from flexnet_fe.shell.explicit import (Backend, LoadHistory, central_difference, constrain)
from flexnet_fe.shell.forms import NDOF_NODE
from flexnet_fe.shell.hotspot import Exclusion, no_exclusion, zone_mask
from flexnet_fe.shell.model import ShellModel
from flexnet_fe.shell.recovery import (RecoveryData, accumulate_cells, build_recovery,
                                       nodal_from_numerators)


def recovery_for(model: ShellModel) -> RecoveryData:
    """Recovery data of a model's owned cells; the lumped weights completed across processes."""
    V = model.V
    mesh = V.mesh
    nc = mesh.topology.index_map(2).size_local
    cells = V.dofmap.list.array.reshape(-1, 4)[:nc]
    x = V.tabulate_dof_coordinates()
    imap = V.dofmap.index_map
    n_local = imap.size_local + imap.num_ghosts
    mat = model.material
    R = build_recovery(cells, x, n_local, model.fin.plane.e1, model.fin.plane.e2,
                       model.fin.plane.origin,
                       (mat.plane_stress_modulus, mat.poisson_ratio, mat.thickness))
    if mesh.comm.size > 1:
        w = np.where(R.winv > 0, 1.0 / np.where(R.winv > 0, R.winv, 1.0), 0.0)
        S = fem.Function(fem.FunctionSpace(mesh, ("Lagrange", 1)))
        S.x.array[:] = w
        S.x.scatter_reverse(la.ScatterMode.add)
        w = S.x.array[: imap.size_local]
        R.winv[:] = 0.0
        R.winv[: imap.size_local] = np.where(w > 0, 1.0 / np.where(w > 0, w, 1.0), 0.0)
    return R


@dataclass
class RunResult:
    """What a run produced (owned nodes of this process; history on every process)."""

    t: np.ndarray
    """sample times [s]"""
    vm: np.ndarray
    """largest nodal von Mises per sample [Pa]"""
    loc: np.ndarray
    """its node's coordinates (ns, 3) [m]"""
    p1: np.ndarray
    umax: np.ndarray
    ke: np.ndarray
    se: np.ndarray
    work: np.ndarray
    env: np.ndarray
    """per owned node: peak over samples of (von Mises, max principal) (n_owned_nodes, 2) [Pa]"""
    peak_vm: float
    peak_t: float
    peak_node: int
    """owned node of the peak on the process holding it (−1 elsewhere)"""
    peak_p1: float
    u_peak: np.ndarray
    """state at the peak, owned DOFs of this process"""
    steps: int
    failed_at: int
    """0, or the step at which the energy check failed"""
    u: np.ndarray
    """final state, owned DOFs, frame B"""
    peak_raw: float = 0.0
    """largest nodal von Mises over samples anywhere, St-Venant zones included [Pa]"""


FrameFn = Callable[[float, np.ndarray], None]
"""frame(t [s], u owned DOFs) — called at output frames and at new running peaks"""


def run(model: ShellModel, loads: LoadHistory, R: RecoveryData, *, dt: float, n_steps: int,
        sample_every: int, frame_every: int, alpha: float = 0.0, beta: float = 0.0,
        growth_limit: float = 10.0, frame: FrameFn | None = None,
        backend: Backend = Backend.AUTO, u0: np.ndarray | None = None,
        exclusion: Exclusion | None = None, peak_every: int = 0,
        start_step: int = 0) -> RunResult:
    """Advance ``n_steps`` steps of size ``dt`` [s] from step ``start_step`` (the state ``u0``,
    at rest, is at t = start_step dt; times stay absolute: step n is at t = n dt), sampling
    stresses every ``sample_every`` steps (at multiples of it) and calling ``frame`` every
    ``frame_every`` steps (a multiple of sample_every), at the start and at the end — and, before a regular frame, at the latest running von Mises peak
    if it rose since the previous frame (so the frames include the final peak's instant).
    ``exclusion``: owned nodes in the St-Venant zones of each contact sample's loads
    (:mod:`flexnet_fe.shell.hotspot`), left out of the peaks and the history's maxima (not of
    the envelope); None: no zones. ``peak_every``: evaluate the stresses for the running peaks
    and the envelope every that many steps (a divisor of ``sample_every``; 0: at the samples
    only); the history rows stay at ``sample_every``."""
    serial = model.V.mesh.comm.size == 1
    if backend is Backend.AUTO:
        backend = Backend.COMPILED if serial else Backend.PETSC
    if backend is Backend.COMPILED and (not serial or model.op.Kb is None):
        raise ValueError("the compiled backend runs on one process; use backend = 'petsc' "
                         "under MPI")
    if frame_every % sample_every:
        raise ValueError("frame_every must be a multiple of sample_every")
    if peak_every < 0 or (peak_every and sample_every % peak_every):
        raise ValueError("peak_every must be 0 or a divisor of sample_every")
    if start_step < 0 or start_step % sample_every:
        raise ValueError("start_step must be a non-negative multiple of sample_every")
    go = _run_compiled if backend is Backend.COMPILED else _run_petsc
    return go(model, loads, R, dt=dt, n_steps=n_steps, sample_every=sample_every,
              frame_every=frame_every, alpha=alpha, beta=beta, growth_limit=growth_limit,
              frame=frame or (lambda t, u: None), u0=u0,
              exclusion=exclusion or no_exclusion(len(loads.times)), peak_every=peak_every,
              start_step=start_step)


class LocalFrame:
    """Nodal rotation between frame-B DOFs (u_x, u_y, u_z, θ1, θ2) and the fin's local DOFs
    (u1, u2, w, θ1, θ2) used by the compiled kernel."""

    def __init__(self, plane):
        self.T = kn.node_rotation(plane.e1, plane.e2, plane.n)

    def to_local(self, x: np.ndarray) -> np.ndarray:
        return (x.reshape(-1, NDOF_NODE) @ self.T.T).ravel()

    def to_body(self, x: np.ndarray) -> np.ndarray:
        return (x.reshape(-1, NDOF_NODE) @ self.T).ravel()


def step_data(model: ShellModel, loads: LoadHistory, frame: LocalFrame,
              exclusion: Exclusion | None = None) -> kn.StepData:
    """The compiled kernel's inputs in the fin's local frame (K split into membrane and
    bending blocks, contact loads and frame accelerations rotated once)."""
    op = model.op
    n = op.n_owned
    Tn = sparse.kron(sparse.identity(n // NDOF_NODE, format="csr"), sparse.csr_matrix(frame.T))
    P = (Tn @ loads.nodal).tocsc()
    P.eliminate_zeros()
    P.sort_indices()
    acc = np.ascontiguousarray(loads.accel, dtype=float).reshape(-1, 3) @ frame.T[:3, :3].T
    ex = exclusion or no_exclusion(len(loads.times))
    return kn.StepData(K=kn.split_upper(op.Kb, frame.T), minv=op.minv, mass=op.mass,
                       mass_t=loads.mass_c.sum(axis=0),
                       times=np.asarray(loads.times, float), colptr=P.indptr.astype(np.int64),
                       rows=P.indices.astype(np.int64), vals=P.data.astype(float),
                       acc_times=np.asarray(loads.accel_times, float),
                       acc=np.ascontiguousarray(acc), wfix=op.wfix,
                       normal=np.array([0.0, 0.0, 1.0]), zones=ex)


def _run_compiled(model, loads, R, *, dt, n_steps, sample_every, frame_every, alpha, beta,
                  growth_limit, frame, u0, exclusion, peak_every, start_step) -> RunResult:
    op = model.op
    lf = LocalFrame(model.fin.plane)
    D = step_data(model, loads, lf, exclusion)
    RL = R._replace(e1=np.array([1.0, 0.0, 0.0]), e2=np.array([0.0, 1.0, 0.0]))
    Pm = kn.StepParams(dt=dt, alpha=alpha, beta=beta, growth_limit=growth_limit,
                       sample_every=sample_every, peak_every=peak_every)
    St = kn.new_state(op.n_owned, None if u0 is None
                      else lf.to_local(constrain(op, np.array(u0, float))), start_step=start_step)
    nn = op.n_owned // NDOF_NODE
    H = kn.new_history(n_steps // sample_every + 2, nn)
    # the sample at the start (the kernel samples at the multiples of sample_every it reaches)
    _sample0(D, RL, St, H, Pm, start_step)
    frame(start_step * dt, lf.to_body(St.u))
    end = start_step + n_steps
    done, failed, last_peak_step = start_step, 0, start_step  # the start frame is written
    while done < end and not failed:
        n = min(frame_every - done % frame_every, end - done)
        failed = kn.advance(D, Pm, RL, St, H, n)
        done = int(St.scal[kn.S_STEP])
        if failed:
            break
        ps = int(St.scal[kn.S_PEAK_STEP])
        if ps != last_peak_step and ps < done:
            frame(St.scal[kn.S_PEAK_T], lf.to_body(St.u_peak))
        last_peak_step = ps
        frame(done * dt, lf.to_body(St.u))
    ns = int(St.scal[kn.S_NSAMP])
    sc = St.scal
    node = H.node[:ns]
    loc = np.where((node >= 0)[:, None], op.x_nodes[np.maximum(node, 0)], np.nan)  # NaN: no stress
    return RunResult(t=H.t[:ns].copy(), vm=H.vm[:ns].copy(), loc=loc,
                     p1=H.p1[:ns].copy(), umax=H.umax[:ns].copy(), ke=H.ke[:ns].copy(),
                     se=H.se[:ns].copy(), work=H.work[:ns].copy(), env=H.env,
                     peak_vm=float(sc[kn.S_PEAK_VM]), peak_t=float(sc[kn.S_PEAK_T]),
                     peak_node=int(sc[kn.S_PEAK_NODE]), peak_p1=float(sc[kn.S_PEAK_P1]),
                     u_peak=lf.to_body(St.u_peak), steps=done - start_step,
                     failed_at=int(failed),
                     u=lf.to_body(St.u), peak_raw=float(sc[kn.S_PEAK_RAW]))


def _sample0(D, R, St, H, Pm, start_step: int = 0):
    """History row 0 (the start, t = start_step dt) in the compiled path."""
    sc = St.scal
    t0 = start_step * Pm.dt
    kn._sample(D, R, St, H, 0, start_step, t0)
    H.t[0] = t0
    H.ke[0] = 0.5 * float(D.mass @ (St.v * St.v))
    kn.split_product(D.K, St.u, St.y)
    se = 0.5 * float(St.u @ St.y)
    St.y[:] = 0.0
    H.work[0] = 0.0
    kn._close_sample(H, sc, 0, se, Pm.growth_limit)
    sc[kn.S_NSAMP] = 1


class ParallelSampler:
    """Nodal stresses under MPI: local numerators, reverse scatter (add), owned nodal values."""

    def __init__(self, model: ShellModel, R: RecoveryData):
        V = model.V
        self.R = R
        self.U = fem.Function(V)
        self.n_owned = V.dofmap.index_map.size_local
        S6 = fem.VectorFunctionSpace(V.mesh, ("Lagrange", 1), dim=6)
        if not np.array_equal(S6.dofmap.list.array, V.dofmap.list.array):
            raise RuntimeError("P1 spaces of block size 5 and 6 number the nodes differently")
        self.S = fem.Function(S6)
        self.nodal = np.zeros((self.n_owned, 4))
        self.comm = V.mesh.comm

    def __call__(self, u_owned: np.ndarray):
        self.U.x.array[: u_owned.size] = u_owned
        self.U.x.scatter_forward()
        accumulate_cells(self.R, self.U.x.array)
        self.S.x.array[:] = self.R.num.ravel()
        self.S.x.scatter_reverse(la.ScatterMode.add)
        self.R.num[:] = self.S.x.array.reshape(-1, 6)
        return nodal_from_numerators(self.R, self.U.x.array, self.nodal, self.n_owned)


def _masked_max(nodal: np.ndarray, exclusion: Exclusion, times: np.ndarray, t: float):
    """(max vm, its node, max p1) over the owned nodes outside the St-Venant zones active at t
    (as :func:`flexnet_fe.shell.kernel._mark_zones`); node −1 if none."""
    keep = np.ones(len(nodal), bool)
    n = len(times)
    if n and times[0] <= t <= times[-1]:
        k = min(int(np.searchsorted(times, t, side="right")) - 1, max(n - 2, 0))
        keep[zone_mask(exclusion, k, k + 2)] = False
    vm = np.where(keep, nodal[:, :2].max(axis=1, initial=0.0), 0.0)
    p1 = np.where(keep, nodal[:, 2:].max(axis=1, initial=-np.inf), -np.inf)
    if not len(vm) or vm.max() <= 0.0:
        return 0.0, -1, float(p1.max(initial=-np.inf))
    node = int(np.argmax(vm))
    return float(vm[node]), node, float(p1.max(initial=-np.inf))


def _run_petsc(model, loads, R, *, dt, n_steps, sample_every, frame_every, alpha, beta,
               growth_limit, frame, u0, exclusion, peak_every, start_step) -> RunResult:
    from flexnet_fe.errors import NumericalError

    op = model.op
    comm = op.comm
    sampler = ParallelSampler(model, R)
    nn = op.n_owned // NDOF_NODE
    env = np.zeros((nn, 2))
    rows = {k: [] for k in ("t", "vm", "loc", "p1", "umax", "ke", "se", "work")}
    peak = dict(vm=-1.0, t=0.0, node=-1, p1=-np.inf, step=-1, u=np.zeros(op.n_owned), raw=0.0)
    last_peak_step, done, failed = -1, start_step, 0
    last_u = np.zeros(op.n_owned)
    gen = central_difference(op, loads, dt, n_steps, sample_every, dt_crit=dt, alpha=alpha,
                             beta=beta, u0=u0, growth_limit=growth_limit, peak_every=peak_every,
                             start_step=start_step)
    try:
        for smp in gen:
            vraw, _, _, umax = sampler(smp.u)
            vmax, node, p1max = _masked_max(sampler.nodal, exclusion, loads.times, smp.t)
            peak["raw"] = max(peak["raw"], comm.allreduce(vraw, op=MPI.MAX))
            np.maximum(env[:, 0], sampler.nodal[:, :2].max(axis=1), out=env[:, 0])
            np.maximum(env[:, 1], sampler.nodal[:, 2:].max(axis=1), out=env[:, 1])
            gv, owner = comm.allreduce((vmax, comm.rank), op=MPI.MAXLOC)
            p1g = comm.allreduce(p1max, op=MPI.MAX)
            if smp.row:  # a history row (else: an instant for the peaks and the envelope only)
                loc = comm.bcast(op.x_nodes[node] if comm.rank == owner and node >= 0
                                 else None, root=owner)
                for k, val in zip(rows, (smp.t, gv,
                                         loc if loc is not None else np.full(3, np.nan), p1g,
                                         comm.allreduce(umax, op=MPI.MAX), smp.kinetic,
                                         smp.strain, smp.work)):
                    rows[k].append(val)
            if gv > peak["vm"]:
                peak.update(vm=gv, t=smp.t, step=smp.step,
                            node=node if comm.rank == owner else -1)
                peak["u"][:] = smp.u  # every process keeps its owned part of the peak state
            peak["p1"] = max(peak["p1"], p1g)
            done = smp.step
            last_u = smp.u
            if smp.step % frame_every == 0 or smp.step == start_step + n_steps:
                if peak["step"] != last_peak_step and 0 <= peak["step"] < smp.step:
                    frame(peak["t"], peak["u"])
                last_peak_step = peak["step"]
                frame(smp.t, smp.u)
    except NumericalError as err:
        failed = int(str(err).split("(step ")[1].split(")")[0]) if "(step " in str(err) else -1
    arr = {k: np.asarray(v, dtype=float) for k, v in rows.items()}
    return RunResult(t=arr["t"], vm=arr["vm"], loc=arr["loc"].reshape(-1, 3), p1=arr["p1"],
                     umax=arr["umax"], ke=arr["ke"], se=arr["se"], work=arr["work"], env=env,
                     peak_vm=peak["vm"], peak_t=peak["t"], peak_node=peak["node"],
                     peak_p1=peak["p1"], u_peak=peak["u"], steps=done - start_step,
                     failed_at=failed,
                     u=last_u, peak_raw=peak["raw"])
