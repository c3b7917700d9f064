"""Explicit central-difference elastodynamics of the shell: M ü + C u̇ + K u = f(t).

The stiffness K is assembled once (block size 5, PETSc BAIJ) and applied by one sparse
product per step; M is the lumped diagonal (:mod:`flexnet_fe.shell.mass`); C = αM + βK
(Rayleigh). Clamped DOFs have M⁻¹ = 0, so they never move.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import Iterator

import numpy as np
from dolfinx import fem
from dolfinx.fem.petsc import assemble_matrix
from mpi4py import MPI
from petsc4py import PETSc
from numba import njit
from scipy import sparse

from flexnet_fe.errors import NumericalError
from flexnet_fe.shell.forms import NDOF_NODE


class MatFormat(str, Enum):
    """PETSc storage of K for the per-step product (DESIGN.md §2)."""

    AIJ = "aij"
    BAIJ = "baij"
    SBAIJ = "sbaij"


@dataclass(frozen=True)
class ShellOperator:
    """What never changes during a run: K, the inverse lumped mass, the free-DOF set."""

    K: PETSc.Mat
    """stiffness [N/m, N, N m], global, no supports applied (see :func:`assemble_operator`)"""
    mass: np.ndarray
    """lumped mass of the owned DOFs, shape (n_owned·5,) [kg | kg m²]"""
    minv: np.ndarray
    """1/mass on free DOFs, 0 on fixed DOFs, shape (n_owned·5,)"""
    x_nodes: np.ndarray
    """coordinates of the owned nodes [m], shape (n_owned, 3)"""
    comm: MPI.Comm

    @property
    def n_owned(self) -> int:
        return self.mass.size


def assemble_operator(a_forms: list, V: fem.FunctionSpace, mass: PETSc.Vec, fixed: np.ndarray,
                      fmt: MatFormat = MatFormat.SBAIJ) -> ShellOperator:
    """Assemble K once as the sum of the bilinear forms ``a_forms`` and convert it to ``fmt``;
    build M⁻¹ with zeros on the ``fixed`` DOFs (local unrolled indices, owned or ghost).

    Supports are imposed through M⁻¹ = 0 only: a fixed DOF starts at zero and never
    accelerates, so K needs no modification (it stays symmetric; its rows at fixed DOFs are the
    reactions, which the solver ignores).
    """
    K = assemble_matrix(fem.form(a_forms[0]))
    K.assemble()
    for a in a_forms[1:]:
        Ki = assemble_matrix(fem.form(a))
        Ki.assemble()
        K.axpy(1.0, Ki, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        Ki.destroy()
    if fmt is MatFormat.SBAIJ:
        K.setOption(PETSc.Mat.Option.SYMMETRIC, True)  # the shell energy is a symmetric form
    if fmt is not MatFormat.AIJ:
        K = K.convert(fmt.value)
    n_owned = V.dofmap.index_map.size_local * NDOF_NODE
    m = mass.getArray(readonly=True)[:n_owned].copy()
    if np.any(m <= 0):
        raise NumericalError("lumped mass has a non-positive entry: the mesh has a degenerate cell")
    minv = 1.0 / m
    minv[fixed[fixed < n_owned]] = 0.0
    x_nodes = V.tabulate_dof_coordinates()[: V.dofmap.index_map.size_local].copy()
    return ShellOperator(K=K, mass=m, minv=minv, x_nodes=x_nodes, comm=V.mesh.comm)


def _vec(op: ShellOperator, arr: np.ndarray) -> PETSc.Vec:
    """A PETSc Vec sharing memory with the owned-DOF array ``arr``."""
    return PETSc.Vec().createWithArray(arr, bsize=NDOF_NODE, comm=op.comm)


def max_eigenvalue(op: ShellOperator, *, iterations: int = 1000) -> tuple[float, float]:
    """Largest eigenvalue λ_max of M⁻¹K [1/s²] by the power method on the symmetric
    B = M^{-1/2} K M^{-1/2} (same spectrum). Returns (λ_max, relative change of the estimate
    over the last 10 iterations).

    The Rayleigh quotient approaches λ_max from below (the safety factor covers the remainder;
    the tests measure it against Lanczos). A fixed iteration count and a start vector that
    depends only on node coordinates (not on the DOF numbering, which changes with the number
    of processes) make serial and parallel runs agree to round-off, so they take the same step.
    """
    comm = op.comm
    d = np.sqrt(op.minv)
    lo, hi = np.empty(3), np.empty(3)
    comm.Allreduce(op.x_nodes.min(axis=0, initial=np.inf), lo, op=MPI.MIN)
    comm.Allreduce(op.x_nodes.max(axis=0, initial=-np.inf), hi, op=MPI.MAX)
    span = float((hi - lo).max()) or 1.0
    phase = ((op.x_nodes - lo) / span) @ np.array([37.1, 53.3, 71.9])
    x = np.sin(phase[:, None] * (1.0 + np.arange(NDOF_NODE))[None, :] + 0.3).ravel() * (d > 0)
    z, y = np.zeros_like(x), np.zeros_like(x)
    zv, yv = _vec(op, z), _vec(op, y)
    history = []
    for _ in range(max(iterations, 11)):
        x /= np.sqrt(comm.allreduce(float(x @ x), op=MPI.SUM))
        np.multiply(d, x, out=z)
        op.K.mult(zv, yv)
        y *= d
        history.append(comm.allreduce(float(x @ y), op=MPI.SUM))
        x[:] = y
    lam = history[-1]
    return lam, abs(lam - history[-11]) / abs(lam)


def critical_step(lam_max: float, alpha: float = 0.0, beta: float = 0.0) -> float:
    """Stability limit of central differences [s]: dt_crit = (2/ω)(√(1+ξ²) − ξ), ω = √λ_max,
    ξ = α/(2ω) + βω/2 the Rayleigh damping ratio at ω (Belytschko, Liu & Moran 2000, §6.3)."""
    w = np.sqrt(lam_max)
    xi = alpha / (2.0 * w) + beta * w / 2.0
    return 2.0 / w * (np.sqrt(1.0 + xi ** 2) - xi)


def _bracket(times: np.ndarray, t: float) -> tuple[int, float] | None:
    """Index k and fraction s with t = (1−s) times[k] + s times[k+1]; None outside the samples."""
    if len(times) == 0 or t < times[0] or t > times[-1]:
        return None
    if len(times) == 1:
        return 0, 0.0
    k = min(int(np.searchsorted(times, t, side="right")) - 1, len(times) - 2)
    return k, (t - times[k]) / (times[k + 1] - times[k])


@dataclass(frozen=True)
class LoadHistory:
    """External nodal loads f(t) on the owned DOFs, linear in time between samples.

    f(t) = P(t) − Σ_c a_c(t) m_c: P the contact loads sampled at ``times`` and a(t) the rigid-body
    acceleration of the body frame sampled at ``accel_times`` (the inertial load −ρ t a of the
    accelerating frame, lumped as −m_c a_c on the translational DOFs). Both are zero outside
    their sample ranges.
    """

    times: np.ndarray
    """contact sample times [s], shape (nt,), increasing"""
    nodal: sparse.csc_matrix
    """nodal forces/moments at the contact samples [N | N m], shape (n_owned·5, nt)"""
    accel_times: np.ndarray
    """acceleration sample times [s], shape (na,), increasing"""
    accel: np.ndarray
    """frame (CG) acceleration in B at the samples [m/s²], shape (na, 3)"""
    mass_c: np.ndarray
    """translational lumped mass per component, shape (3, n_owned·5) [kg]"""

    def evaluate(self, t: float, out: np.ndarray) -> np.ndarray:
        """Write f(t) into ``out`` (shape (n_owned·5,)) and return it."""
        out[:] = 0.0
        br = _bracket(self.times, t)
        if br is not None:
            k, s = br
            P = self.nodal
            for j, wgt in ((k, 1.0 - s), (k + 1, s)):
                if wgt != 0.0:
                    a, b = P.indptr[j], P.indptr[j + 1]
                    out[P.indices[a:b]] += wgt * P.data[a:b]
        br = _bracket(self.accel_times, t)
        if br is not None:
            k, s = br
            acc = (1.0 - s) * self.accel[k] + (s * self.accel[k + 1] if s else 0.0)
            for c in range(3):
                if acc[c] != 0.0:
                    out -= acc[c] * self.mass_c[c]
        return out


def no_loads(op: ShellOperator) -> LoadHistory:
    """A load history that is zero at all times."""
    return LoadHistory(times=np.zeros(0), nodal=sparse.csc_matrix((op.n_owned, 0)),
                       accel_times=np.zeros(0), accel=np.zeros((0, 3)),
                       mass_c=np.zeros((3, op.n_owned)))


def translational_mass(op: ShellOperator) -> np.ndarray:
    """m_c: lumped mass on component c's DOFs (free DOFs only), shape (3, n_owned·5) [kg]."""
    mc = np.zeros((3, op.n_owned))
    free = op.minv > 0
    for c in range(3):
        mc[c, c::NDOF_NODE] = op.mass[c::NDOF_NODE]
        mc[c] *= free
    return mc


@dataclass
class Sample:
    """Solver output at one sampling instant (arrays are views, copy to keep)."""

    step: int
    t: float
    """time [s]"""
    u: np.ndarray
    """displacement/rotation at t, owned DOFs [m | rad]"""
    v: np.ndarray
    """velocity at t − dt/2 (central difference; at step 0 the initial velocity) [m/s | rad/s]"""
    kinetic: float
    """½ vᵀ M v with the half-step velocity [J]"""
    strain: float
    """½ uᵀ K u [J]"""
    work: float
    """accumulated external work, Σ over sample intervals of |Σ_steps f·Δu| [J]"""


@njit(cache=True)
def _update(u, v, fe, fi, minv, h, dt, alpha):
    """Fused central-difference update over the owned DOFs (one pass over 6 arrays):
    a = M⁻¹(f_ext − f_int) − α v;  v += h a;  u += dt v.
    Returns the external work of the step on these DOFs, f_ext · Δu [J] (same pass)."""
    work = 0.0
    for i in range(u.size):
        a = minv[i] * (fe[i] - fi[i]) - alpha * v[i]
        v[i] += h * a
        du = dt * v[i]
        u[i] += du
        work += fe[i] * du
    return work


def central_difference(op: ShellOperator, loads: LoadHistory, dt: float, n_steps: int,
                       sample_every: int, *, dt_crit: float, alpha: float = 0.0,
                       beta: float = 0.0, u0: np.ndarray | None = None,
                       v0: np.ndarray | None = None, growth_limit: float = 10.0
                       ) -> Iterator[Sample]:
    """Advance M ü + (αM + βK) u̇ + K u = f(t) by central differences, yielding a
    :class:`Sample` at step 0 and every ``sample_every`` steps (and at the last step).

    Scheme (Belytschko, Liu & Moran 2000, Box 6.1), velocity at half steps:
        a_n = M⁻¹ [f(t_n) − K (u_n + β v_{n−½})] − α v_{n−½}
        v_{n+½} = v_{n−½} + dt a_n   (first step: v_½ = v_0 + dt/2 a_0)
        u_{n+1} = u_n + dt v_{n+½}
    The damping force uses the lagged velocity v_{n−½} (explicit). One sparse product per step.

    Raises :class:`NumericalError` naming dt and dt_crit when the state is not finite or
    when kinetic + strain energy exceeds ``growth_limit`` × (initial energy + accumulated
    |external work|): an unstable step grows energy without bound.
    """
    n = op.n_owned
    u = np.zeros(n) if u0 is None else np.array(u0, dtype=float)
    v = np.zeros(n) if v0 is None else np.array(v0, dtype=float)
    w = np.zeros(n)
    fi = np.zeros(n)
    fe = np.zeros(n)
    wv, fiv, uv = _vec(op, w), _vec(op, fi), _vec(op, u)
    comm = op.comm
    minv, mass, K = op.minv, op.mass, op.K
    u *= minv > 0  # clamped DOFs start (and stay) at zero
    v *= minv > 0

    def energies() -> tuple[float, float]:
        K.mult(uv, fiv)
        ke = 0.5 * float(v @ (mass * v))
        se = 0.5 * float(u @ fi)
        tot = np.empty(2)
        comm.Allreduce(np.array([ke, se]), tot, op=MPI.SUM)
        return float(tot[0]), float(tot[1])

    ke, se = energies()
    e0 = ke + se
    work = work_local = 0.0
    yield Sample(0, 0.0, u, v, ke, se, 0.0)
    for step in range(1, n_steps + 1):
        t = (step - 1) * dt
        if beta:
            np.multiply(v, beta, out=w)
            w += u
            K.mult(wv, fiv)
        else:
            K.mult(uv, fiv)
        loads.evaluate(t, fe)
        # f_ext · Δu summed every step, so load pulses shorter than a sample interval count too.
        work_local += _update(u, v, fe, fi, minv, 0.5 * dt if step == 1 else dt, dt, alpha)
        if step % sample_every == 0 or step == n_steps:
            tn = step * dt
            ke, se = energies()
            work += abs(comm.allreduce(work_local, op=MPI.SUM))
            work_local = 0.0
            total = ke + se
            if not np.isfinite(total) or total > growth_limit * (e0 + work):
                raise NumericalError(
                    f"shell solver unstable at t = {tn:.6e} s (step {step}): energy {total:.3e} J "
                    f"vs budget {e0 + work:.3e} J; dt = {dt:.4e} s, dt_crit = {dt_crit:.4e} s "
                    f"(dt/dt_crit = {dt / dt_crit:.3f})")
            yield Sample(step, tn, u, v, ke, se, work)
