"""The shell stage: fin stress histories from the collision loads (explicit dolfinx solver).

Inputs: the ``[shell]`` table, the fins (mesh + material), ``collide/fin_contacts.npz`` and
``collide/history.csv`` (rigid-body CG acceleration in B). Outputs in ``stage_dir/<fin>/``:
``history.csv`` (float64), ``fields.xdmf`` (6 scalar DG0 stress fields + CG1 displacement,
appended and closed at every output so a killed run keeps its earlier steps) and
``envelope.xdmf`` (peak-over-time von Mises and maximum principal stress per cell).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import ufl
from dolfinx import fem
from dolfinx.io import XDMFFile
from mpi4py import MPI
from scipy import sparse

from flexnet_fe.contact.transfer import FinGeometry, contact_transfer
from flexnet_fe.errors import CaseError, NumericalError
from flexnet_fe.io import read_history_csv, write_history_csv
from flexnet_fe.progress import progress_bar
from flexnet_fe.shell.config import FinSelection, FinSpec, ShellConfig
from flexnet_fe.shell.explicit import (LoadHistory, central_difference, critical_step,
                                       max_eigenvalue, translational_mass)
from flexnet_fe.shell.forms import NDOF_NODE, ShellMaterial
from flexnet_fe.shell.meshio import load_fin_mesh
from flexnet_fe.shell.model import ShellModel, build_model
from flexnet_fe.shell.stress import FIELD_NAMES, StressEvaluator, stress_evaluator

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


class _FieldWriter:
    """XDMF output: mesh written once, then one append-and-close per output step."""

    def __init__(self, model: ShellModel, path: Path):
        mesh = model.V.mesh
        self.path = path
        self.V0 = fem.FunctionSpace(mesh, ("DG", 0))
        self.scalars = [fem.Function(self.V0, name=n) for n in FIELD_NAMES]
        V1 = fem.VectorFunctionSpace(mesh, ("Lagrange", 1))
        self.disp = fem.Function(V1, name="displacement_m")
        self.U = fem.Function(model.V)
        self.disp_expr = fem.Expression(ufl.as_vector([self.U[0], self.U[1], self.U[2]]),
                                        V1.element.interpolation_points())
        self.n_owned_cells = self.V0.dofmap.index_map.size_local
        with XDMFFile(mesh.comm, str(path), "w") as f:
            f.write_mesh(mesh)

    def write(self, t: float, stresses: np.ndarray, u_owned: np.ndarray) -> None:
        for k, fn in enumerate(self.scalars):
            fn.x.array[: self.n_owned_cells] = stresses[:, k]
            fn.x.scatter_forward()
        self.U.x.array[: u_owned.size] = u_owned
        self.U.x.scatter_forward()
        self.disp.interpolate(self.disp_expr)
        with XDMFFile(self.V0.mesh.comm, str(self.path), "a") as f:
            for fn in self.scalars:
                f.write_function(fn, t)
            f.write_function(self.disp, t)


def _write_envelope(writer: _FieldWriter, env: np.ndarray, path: Path) -> None:
    mesh = writer.V0.mesh
    with XDMFFile(mesh.comm, str(path), "w") as f:
        f.write_mesh(mesh)
        for k, name in enumerate(("peak_von_mises_pa", "peak_max_principal_pa")):
            fn = fem.Function(writer.V0, name=name)
            fn.x.array[: writer.n_owned_cells] = env[:, k]
            fn.x.scatter_forward()
            f.write_function(fn, 0.0)


def _global_max(comm, values: np.ndarray, where: np.ndarray) -> tuple[float, np.ndarray]:
    """Largest value over all ranks and its location (3,); NaN location when it is 0."""
    i = int(np.argmax(values)) if len(values) else -1
    v = float(values[i]) if i >= 0 else -np.inf
    best, rank = comm.allreduce((v, comm.rank), op=MPI.MAXLOC)
    if best <= 0.0:  # no stress yet: no meaningful location
        return max(best, 0.0), np.full(3, np.nan)
    loc = comm.bcast(where[i] if comm.rank == rank else None, root=rank)
    return best, np.asarray(loc, dtype=float)


def solve_fin(model: ShellModel, loads: LoadHistory, shell: ShellConfig, end_time: float,
              out_dir: Path, log: logging.Logger, *, name: str) -> dict:
    """Run one fin to ``end_time`` [s]; write history.csv, fields.xdmf, envelope.xdmf in
    ``out_dir``; return the fin's summary (peaks, dt, dt_crit, dofs, steps)."""
    comm = model.V.mesh.comm
    out_dir.mkdir(parents=True, exist_ok=True)
    mat = model.material
    lam, lam_change = max_eigenvalue(model.op, iterations=shell.power_iterations)
    dt_crit = critical_step(lam, shell.rayleigh_alpha, shell.rayleigh_beta)
    dt = shell.safety_factor * dt_crit
    c_p = math.sqrt(mat.plane_stress_modulus / mat.density)
    n_steps = max(1, math.ceil(end_time / dt))
    hist_dt = shell.history_interval or end_time / 400.0
    field_dt = shell.field_interval or end_time / 40.0
    every = max(1, round(hist_dt / dt))
    field_every = max(every, round(field_dt / dt / every) * every)
    dofs = model.V.dofmap.index_map.size_global * NDOF_NODE
    log.info("shell %s: %d DOFs, rotary inertia ×%.3g, dt_crit = %.4e s (power method, %d it, "
             "last change %.1e), "
             "dt = %.4e s (×%.2f), element estimate h_min/c_p = %.4e s, %d steps to %.4e s",
             name, dofs, model.rotary_scale, dt_crit, shell.power_iterations, lam_change, dt,
             shell.safety_factor, model.h_min / c_p, n_steps, end_time)
    ev: StressEvaluator = stress_evaluator(model)
    writer = _FieldWriter(model, out_dir / "fields.xdmf")
    env = np.zeros((ev.n_owned_cells, 2))
    cols = {k: [] for k in ("t_s", "max_von_mises_pa", "max_von_mises_x_m", "max_von_mises_y_m",
                            "max_von_mises_z_m", "max_principal_pa", "max_abs_u_m",
                            "kinetic_energy_j", "strain_energy_j", "external_work_j")}
    peak = {"vm": -1.0, "t": 0.0, "loc": np.zeros(3), "p1": -np.inf}
    gen = central_difference(model.op, loads, dt, n_steps, every, dt_crit=dt_crit,
                             alpha=shell.rayleigh_alpha, beta=shell.rayleigh_beta,
                             growth_limit=shell.energy_growth_limit)
    try:
        with progress_bar(n_steps, f"shell {name}") as bar:
            last = 0
            for smp in gen:
                s = ev.evaluate(smp.u)
                vm = s[:, :3].max(axis=1)
                p1 = s[:, 3:].max(axis=1)
                np.maximum(env[:, 0], vm, out=env[:, 0])
                np.maximum(env[:, 1], p1, out=env[:, 1])
                vmax, loc = _global_max(comm, vm, ev.midpoints)
                p1max = comm.allreduce(float(p1.max()) if len(p1) else -np.inf, op=MPI.MAX)
                umax = comm.allreduce(float(np.sqrt((smp.u.reshape(-1, NDOF_NODE)[:, :3] ** 2)
                                                    .sum(1)).max(initial=0.0)), op=MPI.MAX)
                for k, v in zip(cols, (smp.t, vmax, *loc, p1max, umax, smp.kinetic, smp.strain,
                                       smp.work)):
                    cols[k].append(v)
                if vmax > peak["vm"]:
                    peak.update(vm=vmax, t=smp.t, loc=loc)
                peak["p1"] = max(peak["p1"], p1max)
                if smp.step % field_every == 0 or smp.step == n_steps:
                    writer.write(smp.t, s, smp.u)
                bar.update(smp.step - last)
                last = smp.step
    except NumericalError:
        _flush(comm, out_dir, cols, writer, env)
        raise
    _flush(comm, out_dir, cols, writer, env)
    return {"peak_von_mises_pa": peak["vm"], "peak_time_s": peak["t"],
            "peak_location_m": ([float(x) for x in peak["loc"]]  # None: never stressed
                                if np.all(np.isfinite(peak["loc"])) else None),
            "peak_max_principal_pa": peak["p1"],
            "peak_over_yield": peak["vm"] / mat.yield_strength,
            "max_abs_u_m": float(max(cols["max_abs_u_m"])),
            "dt_s": dt, "dt_crit_s": dt_crit, "dt_element_estimate_s": model.h_min / c_p,
            "rotary_inertia_scale": model.rotary_scale, "dofs": dofs, "steps": n_steps}


def _flush(comm, out_dir: Path, cols: dict, writer: _FieldWriter, env: np.ndarray) -> None:
    if comm.rank == 0:
        write_history_csv(out_dir / "history.csv", {k: np.asarray(v) for k, v in cols.items()})
    _write_envelope(writer, env, out_dir / "envelope.xdmf")


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
    contacts = read_fin_contacts(contacts_npz)
    acc_t, acc = read_body_acceleration(collide_history_csv)
    unknown = [n for n in contacts.fin_names if n not in {f.name for f in fins}]
    if unknown:
        raise CaseError(str(contacts_npz), "fin_names", f"fin(s) {unknown} not in the missile model")
    last = max(contacts.t[-1] if len(contacts.t) else 0.0, acc_t[-1] if len(acc_t) else 0.0)
    end_time = shell.end_time or last + shell.end_margin
    if end_time <= 0:
        raise CaseError("case.toml", "shell.end_time", "no contact samples and no end_time")
    summary: dict = {}
    dts, dtcs, dofs, steps = [], [], 0, 0
    for spec in select_fins(shell, fins, contacts):
        fin_mesh = load_fin_mesh(spec.mesh_path, comm)
        mat = ShellMaterial(thickness=spec.thickness, youngs_modulus=spec.youngs_modulus,
                            poisson_ratio=spec.poisson_ratio, density=spec.density,
                            yield_strength=spec.yield_strength,
                            shear_correction=shell.shear_correction)
        model = build_model(fin_mesh, mat, shell.rotary_inertia_scale)
        idx = contacts.fin_names.index(spec.name) if spec.name in contacts.fin_names else -1
        loads = fin_load_history(model, contacts, idx, acc_t, acc)
        res = solve_fin(model, loads, shell, end_time, Path(stage_dir) / spec.name, log,
                        name=spec.name)
        summary[spec.name] = res
        dts.append(res["dt_s"])
        dtcs.append(res["dt_crit_s"])
        dofs += res["dofs"]
        steps += res["steps"]
    summary.update(dt_s=min(dts, default=0.0), dt_crit_s=min(dtcs, default=0.0), dofs=dofs,
                   steps=steps, end_time_s=end_time, wall_s=time.perf_counter() - t0)
    return summary
