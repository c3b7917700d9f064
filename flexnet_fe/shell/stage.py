"""The shell stage: fin stress histories from the collision loads (explicit dolfinx solver).

Inputs: the ``[shell]`` table, the fins (mesh + material), ``collide/fin_contacts.npz`` and
``collide/history.csv`` (rigid-body CG acceleration in B). Outputs in ``stage_dir/<fin>/``:
``history.csv`` (float64; per sample the largest recovered nodal von Mises and where; the peak
row carries the located peak), ``fields.xdmf`` (recovered stresses as CG1 ``*_nodal_pa`` and as
per-cell maxima DG0 ``von_mises_{top,mid,bottom}_pa``, CG1 displacement; frames every
``field_interval`` plus each running peak's instant; appended and closed at every frame so a
killed run keeps its earlier frames) and ``envelope.xdmf`` (peak over samples per node, CG1,
and per cell, DG0 ``peak_von_mises_pa``, ``peak_max_principal_pa``).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Iterable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from dolfinx import fem
from dolfinx.io import XDMFFile
from mpi4py import MPI
from scipy import sparse

from flexnet_fe.shell.transfer import FinGeometry, contact_transfer
from flexnet_fe.errors import CaseError, NumericalError
from flexnet_fe.io import read_history_csv, write_history_csv
from flexnet_fe.progress import progress_bar
from flexnet_fe.shell.config import FinSelection, FinSpec, ShellConfig
from flexnet_fe.shell.explicit import (Backend, LoadHistory, critical_step, max_eigenvalue,
                                       translational_mass)
from flexnet_fe.shell.forms import NDOF_NODE, ShellMaterial
from flexnet_fe.shell.meshio import load_fin_mesh
from flexnet_fe.machine import cpu_count
from flexnet_fe.shell.model import ShellModel, build_model
from flexnet_fe.shell import hotspot, strikes
from flexnet_fe.shell.recovery import build_recovery, locate_peak, stress_tensors, von_mises
from flexnet_fe.shell.schedule import (FREE_VIBRATION_LIMIT, IO_LOCK, FinWindow,
                                      fin_window, run_as_ready, window_steps)
from flexnet_fe.shell.solve import ParallelSampler, RunResult, recovery_for, run
from flexnet_fe.runs import ENVELOPE_XDMF, FIELDS_XDMF, FIN_STRIKE_ENVELOPE, HISTORY

ACCEL_COLUMNS = ("accel_body_x_mps2", "accel_body_y_mps2", "accel_body_z_mps2")


@dataclass(frozen=True)
class FinContacts:
    """The collision stage's fin loads (``fin_contacts.npz``), CSR over sample times."""

    fin_names: tuple[str, ...]
    t: np.ndarray
    """sample times [s], (nt,)"""
    sample: np.ndarray
    """sample index of each event, (ne,)"""
    fin: np.ndarray
    """fin index of each event, (ne,)"""
    point: np.ndarray
    """contact point in B [m], (ne, 3)"""
    force: np.ndarray
    """force on the fin in B [N], (ne, 3)"""
    width: np.ndarray
    """rope contact width [m], (ne,)"""


def read_fin_contacts(path: Path) -> FinContacts:
    """Read and check ``fin_contacts.npz`` (allow_pickle=False)."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            d = {k: z[k] for k in ("fin_names", "t", "row_start", "fin", "point", "force", "width")}
    except KeyError as err:
        raise CaseError(str(path), str(err).strip("'\""), "missing array") from None
    t, rs = d["t"].astype(float), d["row_start"].astype(np.int64)
    ne = len(d["fin"])
    checks = [("row_start", len(rs) == len(t) + 1 and rs[0] == 0 and rs[-1] == ne
               and np.all(np.diff(rs) >= 0), "must be CSR offsets of length nt+1 ending at ne"),
              ("t", np.all(np.diff(t) > 0), "sample times must increase"),
              ("point", d["point"].shape == (ne, 3), "shape must be (ne, 3)"),
              ("force", d["force"].shape == (ne, 3), "shape must be (ne, 3)"),
              ("width", d["width"].shape == (ne,) and np.all(d["width"] > 0), "must be > 0, (ne,)"),
              ("fin", ne == 0 or (d["fin"].min() >= 0 and d["fin"].max() < len(d["fin_names"])),
               "index out of range of fin_names")]
    for field, ok, why in checks:
        if not ok:
            raise CaseError(str(path), field, why)
    for k in ("t", "point", "force", "width"):
        if not np.all(np.isfinite(d[k])):
            raise CaseError(str(path), k, "contains NaN or inf")
    sample = np.repeat(np.arange(len(t)), np.diff(rs))
    return FinContacts(fin_names=tuple(str(s) for s in d["fin_names"]), t=t, sample=sample,
                       fin=d["fin"].astype(np.int64), point=d["point"].astype(float),
                       force=d["force"].astype(float), width=d["width"].astype(float))


def read_body_acceleration(path: Path | None) -> tuple[np.ndarray, np.ndarray]:
    """(times [s] (na,), CG acceleration in B [m/s²] (na, 3)) from ``collide/history.csv``;
    empty arrays for ``None``."""
    if path is None:
        return np.zeros(0), np.zeros((0, 3))
    h = read_history_csv(path)
    missing = [c for c in ("t_s",) + ACCEL_COLUMNS if c not in h]
    if missing:
        raise CaseError(str(path), missing[0], "column missing")
    return h["t_s"], np.column_stack([h[c] for c in ACCEL_COLUMNS])


class FinZones:
    """The contact events of one fin and their St-Venant zones (:mod:`flexnet_fe.shell.hotspot`)."""

    def __init__(self, model: ShellModel, contacts: FinContacts, fin_index: int, factor: float):
        sel = np.flatnonzero(contacts.fin == fin_index)
        self.times = contacts.t
        self.sample = contacts.sample[sel]
        self.points = contacts.point[sel]
        self.forces = contacts.force[sel]
        self.widths = contacts.width[sel]
        self.radius = hotspot.exclusion_radius(model.material.thickness, self.widths, factor)
        self.exclusion = hotspot.exclusion_zones(model.op.x_nodes, self.sample, self.points,
                                                 self.radius, len(contacts.t))

    def active(self, t: float):
        """(points (m, 3), radii (m,)) of the zones active at t [s]."""
        return hotspot.excluded_points(self.times, t, self.sample, self.points, self.radius)

    def bearing(self, model: ShellModel, rope_modulus: float) -> hotspot.Bearing:
        """Largest closed-form bearing/contact stress of the fin's events (rope_modulus [Pa]:
        ``shell.bearing_rope_modulus``)."""
        if not len(self.points):
            return hotspot.Bearing(0.0, 0.0, "", None, 0.0)
        from flexnet_fe.shell.transfer import _boundary_segments, _nearest_on_boundary
        pl = model.fin.plane
        fg = FinGeometry(mesh=model.V.mesh, V=model.V, origin=pl.origin, e1=pl.e1, e2=pl.e2,
                         n=pl.n)
        segs = _boundary_segments(fg)  # collective: every rank calls it
        rel = self.points - pl.origin
        dist = _nearest_on_boundary(segs, np.column_stack([rel @ pl.e1, rel @ pl.e2]))[1]
        mat = model.material
        e_star = hotspot.contact_modulus(mat.youngs_modulus, mat.poisson_ratio, rope_modulus)
        return hotspot.bearing_stress(self.times[self.sample], self.points, self.forces,
                                      self.widths, dist, pl.n, mat.thickness, e_star)


LOAD_SAMPLING_RESOLVED_S = 3.2e-7
"""[s] The fin-load sample interval at and below which the peak stresses no longer follow it
(``collide.load_interval``). Measured on radar_traction, one collision sampled at 0.078 µs and
coarsened (benchmarks/shell_load_sampling.py; docs/validation.md, "The fin loads' time
sampling"): from 10 µs the peaks grow ×3.9–11 down to 0.3125 µs (the 10 µs sampling low-passed
rope strikes that last ~1–4 µs); from 0.3125 to 0.156 µs the rudders move +1.5…+6.6 % and three
wings −5…+10 %. Coarser than this, every run warns that its peaks are under-estimated."""

LOAD_SAMPLING_UNDER = "×4.7–7.5 (wings) and ×3.9–11 (rudders) at 10 µs"
"""How far below the resolved peaks radar_traction's were at the 10 µs sampling."""


def load_sample_interval(contacts: FinContacts) -> float | None:
    """The fin loads' sample interval [s] (``collide.load_interval``); None without contact loads.
    (summary ``load_sample_interval_s``: the report's verdict names it, ``report.verdict``.)"""
    if contacts.fin.size == 0 or contacts.t.size < 2:
        return None
    return float(np.median(np.diff(contacts.t)))


def load_sampling_resolved(contacts: FinContacts) -> bool | None:
    """Whether the fin loads are sampled finely enough for the peaks not to follow the sampling
    (interval ≤ LOAD_SAMPLING_RESOLVED_S); None without contact loads (summary
    ``load_sampling_resolved``)."""
    return _resolved(load_sample_interval(contacts))


def _resolved(dt: float | None) -> bool | None:
    return None if dt is None else dt <= LOAD_SAMPLING_RESOLVED_S * (1 + 1e-9)


def load_sampling_warning(contacts: FinContacts) -> str:
    """What the fin loads' sampling does to the peaks ("" without contact loads): coarser than
    LOAD_SAMPLING_RESOLVED_S they are under-estimated; at or below it they no longer follow the
    sampling but still follow the rope's discretisation and the collision's details."""
    dt = load_sample_interval(contacts)
    if dt is None:
        return ""
    if not _resolved(dt):
        return (f"shell: the fin loads are the collision's means over {dt * 1e6:.3g} µs (collide.load_interval), "
                f"linear between samples — a low-pass of about {0.5e-3 / dt:.3g} kHz that cuts the rope's strikes "
                f"(1–4 µs): the peak stresses are UNDER-ESTIMATED (radar_traction: {LOAD_SAMPLING_UNDER} against "
                f"its loads sampled at ≤ {LOAD_SAMPLING_RESOLVED_S * 1e6:.2g} µs; set collide.load_interval; "
                f"docs/validation.md, \"The fin loads' time sampling\")")
    return (f"shell: the fin loads are sampled every {dt * 1e6:.3g} µs, fine enough for the peaks not to follow the "
            f"sampling (radar_traction: ≤ 7 % on the rudders from 0.3125 to 0.156 µs), but the peaks are not converged "
            f"in the rope: they come from single strikes of the rope on the leading edges, whose peak force follows "
            f"the contact's stiffness per unit of rope mass — net.transverse_modulus, which the paper does not give "
            f"(radar_traction's rudders 2 and 3: 173 and 372 MPa at 10 GPa, 684 and 758 MPa at 100 GPa) — and the "
            f"rope's discretisation and the aim (radar_traction, rope pieces 0.7 / 1.4 / 2.8 mm and the aim point moved "
            f"0.5–1 mm: rudder peaks ±20–27 %, their strike envelopes (shell.strike_envelope) ±8–20 %; "
            f"docs/validation.md, \"Where the rope strikes\"); a defined number is a statistic over where the "
            f"missile meets the net: `flexnet ensemble` (docs/validation.md, \"Ensembles\")")


def fin_load_history(model: ShellModel, contacts: FinContacts, fin_index: int,
                     accel_t: np.ndarray, accel: np.ndarray) -> LoadHistory:
    """Nodal load history of one fin: transfer matrix G (once) then P = G F, one sparse product
    for all samples (F: event forces arranged by sample, shape (3·ne, nt))."""
    sel = np.flatnonzero(contacts.fin == fin_index)
    nt = len(contacts.t)
    pl = model.fin.plane
    fg = FinGeometry(mesh=model.V.mesh, V=model.V, origin=pl.origin, e1=pl.e1, e2=pl.e2, n=pl.n)
    if len(sel):
        G = contact_transfer(fg, contacts.point[sel], contacts.width[sel],
                             plane_tol=2.0 * model.material.thickness)
        rows = np.arange(3 * len(sel))
        cols = np.repeat(contacts.sample[sel], 3)
        F = sparse.csr_matrix((contacts.force[sel].ravel(), (rows, cols)), shape=(3 * len(sel), nt))
        P = (G @ F).tocsc()
    else:
        P = sparse.csc_matrix((model.op.n_owned, nt))
    P.sort_indices()
    return LoadHistory(times=contacts.t, nodal=P, accel_times=accel_t, accel=accel,
                       mass_c=translational_mass(model.op))


NODAL_NAMES = ("von_mises_top_nodal_pa", "von_mises_bottom_nodal_pa")
"""Recovered nodal (CG1) stress fields of ``fields.xdmf``, in the sampler's column order (the
maximum principal stress is in the envelope and the history; each XDMF write costs ≈ 5 ms)."""
CELL_NAMES = ("von_mises_top_pa", "von_mises_mid_pa", "von_mises_bottom_pa")
"""DG0 fields of ``fields.xdmf``: per cell the largest recovered von Mises of its nodes on the
top, mid (membrane only) and bottom surface."""


def pressure_history(model: ShellModel, times, pressure) -> LoadHistory:
    """Uniform pressure p(t) [Pa] along +n: f_i = p ∫ N_i dA n (linear between samples)."""
    from flexnet_fe.shell.api import pressure as api_pressure
    return api_pressure(model, times, pressure)


class _FieldWriter:
    """XDMF output: mesh written once, then one append-and-close per output frame. Scalar
    fields only (DESIGN.md §2): recovered nodal stresses as CG1, per-cell maxima as DG0, the
    displacement as a CG1 vector."""

    def __init__(self, model: ShellModel, R, path: Path):
        mesh = model.V.mesh
        self.path = path
        self.sampler = ParallelSampler(model, R)
        self.V0 = fem.FunctionSpace(mesh, ("DG", 0))
        self.V1 = fem.FunctionSpace(mesh, ("Lagrange", 1))
        self.nodal = [fem.Function(self.V1, name=n) for n in NODAL_NAMES]
        self.cells_fn = [fem.Function(self.V0, name=n) for n in CELL_NAMES]
        self.mid = fem.Function(self.V1)
        Vd = fem.VectorFunctionSpace(mesh, ("Lagrange", 1))
        self.disp = fem.Function(Vd, name="displacement_m")
        self.n_owned_cells = self.V0.dofmap.index_map.size_local
        self.cells = self.V1.dofmap.list.array.reshape(-1, 4)[: self.n_owned_cells]
        with XDMFFile(mesh.comm, str(path), "w") as f:
            f.write_mesh(mesh)

    def cell_max(self, fn: fem.Function, values: np.ndarray) -> None:
        """DG0 ``fn`` = max over each owned cell's nodes of the nodal ``values`` (local nodes)."""
        fn.x.array[: self.n_owned_cells] = values[self.cells].max(axis=1)
        fn.x.scatter_forward()

    def nodal_field(self, fn: fem.Function, owned_values: np.ndarray) -> np.ndarray:
        fn.x.array[: len(owned_values)] = owned_values
        fn.x.scatter_forward()
        return fn.x.array

    def write(self, t: float, u_owned: np.ndarray) -> None:
        self.sampler(u_owned)
        nod = self.sampler.nodal
        for k, fn in enumerate(self.nodal):
            self.nodal_field(fn, nod[:, k])
        R = self.sampler.R
        n = len(nod)
        mid = von_mises(stress_tensors(R.num[:n] * R.winv[:n, None], R, 0.0))
        self.nodal_field(self.mid, mid)
        for fn, src in zip(self.cells_fn, (self.nodal[0], self.mid, self.nodal[1])):
            self.cell_max(fn, src.x.array)
        self.disp.x.array.reshape(-1, 3)[: len(nod)] = u_owned.reshape(-1, NDOF_NODE)[:, :3]
        self.disp.x.scatter_forward()
        with XDMFFile(self.V0.mesh.comm, str(self.path), "a") as f:
            for fn in (*self.nodal, *self.cells_fn, self.disp):
                f.write_function(fn, t)

    def envelope(self, env: np.ndarray, path: Path) -> None:
        """``envelope.xdmf``: peak over samples per node (CG1 ``*_nodal_pa``) and per cell
        (DG0, max of its nodes: ``peak_von_mises_pa``, ``peak_max_principal_pa``)."""
        mesh = self.V0.mesh
        with XDMFFile(mesh.comm, str(path), "w") as f:
            f.write_mesh(mesh)
            for k, name in enumerate(("peak_von_mises", "peak_max_principal")):
                fn = fem.Function(self.V1, name=f"{name}_nodal_pa")
                vals = self.nodal_field(fn, env[:, k])
                fc = fem.Function(self.V0, name=f"{name}_pa")
                self.cell_max(fc, vals)
                f.write_function(fn, 0.0)
                f.write_function(fc, 0.0)


@dataclass(frozen=True)
class TimeSteps:
    """A fin's step size and schedule (steps numbered from t = 0: step n is at t = n dt)."""

    dt: float
    dt_crit: float
    start_step: int
    """the window's first step (a history row; the fin is at rest there)"""
    n_steps: int
    every: int
    """history rows every that many steps"""
    peak_every: int
    """stresses for the peaks and the envelope every that many steps"""
    field_every: int
    dofs: int


def _time_steps(model: ShellModel, shell: ShellConfig, window: FinWindow, log,
                name: str) -> TimeSteps:
    """dt_crit (Lanczos), dt, the window's steps, sampling and frame strides."""
    lam, resid = max_eigenvalue(model.op, steps=shell.lanczos_steps)
    dt_crit = critical_step(lam, shell.rayleigh_alpha, shell.rayleigh_beta)
    dt = shell.safety_factor * dt_crit
    peak_every = max(1, round(shell.peak_interval / dt))
    every = peak_every * max(1, round(shell.history_interval / (dt * peak_every)))
    # whole sampling intervals, so that the last step is a sample in both backends (the PETSc
    # path also samples the last step; the compiled one samples multiples of ``every`` only)
    start, n_steps = window_steps(window, dt, every)
    field_dt = shell.field_interval or n_steps * dt / 10.0
    field_every = max(every, round(field_dt / dt / every) * every)
    mat = model.material
    c_p = math.sqrt(mat.plane_stress_modulus / mat.density)
    dofs = model.V.dofmap.index_map.size_global * NDOF_NODE
    ms = model.mass_scaling
    log.info("shell %s: %d DOFs, rotary inertia ×%.3g, mass scaling to ×%.3g the smallest cell "
             "step (%d cells, %d nodes, mass ×%.3g at most, +%.2e of the fin's), dt_crit = %.4e s "
             "(Lanczos, %d steps, residual %.1e), dt = %.4e s (×%.2f), element estimate "
             "h_min/c_p = %.4e s, %d steps from %.4e s to %.4e s, stresses every %d steps "
             "(history rows every %d)",
             name, dofs, model.rotary_scale, ms["ratio"], ms["cells"], ms["nodes"],
             ms["max_factor"], ms["added_mass_rel"], dt_crit, shell.lanczos_steps, resid, dt,
             shell.safety_factor, model.h_min / c_p, n_steps, start * dt,
             (start + n_steps) * dt, peak_every, every)
    return TimeSteps(dt=dt, dt_crit=dt_crit, start_step=start, n_steps=n_steps, every=every,
                     peak_every=peak_every, field_every=field_every, dofs=dofs)


def _whole_fin(model: ShellModel, R, u_owned: np.ndarray, node: int):
    """(recovery data, state (frame B), peak node, node coordinates) of the whole fin on rank 0
    (None elsewhere): under MPI the owned parts are gathered, so that the peak is located with
    every cell around its node — the same search as a serial run."""
    comm = model.V.mesh.comm
    x = model.V.tabulate_dof_coordinates()
    if comm.size == 1:
        return R, u_owned, node, x
    imap = model.V.dofmap.index_map
    nloc = imap.size_local
    gl = imap.local_to_global(np.arange(nloc + imap.num_ghosts, dtype=np.int32)).astype(np.int64)
    parts = comm.gather((gl[R.cells], gl[:nloc], x[:nloc], u_owned.reshape(-1, NDOF_NODE),
                         int(gl[node]) if node >= 0 else -1), root=0)
    if comm.rank != 0:
        return None
    n = imap.size_global
    xg, ug = np.zeros((n, 3)), np.zeros((n, NDOF_NODE))
    for _, g, xp, up, _ in parts:
        xg[g], ug[g] = xp, up
    cells = np.concatenate([p[0] for p in parts])
    pl, mat = model.fin.plane, model.material
    Rg = build_recovery(cells, xg, n, pl.e1, pl.e2, pl.origin,
                        (mat.plane_stress_modulus, mat.poisson_ratio, mat.thickness))
    return Rg, ug.ravel(), max(p[4] for p in parts), xg


def _peak(model: ShellModel, R, res, zones: FinZones | None):
    """Located structural peak (value, location, surface, ZZ error estimate), searched outside
    the St-Venant zones active at the peak's instant; the same on every rank."""
    comm = model.V.mesh.comm
    if comm.allreduce(res.peak_node, op=MPI.MAX) < 0 or res.peak_vm <= 0.0:
        return None
    whole = _whole_fin(model, R, res.u_peak, res.peak_node)
    pk = None
    if whole is not None:
        Rg, u, node, x = whole
        excl = zones.active(res.peak_t) if zones is not None else None
        pk = locate_peak(Rg, u, node, x, model.fin.plane.origin, exclude=excl)
    return comm.bcast(pk, root=0)


@dataclass
class FinJob:
    """One fin ready to run: model, loads and output set up (serially, dolfinx)."""

    name: str
    model: ShellModel
    loads: LoadHistory
    zones: FinZones | None
    window: FinWindow
    steps: TimeSteps
    R: object
    """recovery data (:class:`flexnet_fe.shell.recovery.RecoveryData`)"""
    writer: _FieldWriter
    out_dir: Path


def prepare_fin(model: ShellModel, loads: LoadHistory, shell: ShellConfig, window: FinWindow,
                out_dir: Path, log: logging.Logger, *, name: str,
                zones: FinZones | None = None) -> FinJob:
    """dt (Lanczos), recovery data and the XDMF writer of one fin (serial: dolfinx calls)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    steps = _time_steps(model, shell, window, log, name)
    R = recovery_for(model)
    return FinJob(name=name, model=model, loads=loads, zones=zones, window=window, steps=steps,
                  R=R, writer=_FieldWriter(model, R, out_dir / FIELDS_XDMF), out_dir=out_dir)


def run_fin(job: FinJob, shell: ShellConfig, bar, log: logging.Logger | None = None) -> RunResult:
    """The fin's time loop (callable from a worker thread: the compiled kernel releases the
    GIL; XDMF frames and progress updates are made under :data:`IO_LOCK`); one log line when it
    ends."""
    ts = job.steps
    t0 = time.perf_counter()
    done = [ts.start_step]

    def frame(t: float, u: np.ndarray) -> None:
        with IO_LOCK:
            job.writer.write(t, u)
            k = min(ts.start_step + ts.n_steps, int(round(t / ts.dt)))
            if k > done[0]:
                bar.update(k - done[0])
                done[0] = k

    res = run(job.model, job.loads, job.R, dt=ts.dt, n_steps=ts.n_steps,
              sample_every=ts.every, frame_every=ts.field_every, alpha=shell.rayleigh_alpha,
              beta=shell.rayleigh_beta, growth_limit=shell.energy_growth_limit, frame=frame,
              backend=Backend(shell.backend),
              exclusion=job.zones.exclusion if job.zones is not None else None,
              peak_every=ts.peak_every, start_step=ts.start_step)
    if log is not None:
        log.info("shell %s: %d steps in %.1f s%s", job.name, res.steps,
                 time.perf_counter() - t0, " (unstable)" if res.failed_at else "")
    return res


def finish_fin(job: FinJob, res: RunResult, shell: ShellConfig) -> dict:
    """Locate the peak, write history.csv and envelope.xdmf (serial); return the fin's summary
    (peaks with their error estimate, dt, dt_crit, dofs, steps, window). Raises
    :class:`NumericalError` (after writing the history) if the run blew up."""
    model, ts, comm = job.model, job.steps, job.model.V.mesh.comm
    pk = None if res.failed_at else _peak(model, job.R, res, job.zones)
    vm, loc = res.vm.copy(), res.loc.copy()
    if pk is not None:  # the row nearest the peak's instant carries the located peak
        i = int(np.argmin(np.abs(res.t - res.peak_t)))
        vm[i], loc[i] = max(pk.value, vm[i]), pk.location
    cols = {"t_s": res.t, "max_von_mises_pa": vm, "max_von_mises_x_m": loc[:, 0],
            "max_von_mises_y_m": loc[:, 1], "max_von_mises_z_m": loc[:, 2],
            "max_principal_pa": res.p1, "max_abs_u_m": res.umax, "kinetic_energy_j": res.ke,
            "strain_energy_j": res.se, "external_work_j": res.work}
    if comm.rank == 0:
        write_history_csv(job.out_dir / HISTORY, cols)
    job.writer.envelope(res.env, job.out_dir / ENVELOPE_XDMF)
    if res.failed_at:
        raise NumericalError(
            f"shell solver unstable at step {res.failed_at} (t = {res.failed_at * ts.dt:.6e} s): "
            f"kinetic + strain energy exceeds {shell.energy_growth_limit} × (initial energy + "
            f"external work); dt = {ts.dt:.4e} s, dt_crit = {ts.dt_crit:.4e} s "
            f"(dt/dt_crit = {ts.dt / ts.dt_crit:.3f})")
    mat = model.material
    c_p = math.sqrt(mat.plane_stress_modulus / mat.density)
    peak = float(vm.max(initial=0.0))
    return {"peak_von_mises_pa": peak, "peak_time_s": res.peak_t,
            "peak_location_m": [float(v) for v in pk.location] if pk else None,
            "peak_surface": pk.surface if pk else None,
            "peak_error_estimate_rel": pk.error_estimate_rel if pk else 0.0,
            "peak_error_estimate_kind": "zz",
            "peak_nodal_von_mises_pa": max(res.peak_vm, 0.0),
            "peak_von_mises_with_load_zones_pa": res.peak_raw,
            "stvenant_radius_m": (float(job.zones.radius.max(initial=0.0))
                                  if job.zones is not None else 0.0),
            "peak_max_principal_pa": res.peak_p1,
            "allowable_pa": mat.yield_strength,
            "peak_over_allowable": peak / mat.yield_strength,
            "max_abs_u_m": float(res.umax.max(initial=0.0)),
            "dt_s": ts.dt, "dt_crit_s": ts.dt_crit, "dt_element_estimate_s": model.h_min / c_p,
            "rotary_inertia_scale": model.rotary_scale,
            "mass_scaling_ratio": model.mass_scaling["ratio"],
            "mass_scaled_cells": model.mass_scaling["cells"],
            "mass_max_factor": model.mass_scaling["max_factor"],
            "mass_added_rel": model.mass_scaling["added_mass_rel"],
            "dofs": ts.dofs, "steps": ts.n_steps,
            "start_time_s": ts.start_step * ts.dt,
            "end_time_s": (ts.start_step + ts.n_steps) * ts.dt,
            "sample_interval_s": ts.every * ts.dt, "peak_interval_s": ts.peak_every * ts.dt,
            **after_last_load(res.t, vm, job.window.last_load_s, peak)}


def after_last_load(t: np.ndarray, vm: np.ndarray, last_load_s: float, peak: float) -> dict:
    """The fin's free vibration after its last contact load, from the history rows (t (ns,) [s],
    vm (ns,) [Pa]): ``after_last_load_max_von_mises_pa`` (the largest von Mises of a row after
    ``last_load_s`` [s]) and ``after_last_load_over_peak`` (that over the peak [Pa]); None for both
    when the window has no last load (shell.window = 'full', a given pressure) or no row after it."""
    after = np.asarray(t) > last_load_s  # (False everywhere for nan)
    if not after.any():
        return {"after_last_load_max_von_mises_pa": None, "after_last_load_over_peak": None}
    top = float(np.asarray(vm)[after].max())
    return {"after_last_load_max_von_mises_pa": top,
            "after_last_load_over_peak": top / peak if peak > 0 else None}


def solve_fin(model: ShellModel, loads: LoadHistory, shell: ShellConfig, window: FinWindow,
              out_dir: Path, log: logging.Logger, *, name: str,
              zones: FinZones | None = None) -> dict:
    """One fin over its ``window``, in this thread: :func:`prepare_fin`, :func:`run_fin`,
    :func:`finish_fin`; outputs in ``out_dir`` (history.csv, fields.xdmf with frames every
    ``field_interval`` plus the running peak's instants, envelope.xdmf)."""
    job = prepare_fin(model, loads, shell, window, out_dir, log, name=name, zones=zones)
    with progress_bar(job.steps.n_steps, f"shell {name}") as bar:
        res = run_fin(job, shell, bar, log)
    return finish_fin(job, res, shell)


def fin_specs(fins, mesh_paths: dict) -> list[FinSpec]:
    """FinSpecs from the missile model's fins (objects with ``name``, ``thickness`` and
    ``material.{youngs_modulus, poisson_ratio, density, yield_strength}``) and the fin meshes
    ``{fin name: .msh path}`` written by the missile mesher."""
    return [FinSpec(name=f.name, mesh_path=Path(mesh_paths[f.name]), thickness=f.thickness,
                    youngs_modulus=f.material.youngs_modulus,
                    poisson_ratio=f.material.poisson_ratio, density=f.material.density,
                    yield_strength=f.material.yield_strength) for f in fins]


def loaded_fins(contacts: FinContacts) -> dict[str, int]:
    """Fin name → its index in ``contacts`` for the fins with at least one contact load."""
    return {contacts.fin_names[int(k)]: int(k) for k in np.unique(contacts.fin)}


def select_fins(shell: ShellConfig, fins: list[FinSpec], contacts: FinContacts) -> list[FinSpec]:
    """The fins the stage solves (``shell.fins``)."""
    names = [f.name for f in fins]
    if shell.fins is FinSelection.ALL:
        return list(fins)
    if shell.fins is FinSelection.NAMED:
        unknown = [n for n in shell.fin_names if n not in names]
        if unknown:
            raise CaseError("case.toml", "shell.fin_names", f"unknown fin(s) {unknown}; fins: {names}")
        return [f for f in fins if f.name in shell.fin_names]
    loaded = loaded_fins(contacts)
    return [f for f in fins if f.name in loaded]


def _fin_mesh_path(shell: ShellConfig, spec: FinSpec, contacts: FinContacts, idx: int,
                   stage_dir: Path, comm) -> Path:
    """The fin's mesh: as given, or (``shell.local_mesh_size``) re-meshed with that element size
    within r_ex + 2 local sizes of the fin's contact points (``shell.local_mesh_scheme``),
    written to ``stage_dir/<fin>/mesh.msh`` (rank 0)."""
    pts = contacts.point[contacts.fin == idx] if idx >= 0 else np.zeros((0, 3))
    if shell.local_mesh_size is None or shell.load is not None or not len(pts):
        return spec.mesh_path
    from flexnet_fe.missile.mesh import fin_outline_from_msh, write_refined_fin_mesh
    widths = contacts.width[contacts.fin == idx]
    radius = float(hotspot.exclusion_radius(spec.thickness, widths,
                                            max(shell.stvenant_radius_factor, 1.0)).max())
    path = Path(stage_dir) / spec.name / "mesh.msh"
    if comm.rank == 0:
        corners, h = fin_outline_from_msh(spec.mesh_path)
        write_refined_fin_mesh(corners, max(h, shell.local_mesh_size), pts,
                               shell.local_mesh_size, radius + 2.0 * shell.local_mesh_size, path,
                               scheme=shell.local_mesh_scheme)
    comm.barrier()
    return path


def fin_material(spec: FinSpec, shell: ShellConfig) -> ShellMaterial:
    """The shell material of a fin: its section and material from the missile, κ from ``[shell]``."""
    return ShellMaterial(thickness=spec.thickness, youngs_modulus=spec.youngs_modulus,
                         poisson_ratio=spec.poisson_ratio, density=spec.density,
                         yield_strength=spec.yield_strength, shear_correction=shell.shear_correction)


def setup_fin(shell: ShellConfig, spec: FinSpec, contacts: FinContacts, acc_t, acc,
               stage_dir: Path, end_time: float, log, comm) -> FinJob:
    """Mesh, model, loads, St-Venant zones, window and output of one fin (serial, dolfinx)."""
    idx = contacts.fin_names.index(spec.name) if spec.name in contacts.fin_names else -1
    fin_mesh = load_fin_mesh(_fin_mesh_path(shell, spec, contacts, idx, stage_dir, comm), comm)
    model = build_model(fin_mesh, fin_material(spec, shell), shell.rotary_inertia_scale, supports=dict(shell.supports),
                        mass_scaling=shell.mass_scaling)
    if shell.load is not None:
        loads = pressure_history(model, shell.load.times, shell.load.pressure)
    else:
        loads = fin_load_history(model, contacts, idx, acc_t, acc)
    zones = FinZones(model, contacts, idx, shell.stvenant_radius_factor)
    if shell.window == "fin" and shell.load is None:
        window = fin_window(contacts.t, zones.sample, end_time, shell.end_margin, acc_t, acc,
                            fixed_end=shell.end_time is not None)
    else:
        window = FinWindow(0.0, end_time)
    return prepare_fin(model, loads, shell, window, Path(stage_dir) / spec.name, log,
                       name=spec.name, zones=zones)


MASS_SCALING_MEASURED = 1.25
"""The largest ``shell.mass_scaling`` measured to move none of radar_traction's eight fin peaks and
strike envelopes by 2 % against no scaling (−1.0…+1.7 %, thirtieth session; 1.5 moved a rudder peak
+4.7 %; docs/validation.md, "Selective mass scaling"). A larger ratio adds a warning per scaled fin."""

WINDOW_BOUND_FACTOR = 2.0
"""[-] Safety factor on :func:`omitted_stress`, which is solved on the fin's own unrefined
mesh: its peak sits at a corner of the clamped root, where it grows ×1.18–1.19 per halving of the
mesh (infrared × traction's wing_1 and rudder_1, 20 → 10 → 5 mm: 0.289 → 0.345 → 0.406 and
0.293 → 0.352 → 0.405 MPa; docs/validation.md, "The time window's bound"); 2 covers four
halvings (1.19⁴ = 2.0), down to the 1.25 mm of the cases' local meshes."""


def omitted_stress(spec: FinSpec, shell: ShellConfig, accel_t: np.ndarray, accel: np.ndarray,
                   t_from: float, t_to: float, end: float) -> float:
    """How far the body acceleration a fin's window leaves out over [t_from, t_to) [s] can move
    the fin's stresses up to ``end`` [s]: the peak von Mises [Pa] of the fin's response to −m a(t)
    on that interval only (zero elsewhere; ``accel_t`` (na,) [s], ``accel`` (na, 3) [m/s²], linear
    between samples), from rest at t_from, over [t_from, end] (before :data:`WINDOW_BOUND_FACTOR`);
    0 when there is none.

    Superposition (the shell is linear, time-invariant and starts at rest): before the window
    (t_from = 0, t_to = its start, end = its end) a run from t = 0 is the window's run (from rest
    at its start, every load from then on) plus this response; after it (t_from = the window's end,
    t_to = end = the stage's end) a run on to the stage's end is the window's run continued
    without loads (its free vibration: ``after_last_load_over_peak``) plus this response. Von
    Mises is a seminorm of the stress (the root of a positive semi-definite quadratic form), so
    at every point and instant |σ_vm(full) − σ_vm(window)| ≤ σ_vm(response), and the peaks differ
    by at most its largest value. The response, a smooth inertial field, is solved here on the
    fin's own mesh (``spec.mesh_path``, no refinement at the loads; 0.2–1.3 s per paper fin and
    side, after the loops), on this process alone (identical on every rank), stresses every step."""
    from flexnet_fe.shell import api

    at, aa = np.asarray(accel_t, float), np.asarray(accel, float).reshape(-1, 3)
    if at.size == 0 or t_to <= t_from or end <= t_from:
        return 0.0
    inside = (at > t_from) & (at < t_to)
    # (zero outside the samples, as the stage's kernel reads them: shell.kernel._frame_accel)
    ends = np.array([[np.interp(t, at, aa[:, c], left=0.0, right=0.0) for c in range(3)] for t in (t_from, t_to)])
    times = np.concatenate([[t_from], at[inside], [t_to, t_to * (1 + 1e-9) + 1e-12]]) - t_from
    values = np.vstack([ends[:1], aa[inside], ends[1:], np.zeros(3)])  # a(t) on the interval only
    if not np.any(values):
        return 0.0
    model = build_model(load_fin_mesh(spec.mesh_path, MPI.COMM_SELF), fin_material(spec, shell),
                        shell.rotary_inertia_scale, supports=dict(shell.supports))
    span = end - t_from
    loads = LoadHistory(times=np.array([0.0, span]), nodal=sparse.csc_matrix((model.op.n_owned, 2)),
                        accel_times=times, accel=values, mass_c=translational_mass(model.op))
    return float(api.solve(model, loads, end_time=span).run.peak_vm)


def _fin_summary(job: FinJob, res: dict, shell: ShellConfig, spec: FinSpec,
                 warnings: list[str]) -> dict:
    """The fin's summary completed with the closed-form bearing stress and the window's
    neglected body acceleration; their warnings appended to ``warnings``."""
    zones, model = job.zones, job.model
    b = zones.bearing(model, shell.bearing_rope_modulus)
    allow_b = shell.bearing_allowable_factor * spec.yield_strength
    fmax = float(np.linalg.norm(zones.forces, axis=1).max(initial=0.0))
    fin_mass = float(job.loads.mass_c.sum(axis=1).max(initial=0.0))
    win = job.window
    before, after = ((fin_mass * a / fmax if fmax > 0 else 0.0)
                     for a in (win.accel_before_mps2, win.accel_after_mps2))
    t0, t1 = res["start_time_s"], res["end_time_s"]
    stage_end = win.stage_end_s if math.isfinite(win.stage_end_s) else t1
    bound = WINDOW_BOUND_FACTOR * (omitted_stress(spec, shell, job.loads.accel_times, job.loads.accel, 0.0, t0, t1)
                                   if win.accel_before_mps2 > 0.0 else 0.0)
    bound_after = WINDOW_BOUND_FACTOR * (omitted_stress(spec, shell, job.loads.accel_times, job.loads.accel,
                                                        t1, stage_end, stage_end)
                                         if win.accel_after_mps2 > 0.0 else 0.0)
    peak = res["peak_von_mises_pa"]
    res.update(local_mesh_size_m=shell.local_mesh_size, h_min_m=model.h_min,
               peak_bearing_pa=b.peak_pa, peak_bearing_time_s=b.time_s,
               peak_bearing_kind=b.kind, peak_bearing_location_m=b.location_m,
               peak_bearing_force_n=b.force_n, bearing_allowable_pa=allow_b,
               bearing_over_allowable=b.peak_pa / allow_b,
               window_accel_before_mps2=win.accel_before_mps2,
               window_accel_after_mps2=win.accel_after_mps2,
               window_force_ratio_before=before, window_force_ratio_after=after,
               window_before_stress_bound_pa=bound,
               window_before_stress_bound_rel=bound / peak if peak > 0 else 0.0,
               window_after_stress_bound_pa=bound_after,
               window_after_stress_bound_rel=bound_after / peak if peak > 0 else 0.0)
    if b.peak_pa > allow_b:
        warnings.append(
            f"shell {spec.name}: local bearing/contact stress {b.peak_pa / 1e6:.4g} MPa "
            f"({b.kind} load {b.force_n / 1e3:.3g} kN at {1e3 * b.time_s:.4g} ms, closed "
            f"form) exceeds the bearing allowable {allow_b / 1e6:.4g} MPa "
            f"({shell.bearing_allowable_factor:g} x yield): the fin is crushed there")
    if res["peak_error_estimate_rel"] > shell.peak_error_tolerance:
        how = (f" (the mesh halved at the loads reads {res['peak_check']['peak_von_mises_pa'] / 1e6:.4g} MPa)"
               if "peak_check" in res else " (ZZ recovery)")
        warnings.append(
            f"shell {spec.name}: peak von Mises {res['peak_von_mises_pa'] / 1e6:.4g} MPa has "
            f"an estimated error of {100 * res['peak_error_estimate_rel']:.3g} %{how} (> "
            f"{100 * shell.peak_error_tolerance:.3g} %, shell.peak_error_tolerance): refine "
            f"the fin mesh at the loads (shell.local_mesh_size)")
    ms = model.mass_scaling
    if ms["added_mass_rel"] > 0.0 and ms["ratio"] > MASS_SCALING_MEASURED:
        warnings.append(
            f"shell {spec.name}: selective mass scaling (shell.mass_scaling = {ms['ratio']:g}) "
            f"added {ms['added_mass_rel']:.2e} of the fin's mass on {ms['cells']} cells (up to "
            f"x{ms['max_factor']:.3g} per node), beyond the {MASS_SCALING_MEASURED:g} measured to move no peak "
            f"by 2 %: on radar_traction's fins 1.5 moved the rudders' strike peaks by up to +4.7 % "
            f"(docs/validation.md, \"Selective mass scaling\")")
    span = f"{1e3 * res['start_time_s']:.4g}–{1e3 * res['end_time_s']:.4g} ms"
    free = res.get("after_last_load_over_peak")
    if free is not None and free > FREE_VIBRATION_LIMIT:
        warnings.append(
            f"shell {spec.name}: after its last load the fin vibrates freely (undamped) at up to "
            f"{100 * free:.3g} % of its peak within shell.end_margin (> {100 * FREE_VIBRATION_LIMIT:.3g} "
            f"%): a later, larger peak of that vibration is not ruled out; raise shell.end_margin "
            f"(docs/validation.md, \"After the window\")")
    for side, accel, b, what in (("before", win.accel_before_mps2, bound, "move the peak"),
                                 ("after", win.accel_after_mps2, bound_after, "raise the stresses after it")):
        if b > shell.peak_error_tolerance * peak:
            warnings.append(
                f"shell {spec.name}: the time window ({span}) leaves out a body acceleration of up to "
                f"{accel:.4g} m/s² {side} it, which can {what} by up to {b / 1e6:.4g} MPa "
                f"({100 * b / peak if peak > 0 else math.inf:.3g} % of the peak, > "
                f"{100 * shell.peak_error_tolerance:.3g} %, shell.peak_error_tolerance; by "
                f"superposition, ×{WINDOW_BOUND_FACTOR:g}): set shell.window = 'full'")
    return res


def rerun_fins(shell: ShellConfig, runs: Iterable[tuple[FinSpec, FinContacts, Path, float]], accel, title: str,
               log, comm, workers: int) -> list[dict]:
    """Fins run again, each (spec, its loads, the folder its output goes under, its end time [s])
    with ``shell`` (its end_time set to that end), set up one after the other and run on
    ``workers`` threads as they are set up; each one's result dict (:func:`finish_fin`) in order,
    finished as its run ends (no job list is kept: the check's memory is one fin per thread).
    ``runs`` may be a generator: it is read as the fins are set up."""
    with progress_bar(0, title) as bar:
        def set_up():
            for spec, contacts, folder, end in runs:
                job = setup_fin(shell.model_copy(update={"end_time": end}), spec, contacts, *accel, folder, end,
                                 log, comm)
                with IO_LOCK:
                    bar.total += job.steps.n_steps
                    bar.refresh()
                yield job

        def run_and_finish(job: FinJob) -> dict:
            res = run_fin(job, shell, bar, log)
            with IO_LOCK:
                return finish_fin(job, res, shell)

        return run_as_ready(set_up(), run_and_finish, workers)


PEAK_CHECK_AFTER_S = 1e-4
"""[s] ``shell.peak_check`` runs each fin to this long after its peak instant: a rope strike's
stress peak follows the strike within a few µs (radar × rotary's rudder_4 corner: 30 µs)."""


def check_peaks(shell: ShellConfig, specs: list[FinSpec], results: list[RunResult], fin_res: list[dict],
                contacts: FinContacts, accel, stage_dir: Path, log, comm, workers: int,
                warnings: list[str]) -> None:
    """``shell.peak_check``: each fin with a peak again, on the mesh a run at half the local size
    would use (refined at all its loads), from the same start to its peak instant +
    PEAK_CHECK_AFTER_S: that run's first part, so the same numbers up to there; written to
    ``stage_dir/peak_check/<fin>/``. Each fin's result dict (``fin_res``,
    :func:`finish_fin`) gains ``peak_check`` (the finer peak, its move over the peak, the run's size)
    and its error estimate becomes the mesh halving's, ``peak_error_estimate_kind = "mesh_halving"``:
    2 |σ_h/2 − σ_h| / σ_h — Richardson's error of σ_h, (σ_h/2 − σ_h) 2^p / (2^p − 1), for the
    smallest order p = 1 (the paper fins' observed orders are 1.5–4, docs/validation.md). A stress of
    the full run after the check's end that comes within that estimate of the finer peak is a
    warning (the check did not see the time it could overtake in)."""
    half = shell.model_copy(update={"local_mesh_size": shell.local_mesh_size / 2, "peak_check": False})
    loaded = loaded_fins(contacts)
    # (a fin without contact loads keeps its mesh at any local size: nothing to halve, ZZ stays)
    todo = [i for i, r in enumerate(fin_res) if r["peak_von_mises_pa"] > 0 and specs[i].name in loaded]
    ends = {i: fin_res[i]["peak_time_s"] + PEAK_CHECK_AFTER_S for i in todo}
    fine = rerun_fins(half, [(specs[i], contacts, Path(stage_dir) / "peak_check", ends[i]) for i in todo],
                      accel, f"shell peak check ({len(todo)} fins)", log, comm, workers)
    for i, f in zip(todo, fine):
        r = fin_res[i]
        move = f["peak_von_mises_pa"] / r["peak_von_mises_pa"] - 1.0
        later = float(results[i].vm[results[i].t > ends[i]].max(initial=0.0))
        r["peak_check"] = {"local_mesh_size_m": half.local_mesh_size, "end_time_s": ends[i],
                           "peak_von_mises_pa": f["peak_von_mises_pa"], "peak_time_s": f["peak_time_s"],
                           "peak_location_m": f["peak_location_m"], "move_rel": move,
                           "later_von_mises_pa": later, "dofs": f["dofs"], "steps": f["steps"]}
        r["peak_zz_estimate_rel"] = r["peak_error_estimate_rel"]
        r["peak_error_estimate_rel"], r["peak_error_estimate_kind"] = 2.0 * abs(move), "mesh_halving"
        if later * (1.0 + 2.0 * abs(move)) > f["peak_von_mises_pa"]:
            warnings.append(
                f"shell {specs[i].name}: after the peak check's end ({1e3 * ends[i]:.4g} ms) the fin reaches "
                f"{later / 1e6:.4g} MPa, within the check's error of its finer peak "
                f"{f['peak_von_mises_pa'] / 1e6:.4g} MPa: a later peak may overtake on the finer mesh")


def check_strikes(shell: ShellConfig, specs: list[FinSpec], fin_res: list[dict], contacts: FinContacts,
                  accel, stage_dir: Path, log, comm, workers: int) -> None:
    """``shell.strike_envelope``: each loaded fin with a peak again, with all its contact loads
    moved in span along its leading edge by each of :data:`strikes.STRIKE_OFFSETS` × its rope
    diameter (the largest contact width; ``strikes.move_along_leading_edge``, kept on the fin),
    on the mesh its run would build for those loads, from its window's start to its peak instant
    + PEAK_CHECK_AFTER_S; written to ``stage_dir/strike_envelope/<offset>/<fin>/``. Each fin's
    result dict gains ``strike_envelope`` (offsets [m], their peaks [Pa], times [s] and locations
    [m], the reruns' end [s]) and ``strike_envelope_von_mises_pa``: the largest of those peaks and the fin's own —
    a bound over where along its edge the rope strikes, which the model does not fix to better
    than about a diameter (``shell.strikes``). The move keeps every force and instant, so momentum
    and the impulse per fin are those of the collision."""
    from flexnet_fe.missile.mesh import fin_outline_from_msh
    base = shell.model_copy(update={"peak_check": False, "strike_envelope": False})
    loaded = loaded_fins(contacts)
    todo = [i for i, r in enumerate(fin_res) if r["peak_von_mises_pa"] > 0 and specs[i].name in loaded]
    runs = [(i, f) for i in todo for f in strikes.STRIKE_OFFSETS]
    ends = {i: fin_res[i]["peak_time_s"] + PEAK_CHECK_AFTER_S for i in todo}
    frames, diameters = {}, {}
    for i in todo:
        mine = contacts.fin == loaded[specs[i].name]
        frames[i] = strikes.planform(fin_outline_from_msh(specs[i].mesh_path)[0])
        diameters[i] = float(contacts.width[mine].max())

    def moved_runs():  # each moved copy of the loads made as its fin is set up, then dropped
        for i, f in runs:
            mine = contacts.fin == loaded[specs[i].name]
            point = contacts.point.copy()
            point[mine] = strikes.move_along_leading_edge(contacts.point[mine], frames[i], f * diameters[i])
            yield (specs[i], replace(contacts, point=point), Path(stage_dir) / "strike_envelope" / f"{f:+g}d",
                   ends[i])

    moved = rerun_fins(base, moved_runs(), accel,
                       f"shell strike envelope ({len(todo)} fins x {len(strikes.STRIKE_OFFSETS)} moves)",
                       log, comm, workers)
    for i in todo:
        r = fin_res[i]
        mine = [(f * diameters[i], m) for (j, f), m in zip(runs, moved) if j == i]
        peaks = [m["peak_von_mises_pa"] for _, m in mine]
        r[FIN_STRIKE_ENVELOPE] = max([r["peak_von_mises_pa"], *peaks])
        r["strike_envelope"] = {
            "offsets_m": [o for o, _ in mine], "peaks_pa": peaks,
            "peak_times_s": [m["peak_time_s"] for _, m in mine],
            "peak_locations_m": [m["peak_location_m"] for _, m in mine], "end_time_s": ends[i]}


def stage_end_time(shell: ShellConfig, contacts: FinContacts, acc_t: np.ndarray) -> float:
    """The stage's end [s]: ``shell.end_time``, else the last contact sample or body-acceleration
    row (or given pressure time) + ``shell.end_margin``."""
    last = max(contacts.t[-1] if len(contacts.t) else 0.0, acc_t[-1] if len(acc_t) else 0.0,
               shell.load.times[-1] if shell.load is not None else 0.0)
    end_time = shell.end_time or last + shell.end_margin
    if end_time <= 0:
        raise CaseError("case.toml", "shell.end_time", "no contact samples and no end_time")
    return end_time


def run_shell(shell: ShellConfig, fins: list[FinSpec], contacts_npz: Path,
              collide_history_csv: Path | None, stage_dir: Path, log: logging.Logger,
              comm: MPI.Comm = MPI.COMM_WORLD) -> dict:
    """The shell stage. Returns the ``shell`` section of summary.json: per fin name
    ``peak_von_mises_pa, peak_time_s, peak_location_m, peak_max_principal_pa`` (and more), plus
    ``dt_s`` (smallest), ``dt_crit_s`` (smallest), ``dofs`` (total), ``steps`` (total),
    ``workers``, ``wall_s`` (``setup_wall_s``: until the last fin is set up; ``loops_wall_s``: from
    then until the last loop ends). The fins are set up one after the other (dolfinx), each one's
    time loop handed to one of ``shell.workers`` threads (one under MPI: in this thread) as soon as
    it is set up, while the next is set up (``schedule.run_as_ready``); then each is finished in order.
    """
    t0 = time.perf_counter()
    if shell.load is not None:  # a given pressure replaces the collision loads
        contacts = FinContacts(fin_names=(), t=np.zeros(0), sample=np.zeros(0, np.int64),
                               fin=np.zeros(0, np.int64), point=np.zeros((0, 3)),
                               force=np.zeros((0, 3)), width=np.zeros(0))
        acc_t, acc = np.zeros(0), np.zeros((0, 3))
        shell = shell.model_copy(update={"fins": FinSelection.ALL}) if \
            shell.fins is FinSelection.LOADED else shell
    else:
        contacts = read_fin_contacts(contacts_npz)
        acc_t, acc = read_body_acceleration(collide_history_csv)
    unknown = [n for n in contacts.fin_names if n not in {f.name for f in fins}]
    if unknown:
        raise CaseError(str(contacts_npz), "fin_names", f"fin(s) {unknown} not in the missile model")
    if contacts.fin.size and shell.bearing_rope_modulus is None:
        raise CaseError("[shell]", "bearing_rope_modulus", "not given, and no [net] table to take the rope's "
                                                           "contact modulus from; the fins have contact loads")
    end_time = stage_end_time(shell, contacts, acc_t)
    specs = select_fins(shell, fins, contacts)
    workers = 1 if comm.size > 1 else min(shell.workers or cpu_count(), max(len(specs), 1))
    log.info("shell: %d fins, their loops on %d thread(s), each as soon as its fin is set up", len(specs),
             workers)
    jobs: list[FinJob] = []
    t_setup = [t0]
    with progress_bar(0, f"shell ({len(specs)} fins, {workers} thread(s))") as bar:
        def set_up():
            for spec in specs:
                job = setup_fin(shell, spec, contacts, acc_t, acc, stage_dir, end_time, log, comm)
                jobs.append(job)
                t_setup[0] = time.perf_counter()
                with IO_LOCK:
                    bar.total += job.steps.n_steps
                    bar.refresh()
                yield job

        results = run_as_ready(set_up(), lambda j: run_fin(j, shell, bar, log), workers)
    t_setup, t_loops = t_setup[0], time.perf_counter()
    summary: dict = {}
    warnings: list[str] = []
    fin_res = [finish_fin(job, res, shell) for job, res in zip(jobs, results)]
    if shell.peak_check:
        check_peaks(shell, specs, results, fin_res, contacts, (acc_t, acc), stage_dir, log, comm, workers, warnings)
    if shell.strike_envelope:
        check_strikes(shell, specs, fin_res, contacts, (acc_t, acc), stage_dir, log, comm, workers)
    for spec, job, res in zip(specs, jobs, fin_res):
        summary[spec.name] = _fin_summary(job, res, shell, spec, warnings)
    sample = load_sampling_warning(contacts)
    if sample:
        warnings.append(sample)
    fs = [summary[s.name] for s in specs]
    summary.update(load_sample_interval_s=load_sample_interval(contacts),
                   load_sampling_resolved=load_sampling_resolved(contacts),
                   dt_s=min((r["dt_s"] for r in fs), default=0.0),
                   dt_crit_s=min((r["dt_crit_s"] for r in fs), default=0.0),
                   dofs=sum(r["dofs"] for r in fs), steps=sum(r["steps"] for r in fs),
                   end_time_s=end_time, workers=workers, warnings=warnings,
                   setup_wall_s=t_setup - t0, loops_wall_s=t_loops - t_setup,
                   finish_wall_s=time.perf_counter() - t_loops, wall_s=time.perf_counter() - t0)
    return summary
