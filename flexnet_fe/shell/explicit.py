"""Explicit central-difference elastodynamics of the shell: M ü + C u̇ + K u = f(t).

The stiffness K is assembled once, all forms into one PETSc matrix (block size 5, linear in the
DOFs). Two ways to step it, giving the same numbers (tests: 1e-12 over 1 000 steps):

- compiled (serial, default): the matrix's CSR arrays are copied once into block-upper storage
  (:mod:`flexnet_fe.shell.kernel`) and one numba kernel advances many steps per call;
- PETSc (``MPI``, any number of processes): one ``Mat.mult`` per step (:func:`central_difference`).

M is the lumped diagonal (:mod:`flexnet_fe.shell.mass`); C = αM + βK (Rayleigh). Fixed DOFs
have M⁻¹ = 0, so they never move. dt_crit comes from a Lanczos estimate of λ_max(M⁻¹K)
(:func:`max_eigenvalue`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum
from typing import Iterator

import numpy as np
from dolfinx import fem
from dolfinx.fem.petsc import assemble_matrix, create_matrix
from mpi4py import MPI
from petsc4py import PETSc
from numba import njit
from scipy import sparse

from flexnet_fe.errors import NumericalError
from flexnet_fe.shell.forms import NDOF_NODE
from flexnet_fe.shell.kernel import (BlockUpper, NodeData, block_product, node_update,
                                     upper_blocks)


class Backend(str, Enum):
    """How the explicit step is executed."""

    AUTO = "auto"
    """compiled on one process, PETSc under MPI"""
    COMPILED = "compiled"
    """numba kernel on block-upper storage, many steps per call (serial only)"""
    PETSC = "petsc"
    """one PETSc ``Mat.mult`` per step (any number of processes)"""


@dataclass(frozen=True)
class ShellOperator:
    """What never changes during a run: K, the inverse lumped mass, the free-DOF set."""

    K: PETSc.Mat
    """stiffness [N/m, N, N m], global, no supports applied (see :func:`assemble_operator`)"""
    Kb: BlockUpper | None
    """the same K in block-upper storage for the compiled kernel (serial only, else None)"""
    mass: np.ndarray
    """lumped mass of the owned DOFs, shape (n_owned·5,) [kg | kg m²]"""
    minv: np.ndarray
    """1/mass on free DOFs, 0 on fixed DOFs, shape (n_owned·5,)"""
    x_nodes: np.ndarray
    """coordinates of the owned nodes [m], shape (n_owned, 3)"""
    comm: MPI.Comm
    wfix: np.ndarray
    """1.0 at owned nodes held at w = u·n = 0 (simple supports), else 0.0, (n_owned_nodes,)"""
    normal: np.ndarray
    """fin normal n (3,)"""

    @property
    def n_owned(self) -> int:
        return self.mass.size


def assemble_operator(a_forms: list, V: fem.FunctionSpace, mass: PETSc.Vec,
                      fixed: np.ndarray, *, normal_fixed: np.ndarray | None = None,
                      normal=(0.0, 0.0, 1.0)) -> ShellOperator:
    """Assemble K once as the sum of the bilinear forms ``a_forms`` (all into one matrix: the
    forms share the sparsity of the blocked P1 space) and, in serial, copy its CSR arrays into
    the compiled kernel's block-upper storage (linear in the non-zeros; no PETSc format
    conversion). M⁻¹ has zeros on the ``fixed`` DOFs (local unrolled indices, owned or ghost).

    Supports are imposed through M⁻¹ = 0 only: a fixed DOF starts at zero and never
    accelerates, so K needs no modification (it stays symmetric; its rows at fixed DOFs are the
    reactions, which the solver ignores). ``normal_fixed`` (local node indices): nodes held at
    w = u·n = 0, imposed by removing the normal part of their translational acceleration.
    """
    serial = V.mesh.comm.size == 1
    forms = [fem.form(a) for a in a_forms]
    K = create_matrix(forms[0], "aij" if serial else "baij")
    for f in forms:
        assemble_matrix(K, f)
    K.assemble()
    Kb = upper_blocks(*K.getValuesCSR()) if serial else None
    n_owned = V.dofmap.index_map.size_local * NDOF_NODE
    m = mass.getArray(readonly=True)[:n_owned].copy()
    if np.any(m <= 0):
        raise NumericalError("lumped mass has a non-positive entry: the mesh has a degenerate cell")
    minv = 1.0 / m
    minv[fixed[fixed < n_owned]] = 0.0
    n_nodes = V.dofmap.index_map.size_local
    x_nodes = V.tabulate_dof_coordinates()[:n_nodes].copy()
    wfix = np.zeros(n_nodes)
    if normal_fixed is not None:
        nf = np.asarray(normal_fixed, dtype=np.int64)
        wfix[nf[nf < n_nodes]] = 1.0
    return ShellOperator(K=K, Kb=Kb, mass=m, minv=minv, x_nodes=x_nodes, comm=V.mesh.comm,
                         wfix=wfix, normal=np.asarray(normal, dtype=float))


def constrain(op: ShellOperator, x: np.ndarray) -> np.ndarray:
    """Remove the supported part of a nodal vector in place (owned DOFs): zero on fixed DOFs,
    no normal component at w-fixed nodes. Returns x."""
    x *= op.minv > 0
    xb = x.reshape(-1, NDOF_NODE)
    xb[:, :3] -= op.wfix[:, None] * (xb[:, :3] @ op.normal)[:, None] * op.normal[None, :]
    return x


def apply_K(op: ShellOperator, x: np.ndarray, y: np.ndarray) -> None:
    """y = K x on the owned DOFs (compiled product in serial, PETSc under MPI)."""
    if op.Kb is not None:
        block_product(op.Kb, x, y)
    else:
        op.K.mult(_vec(op, x), _vec(op, y))


def _vec(op: ShellOperator, arr: np.ndarray) -> PETSc.Vec:
    """A PETSc Vec sharing memory with the owned-DOF array ``arr``."""
    return PETSc.Vec().createWithArray(arr, bsize=NDOF_NODE, comm=op.comm)


def start_vector(op: ShellOperator) -> np.ndarray:
    """A start vector that depends only on node coordinates (not on the DOF numbering, which
    changes with the number of processes), zero on fixed DOFs, so serial and parallel runs
    compute the same dt_crit to round-off."""
    comm = op.comm
    lo, hi = np.empty(3), np.empty(3)
    comm.Allreduce(op.x_nodes.min(axis=0, initial=np.inf), lo, op=MPI.MIN)
    comm.Allreduce(op.x_nodes.max(axis=0, initial=-np.inf), hi, op=MPI.MAX)
    span = float((hi - lo).max()) or 1.0
    phase = ((op.x_nodes - lo) / span) @ np.array([37.1, 53.3, 71.9])
    x = np.sin(phase[:, None] * (1.0 + np.arange(NDOF_NODE))[None, :] + 0.3).ravel()
    return x * (op.minv > 0)


@njit(cache=True)
def _project(Q, m, w):
    """c = Q[:m] w (compiled loops: a BLAS call here let OpenBLAS's spinning threads cost
    0.5 s per fin on the loaded 2-core machine, measured, for 10 ms of arithmetic)."""
    c = np.zeros(m)
    for r in range(m):
        s = 0.0
        for i in range(w.size):
            s += Q[r, i] * w[i]
        c[r] = s
    return c


@njit(cache=True)
def _subtract(Q, c, w):
    """w −= cᵀ Q[:len(c)]."""
    for r in range(c.size):
        for i in range(w.size):
            w[i] -= c[r] * Q[r, i]


def max_eigenvalue(op: ShellOperator, *, steps: int = 40) -> tuple[float, float]:
    """Largest eigenvalue λ_max of M⁻¹K [1/s²] (free DOFs) by ``steps`` Lanczos steps with full
    reorthogonalisation on the symmetric B = M^{-1/2} K M^{-1/2} (same spectrum as the lumped
    generalized problem K φ = λ M φ). Returns (θ + r, r/θ): θ the largest Ritz value (a lower
    bound of λ_max) and r = β_k |s_k| its residual norm — an eigenvalue lies within r of θ,
    so θ + r bounds λ_max from above once θ has converged to it (tests: against ARPACK).

    Bounded cost: ``steps`` products and O(steps² n) for the reorthogonalisation, no matter how
    the spectrum's top clusters; the distributed dot products make it valid under MPI.
    """
    comm = op.comm
    d = np.sqrt(op.minv)
    n = op.n_owned
    dot = lambda a, b: comm.allreduce(float(a @ b), op=MPI.SUM)  # noqa: E731
    nfree = comm.allreduce(int((d > 0).sum()), op=MPI.SUM)
    k = max(2, min(steps, nfree))
    Q = np.zeros((k + 1, n))
    alpha, beta = np.zeros(k), np.zeros(k)
    q = start_vector(op)
    Q[0] = q / np.sqrt(dot(q, q))
    z, y = np.zeros(n), np.zeros(n)
    for j in range(k):
        np.multiply(d, Q[j], out=z)
        apply_K(op, z, y)
        w = d * y
        alpha[j] = dot(Q[j], w)
        for _ in range(2):  # full reorthogonalisation (twice is enough)
            c = comm.allreduce(_project(Q, j + 1, w), op=MPI.SUM)
            _subtract(Q, c, w)
        beta[j] = np.sqrt(dot(w, w))
        if beta[j] <= 1e-14 * abs(alpha[: j + 1]).max():  # invariant subspace: exact
            k = j + 1
            break
        Q[j + 1] = w / beta[j]
    T = np.diag(alpha[:k]) + np.diag(beta[: k - 1], 1) + np.diag(beta[: k - 1], -1)
    theta, S = np.linalg.eigh(T)
    r = abs(beta[k - 1] * S[-1, -1])
    return float(theta[-1] + r), float(r / theta[-1])


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
    """½ u_nᵀ K u_{n−1} (β = 0; ½ uᵀ K u at the start and when β ≠ 0) [J]"""
    work: float
    """accumulated external work Σ ½ dt f_k·(v_{k−½} + v_{k+½}) since the start, signed [J]:
    kinetic + strain − work is constant to round-off when undamped (kernel.advance_steps; the
    instability guard uses Σ over sample intervals of |interval work| internally, an upper bound)"""
    row: bool = True
    """False at the extra instants of ``peak_every`` (u, v, t valid; energies and work NaN)"""


@njit(cache=True)
def _update(u, v, fe, fi, N, coef):
    """Central-difference update over the owned nodes (:func:`node_update`; N a
    :class:`NodeData`, coef = (h, dt, α)); returns the external work of the step,
    ½ dt f_ext·(v_{n−½} + v_{n+½}) [J]."""
    work = 0.0
    f5 = np.empty(5)
    for i in range(N.wfix.size):
        for a in range(5):
            f5[a] = fe[5 * i + a]
        work += node_update(u, v, f5, fi, N, i, coef)
    return work


def central_difference(op: ShellOperator, loads: LoadHistory, dt: float, n_steps: int,
                       sample_every: int, *, dt_crit: float, alpha: float = 0.0,
                       beta: float = 0.0, u0: np.ndarray | None = None,
                       v0: np.ndarray | None = None, growth_limit: float = 10.0,
                       peak_every: int = 0, start_step: int = 0) -> Iterator[Sample]:
    """Advance M ü + (αM + βK) u̇ + K u = f(t) by central differences, yielding a
    :class:`Sample` at the start and every ``sample_every`` steps (and at the last step).
    ``start_step``: the state u0, v0 is at t = start_step dt; the steps keep their absolute
    numbers (step n at t = n dt, samples at multiples of ``sample_every``), so that a run over a
    time window gives the samples of a run from t = 0 at the same instants.

    Scheme (Belytschko, Liu & Moran 2000, Box 6.1), velocity at half steps:
        a_n = M⁻¹ [f(t_n) − K (u_n + β v_{n−½})] − α v_{n−½}
        v_{n+½} = v_{n−½} + dt a_n   (first step: v_½ = v_0 + dt/2 a_0)
        u_{n+1} = u_n + dt v_{n+½}
    The damping force uses the lagged velocity v_{n−½} (explicit). One sparse product per step.

    Raises :class:`NumericalError` naming dt and dt_crit when the state is not finite or
    when kinetic + strain energy exceeds ``growth_limit`` × (initial energy + accumulated
    |external work|): an unstable step grows energy without bound.
    ``peak_every`` > 0: also yield (``row`` False, energies NaN) every that many steps between
    the samples, for stress peaks resolved in time.
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
    nodes = NodeData(minv=minv, wfix=op.wfix, normal=np.asarray(op.normal, float))
    constrain(op, u)  # fixed DOFs start (and stay) at zero, w = 0 at simply supported nodes
    constrain(op, v)

    def energies(cross: bool = False) -> tuple[float, float]:
        """(½vᵀMv, ½u_nᵀKu_{n−1} from the step's product if ``cross`` else ½uᵀKu) [J]."""
        if not cross:
            K.mult(uv, fiv)
        ke = 0.5 * float(v @ (mass * v))
        se = 0.5 * float(u @ fi)
        tot = np.empty(2)
        comm.Allreduce(np.array([ke, se]), tot, op=MPI.SUM)
        return float(tot[0]), float(tot[1])

    ke, se = energies()
    e0 = ke + se
    work = work_net = work_local = 0.0  # Σ|interval work| (the guard's budget), signed work [J]
    yield Sample(start_step, start_step * dt, u, v, ke, se, 0.0)
    last = start_step + n_steps
    for step in range(start_step + 1, last + 1):
        t = (step - 1) * dt
        if beta:
            np.multiply(v, beta, out=w)
            w += u
            K.mult(wv, fiv)
        else:
            K.mult(uv, fiv)
        loads.evaluate(t, fe)
        # ½ dt f_ext·(v_{n−½} + v_{n+½}) every step: load pulses shorter than a sample count too
        h = 0.5 * dt if step == start_step + 1 else dt
        work_local += _update(u, v, fe, fi, nodes, (h, dt, alpha))
        if step % sample_every == 0 or step == last:
            tn = step * dt
            ke, se = energies(cross=not beta)
            w_int = comm.allreduce(work_local, op=MPI.SUM)
            work += abs(w_int)
            work_net += w_int
            work_local = 0.0
            total = ke + se
            if not np.isfinite(total) or total > growth_limit * (e0 + work):
                raise NumericalError(
                    f"shell solver unstable at t = {tn:.6e} s (step {step}): energy {total:.3e} J "
                    f"vs budget {e0 + work:.3e} J; dt = {dt:.4e} s, dt_crit = {dt_crit:.4e} s "
                    f"(dt/dt_crit = {dt / dt_crit:.3f})")
            yield Sample(step, tn, u, v, ke, se, work_net)
        elif peak_every > 0 and step % peak_every == 0:
            yield Sample(step, step * dt, u, v, math.nan, math.nan, math.nan, row=False)
