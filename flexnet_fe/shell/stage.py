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
from dataclasses import dataclass
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
from flexnet_fe.shell.model import ShellModel, build_model
from flexnet_fe.shell.recovery import locate_peak, stress_tensors, von_mises
from flexnet_fe.shell.solve import ParallelSampler, recovery_for, run
from flexnet_fe.runs import ENVELOPE_XDMF, FIELDS_XDMF, HISTORY

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


def _time_steps(model: ShellModel, shell: ShellConfig, end_time: float, log, name: str):
    """dt_crit (Lanczos), dt, step count, sampling and frame strides."""
    lam, resid = max_eigenvalue(model.op, steps=shell.lanczos_steps)
    dt_crit = critical_step(lam, shell.rayleigh_alpha, shell.rayleigh_beta)
    dt = shell.safety_factor * dt_crit
    every = max(1, round(shell.history_interval / dt))
    # whole sampling intervals, so that the last step is a sample in both backends (the PETSc
    # path also samples the last step; the compiled one samples multiples of ``every`` only)
    n_steps = every * max(1, math.ceil(end_time / (dt * every)))
    field_dt = shell.field_interval or end_time / 10.0
    field_every = max(every, round(field_dt / dt / every) * every)
    mat = model.material
    c_p = math.sqrt(mat.plane_stress_modulus / mat.density)
    dofs = model.V.dofmap.index_map.size_global * NDOF_NODE
    log.info("shell %s: %d DOFs, rotary inertia ×%.3g, dt_crit = %.4e s (Lanczos, %d steps, "
             "residual %.1e), dt = %.4e s (×%.2f), element estimate h_min/c_p = %.4e s, "
             "%d steps to %.4e s, stresses sampled every %d steps", name, dofs,
             model.rotary_scale, dt_crit, shell.lanczos_steps, resid, dt, shell.safety_factor,
             model.h_min / c_p, n_steps, end_time, every)
    return dt_crit, dt, n_steps, every, field_every, dofs


def _peak(model: ShellModel, R, res, writer: _FieldWriter):
    """Located peak (value, location, surface, ZZ error estimate) on the rank owning it."""
    comm = model.V.mesh.comm
    owner = comm.allreduce(comm.rank if res.peak_node >= 0 else comm.size, op=MPI.MIN)
    if owner >= comm.size or res.peak_vm <= 0.0:
        return None
    U = writer.sampler.U
    U.x.array[: res.u_peak.size] = res.u_peak
    U.x.scatter_forward()
    pk = None
    if comm.rank == owner:
        x = model.V.tabulate_dof_coordinates()
        pk = locate_peak(R, U.x.array, res.peak_node, x, model.fin.plane.origin)
    return comm.bcast(pk, root=owner)


def solve_fin(model: ShellModel, loads: LoadHistory, shell: ShellConfig, end_time: float,
              out_dir: Path, log: logging.Logger, *, name: str) -> dict:
    """Run one fin to ``end_time`` [s]; write history.csv, fields.xdmf (frames every
    ``field_interval`` plus the running peak's instants), envelope.xdmf in ``out_dir``; return
    the fin's summary (peaks with their error estimate, dt, dt_crit, dofs, steps)."""
    comm = model.V.mesh.comm
    out_dir.mkdir(parents=True, exist_ok=True)
    dt_crit, dt, n_steps, every, field_every, dofs = _time_steps(model, shell, end_time, log, name)
    R = recovery_for(model)
    writer = _FieldWriter(model, R, out_dir / FIELDS_XDMF)
    with progress_bar(n_steps, f"shell {name}") as bar:
        done = [0]

        def frame(t: float, u: np.ndarray) -> None:
            writer.write(t, u)
            k = min(n_steps, int(round(t / dt)))
            if k > done[0]:
                bar.update(k - done[0])
                done[0] = k

        res = run(model, loads, R, dt=dt, n_steps=n_steps, sample_every=every,
                  frame_every=field_every, alpha=shell.rayleigh_alpha, beta=shell.rayleigh_beta,
                  growth_limit=shell.energy_growth_limit, frame=frame,
                  backend=Backend(shell.backend))
    pk = None if res.failed_at else _peak(model, R, res, writer)
    vm, loc = res.vm.copy(), res.loc.copy()
    if pk is not None:  # the peak row carries the located peak (≥ its nodal value)
        i = int(np.argmax(res.vm))
        vm[i], loc[i] = max(pk.value, vm[i]), pk.location
    cols = {"t_s": res.t, "max_von_mises_pa": vm, "max_von_mises_x_m": loc[:, 0],
            "max_von_mises_y_m": loc[:, 1], "max_von_mises_z_m": loc[:, 2],
            "max_principal_pa": res.p1, "max_abs_u_m": res.umax, "kinetic_energy_j": res.ke,
            "strain_energy_j": res.se, "external_work_j": res.work}
    if comm.rank == 0:
        write_history_csv(out_dir / HISTORY, cols)
    writer.envelope(res.env, out_dir / ENVELOPE_XDMF)
    if res.failed_at:
        raise NumericalError(
            f"shell solver unstable at step {res.failed_at} (t = {res.failed_at * dt:.6e} s): "
            f"kinetic + strain energy exceeds {shell.energy_growth_limit} × (initial energy + "
            f"external work); dt = {dt:.4e} s, dt_crit = {dt_crit:.4e} s "
            f"(dt/dt_crit = {dt / dt_crit:.3f})")
    mat = model.material
    c_p = math.sqrt(mat.plane_stress_modulus / mat.density)
    out = {"peak_von_mises_pa": float(vm.max(initial=0.0)), "peak_time_s": res.peak_t,
           "peak_location_m": [float(v) for v in pk.location] if pk else None,
           "peak_surface": pk.surface if pk else None,
           "peak_error_estimate_rel": pk.error_estimate_rel if pk else 0.0,
           "peak_nodal_von_mises_pa": max(res.peak_vm, 0.0),
           "peak_max_principal_pa": res.peak_p1,
           "allowable_pa": mat.yield_strength,
           "peak_over_allowable": float(vm.max(initial=0.0)) / mat.yield_strength,
           "max_abs_u_m": float(res.umax.max(initial=0.0)),
           "dt_s": dt, "dt_crit_s": dt_crit, "dt_element_estimate_s": model.h_min / c_p,
           "rotary_inertia_scale": model.rotary_scale, "dofs": dofs, "steps": n_steps,
           "sample_interval_s": every * dt}
    return out


def fin_specs(fins, mesh_paths: dict) -> list[FinSpec]:
    """FinSpecs from the missile model's fins (objects with ``name``, ``thickness`` and
    ``material.{youngs_modulus, poisson_ratio, density, yield_strength}``) and the fin meshes
    ``{fin name: .msh path}`` written by the missile mesher."""
    return [FinSpec(name=f.name, mesh_path=Path(mesh_paths[f.name]), thickness=f.thickness,
                    youngs_modulus=f.material.youngs_modulus,
                    poisson_ratio=f.material.poisson_ratio, density=f.material.density,
                    yield_strength=f.material.yield_strength) for f in fins]


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
    loaded = {contacts.fin_names[i] for i in np.unique(contacts.fin)}
    return [f for f in fins if f.name in loaded]


def run_shell(shell: ShellConfig, fins: list[FinSpec], contacts_npz: Path,
              collide_history_csv: Path | None, stage_dir: Path, log: logging.Logger,
              comm: MPI.Comm = MPI.COMM_WORLD) -> dict:
    """The shell stage. Returns the ``shell`` section of summary.json: per fin name
    ``peak_von_mises_pa, peak_time_s, peak_location_m, peak_max_principal_pa`` (and more), plus
    ``dt_s`` (smallest), ``dt_crit_s`` (smallest), ``dofs`` (total), ``steps`` (total), ``wall_s``.
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
    last = max(contacts.t[-1] if len(contacts.t) else 0.0, acc_t[-1] if len(acc_t) else 0.0,
               shell.load.times[-1] if shell.load is not None else 0.0)
    end_time = shell.end_time or last + shell.end_margin
    if end_time <= 0:
        raise CaseError("case.toml", "shell.end_time", "no contact samples and no end_time")
    summary: dict = {}
    warnings: list[str] = []
    dts, dtcs, dofs, steps = [], [], 0, 0
    for spec in select_fins(shell, fins, contacts):
        fin_mesh = load_fin_mesh(spec.mesh_path, comm)
        mat = ShellMaterial(thickness=spec.thickness, youngs_modulus=spec.youngs_modulus,
                            poisson_ratio=spec.poisson_ratio, density=spec.density,
                            yield_strength=spec.yield_strength,
                            shear_correction=shell.shear_correction)
        model = build_model(fin_mesh, mat, shell.rotary_inertia_scale,
                            supports=dict(shell.supports))
        if shell.load is not None:
            loads = pressure_history(model, shell.load.times, shell.load.pressure)
        else:
            idx = contacts.fin_names.index(spec.name) if spec.name in contacts.fin_names else -1
            loads = fin_load_history(model, contacts, idx, acc_t, acc)
        res = solve_fin(model, loads, shell, end_time, Path(stage_dir) / spec.name, log,
                        name=spec.name)
        summary[spec.name] = res
        if res["peak_error_estimate_rel"] > shell.peak_error_tolerance:
            warnings.append(
                f"shell {spec.name}: peak von Mises {res['peak_von_mises_pa'] / 1e6:.4g} MPa has "
                f"an estimated error of {100 * res['peak_error_estimate_rel']:.3g} % (> "
                f"{100 * shell.peak_error_tolerance:.3g} %, shell.peak_error_tolerance): refine "
                f"the fin mesh")
        dts.append(res["dt_s"])
        dtcs.append(res["dt_crit_s"])
        dofs += res["dofs"]
        steps += res["steps"]
    summary.update(dt_s=min(dts, default=0.0), dt_crit_s=min(dtcs, default=0.0), dofs=dofs,
                   steps=steps, end_time_s=end_time, warnings=warnings,
                   wall_s=time.perf_counter() - t0)
    return summary
