"""Compiled explicit step of the shell (serial): many central-difference steps per call.

One numba kernel advances M ü + (αM + βK) u̇ + K u = f(t) over a whole output interval with no
Python per step. Per step it makes one pass over the node rows of K stored as the *upper
triangle of 5 × 5 blocks* (block CSR, the diagonal block first in each row; SBAIJ-like):

    for node row i:   y_i += Σ_{j ≥ i} B_ij x_j ;   y_j += B_ijᵀ x_i  (j > i)
                      — y_i is now complete (rows k < i added their transposed part earlier) —
                      a_i = M_i⁻¹ (f_i(t) − y_i) − α v_i ;  v_i += h a_i ;  u_i += dt v_i

with x = u + β v. Node i is updated right after its row: rows k < i no longer need x_i and rows
j > i received B_ijᵀ x_i already, so the product, the load and the update are one sweep over
the matrix and the vectors (the matrix streams once per step). The strain energy ½ u_{n+1}ᵀ K u_n,
the work ½ dt f·(v_{n−½} + v_{n+½}) and the kinetic energy fall out of the same sweep; with them
the energy balance is the scheme's exact one (:func:`advance_steps`).

Stress sampling is :func:`flexnet_fe.shell.recovery.sample_nodes` called from inside the kernel:
nodal surface stresses by lumped L2 projection, per-node envelope, global structural peak (value,
node, time; nodes inside the St-Venant zones of the contact loads active at that instant left
out, :mod:`flexnet_fe.shell.hotspot`) and a copy of u at the running peak — every ``peak_every``
steps (the peak must be resolved in time: a rope load rises over one 10 µs contact sample and
the stress peak it causes is a few µs wide); the history rows (energies, per-sample maxima) are
written every ``sample_every`` steps, a multiple of it.

The block matrix is built once from the assembled CSR arrays (:func:`upper_blocks`): linear in
the number of non-zeros, no PETSc AIJ → SBAIJ conversion.
"""

from __future__ import annotations

import platform
from typing import NamedTuple

import numpy as np
from numba import njit

from flexnet_fe.shell.hotspot import mark
from flexnet_fe.shell.recovery import sample_nodes

NB = 5  # DOFs per node

# Flush-to-zero / denormals-are-zero inside the kernel (x86 MXCSR bits 15 and 6). Ahead of a
# wave front the explicit scheme leaves values decaying towards 1e-308; denormal arithmetic is
# 10–100× slower (measured: a state of 1e-310 makes the step 1.6× slower on the whole fin).
# Flushing changes results by < 1e-307 in absolute value. The caller's MXCSR is restored.
_FTZ_DAZ = 0x8040
if platform.machine().lower() in ("x86_64", "amd64"):
    from llvmlite import ir
    from numba.core import cgutils, types
    from numba.extending import intrinsic

    @intrinsic
    def _get_mxcsr(typingctx):
        def codegen(context, builder, signature, args):
            ptr = cgutils.alloca_once(builder, ir.IntType(32))
            fnty = ir.FunctionType(ir.VoidType(), [ir.IntType(8).as_pointer()])
            fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.x86.sse.stmxcsr")
            builder.call(fn, [builder.bitcast(ptr, ir.IntType(8).as_pointer())])
            return builder.zext(builder.load(ptr), ir.IntType(64))
        return types.int64(), codegen

    @intrinsic
    def _set_mxcsr(typingctx, value):
        def codegen(context, builder, signature, args):
            ptr = cgutils.alloca_once(builder, ir.IntType(32))
            builder.store(builder.trunc(args[0], ir.IntType(32)), ptr)
            fnty = ir.FunctionType(ir.VoidType(), [ir.IntType(8).as_pointer()])
            fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.x86.sse.ldmxcsr")
            builder.call(fn, [builder.bitcast(ptr, ir.IntType(8).as_pointer())])
            return context.get_dummy_value()
        return types.void(types.int64), codegen
else:  # other CPUs: no flushing (correct, possibly slower ahead of wave fronts)
    @njit(cache=True)
    def _get_mxcsr():
        return 0

    @njit(cache=True)
    def _set_mxcsr(value):
        pass


class BlockUpper(NamedTuple):
    """Upper triangle of a symmetric block-5 matrix in block CSR (node rows)."""

    indptr: np.ndarray
    """row pointer over node rows, shape (n_nodes + 1,), int64"""
    indices: np.ndarray
    """column node of each stored block (j ≥ i, diagonal first), shape (nnzb,), int32"""
    blocks: np.ndarray
    """5 × 5 blocks, shape (nnzb, 5, 5) [N/m | N | N m]"""


@njit(cache=True)
def _upper_blocks(indptr, indices, data, n_nodes):
    """Block-upper storage from an unblocked CSR matrix whose sparsity is node-blocked: the rows
    of node i share their column nodes, each as 5 consecutive sorted columns. Linear in nnz.
    Returns (bptr, bind, blk, ok); ok is False if the pattern is not node-blocked."""
    bptr = np.zeros(n_nodes + 1, np.int64)
    for i in range(n_nodes):
        r = NB * i
        cnt = 0
        for p in range(indptr[r], indptr[r + 1], NB):
            if indices[p] // NB >= i:
                cnt += 1
        bptr[i + 1] = bptr[i] + cnt
    nnzb = bptr[n_nodes]
    bind = np.empty(nnzb, np.int32)
    blk = np.zeros((nnzb, NB, NB))
    ok = True
    for i in range(n_nodes):
        q = bptr[i]
        nblk = (indptr[NB * i + 1] - indptr[NB * i]) // NB
        for k in range(nblk):
            j = indices[indptr[NB * i] + NB * k] // NB
            if j < i:
                continue
            bind[q] = j
            for a in range(NB):
                base = indptr[NB * i + a] + NB * k
                for b in range(NB):
                    if indices[base + b] != NB * j + b:
                        ok = False
                    blk[q, a, b] = data[base + b]
            q += 1
        if bind[bptr[i]] != i:  # the diagonal block must come first
            ok = False
    return bptr, bind, blk, ok


def upper_blocks(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray) -> BlockUpper:
    """:class:`BlockUpper` from the unblocked CSR arrays (``indptr``, ``indices``, ``data``) of a
    symmetric matrix with node-blocked sparsity (dolfinx assembles a blocked space that way:
    every row of node i has the same column nodes, columns sorted). Raises ValueError if the
    pattern is not node-blocked."""
    n = len(indptr) - 1
    if n % NB:
        raise ValueError(f"matrix size {n} is not a multiple of {NB}")
    rl = np.diff(indptr)
    if np.any(rl % NB) or np.any(rl.reshape(-1, NB) != rl[::NB, None]):
        raise ValueError("matrix sparsity is not node-blocked")
    bptr, bind, blk, ok = _upper_blocks(indptr.astype(np.int64), indices.astype(np.int64),
                                        data.astype(np.float64), n // NB)
    if not ok:
        raise ValueError("matrix sparsity is not node-blocked (or a diagonal block is missing)")
    return BlockUpper(bptr, bind, blk)


@njit(cache=True)
def block_product(K, x, y):
    """y = K x for the symmetric :class:`BlockUpper` ``K`` (x, y shape (5 n_nodes,))."""
    y[:] = 0.0
    ind, ptr, B = K.indices, K.indptr, K.blocks
    for i in range(len(ptr) - 1):
        bi = NB * i
        for p in range(ptr[i], ptr[i + 1]):
            j = ind[p]
            bj = NB * j
            for a in range(NB):
                s = 0.0
                for b in range(NB):
                    s += B[p, a, b] * x[bj + b]
                y[bi + a] += s
            if j != i:
                for b in range(NB):
                    s = 0.0
                    for a in range(NB):
                        s += B[p, a, b] * x[bi + a]
                    y[bj + b] += s


class SplitUpper(NamedTuple):
    """K in the fin's local frame (u1, u2, w, θ1, θ2), upper triangle, with the membrane (u1, u2)
    and bending/shear (w, θ1, θ2) parts of each block stored apart: a flat shell does not couple
    them, so 13 of the 25 block entries carry it all (half the flops and bytes per step)."""

    indptr: np.ndarray
    indices: np.ndarray
    mem: np.ndarray
    """membrane 2 × 2 blocks, row-major, (nnzb, 4)"""
    bend: np.ndarray
    """bending/shear 3 × 3 blocks, row-major, (nnzb, 9)"""


def node_rotation(e1, e2, n) -> np.ndarray:
    """5 × 5 nodal rotation T: local DOFs (u1, u2, w, θ1, θ2) = T (u_x, u_y, u_z, θ1, θ2)."""
    T = np.eye(NB)
    T[:3, :3] = np.array([e1, e2, n], dtype=float)
    return T


def split_upper(K: BlockUpper, T: np.ndarray, *, tol: float = 1e-10) -> SplitUpper:
    """:class:`SplitUpper` of the frame-B block matrix K with the nodal rotation T
    (:func:`node_rotation`): B̃ = T B Tᵀ. Raises ValueError if the membrane–bending coupling of
    B̃ is not negligible (|coupling| > tol × |B̃|: the shell is not flat)."""
    Bt = np.matmul(np.matmul(T, K.blocks), T.T)
    scale = np.abs(Bt).max(initial=0.0)
    cpl = max(np.abs(Bt[:, :2, 2:]).max(initial=0.0), np.abs(Bt[:, 2:, :2]).max(initial=0.0))
    if cpl > tol * scale:
        raise ValueError(f"membrane–bending coupling {cpl:.3e} of K in the fin frame is not "
                         f"negligible (scale {scale:.3e}): the fin is not flat")
    mem = np.ascontiguousarray(Bt[:, :2, :2].reshape(-1, 4))
    bend = np.ascontiguousarray(Bt[:, 2:, 2:].reshape(-1, 9))
    return SplitUpper(K.indptr, K.indices, mem, bend)


@njit(cache=True)
def split_product(K, x, y):
    """y = K x for :class:`SplitUpper` K (local frame vectors, 5 per node)."""
    y[:] = 0.0
    for i in range(len(K.indptr) - 1):
        _split_row(K, i, x, x, y, 0.0)


@njit(cache=True, fastmath=False, inline="always")
def _split_row(K, i, u, v, y, beta):
    """Row i of the symmetric product with x = u + β v: y_i += Σ_{j≥i} B_ij x_j and
    y_j += B_ijᵀ x_i (j > i)."""
    ind, M, B = K.indices, K.mem, K.bend
    bi = NB * i
    xi0 = u[bi] + beta * v[bi]
    xi1 = u[bi + 1] + beta * v[bi + 1]
    xi2 = u[bi + 2] + beta * v[bi + 2]
    xi3 = u[bi + 3] + beta * v[bi + 3]
    xi4 = u[bi + 4] + beta * v[bi + 4]
    p0 = K.indptr[i]
    # diagonal block (symmetric: full product once)
    y0 = M[p0, 0] * xi0 + M[p0, 1] * xi1
    y1 = M[p0, 2] * xi0 + M[p0, 3] * xi1
    y2 = B[p0, 0] * xi2 + B[p0, 1] * xi3 + B[p0, 2] * xi4
    y3 = B[p0, 3] * xi2 + B[p0, 4] * xi3 + B[p0, 5] * xi4
    y4 = B[p0, 6] * xi2 + B[p0, 7] * xi3 + B[p0, 8] * xi4
    for p in range(p0 + 1, K.indptr[i + 1]):
        bj = NB * ind[p]
        x0 = u[bj] + beta * v[bj]
        x1 = u[bj + 1] + beta * v[bj + 1]
        x2 = u[bj + 2] + beta * v[bj + 2]
        x3 = u[bj + 3] + beta * v[bj + 3]
        x4 = u[bj + 4] + beta * v[bj + 4]
        m0, m1, m2, m3 = M[p, 0], M[p, 1], M[p, 2], M[p, 3]
        b0, b1, b2, b3, b4, b5, b6, b7, b8 = (B[p, 0], B[p, 1], B[p, 2], B[p, 3], B[p, 4],
                                              B[p, 5], B[p, 6], B[p, 7], B[p, 8])
        y0 += m0 * x0 + m1 * x1
        y1 += m2 * x0 + m3 * x1
        y2 += b0 * x2 + b1 * x3 + b2 * x4
        y3 += b3 * x2 + b4 * x3 + b5 * x4
        y4 += b6 * x2 + b7 * x3 + b8 * x4
        y[bj] += m0 * xi0 + m2 * xi1
        y[bj + 1] += m1 * xi0 + m3 * xi1
        y[bj + 2] += b0 * xi2 + b3 * xi3 + b6 * xi4
        y[bj + 3] += b1 * xi2 + b4 * xi3 + b7 * xi4
        y[bj + 4] += b2 * xi2 + b5 * xi3 + b8 * xi4
    y[bi] += y0
    y[bi + 1] += y1
    y[bi + 2] += y2
    y[bi + 3] += y3
    y[bi + 4] += y4


class NodeData(NamedTuple):
    """Per-node constraint data of the update (frame B, PETSc path)."""

    minv: np.ndarray
    """1/m on free DOFs, 0 on fixed, (n,)"""
    wfix: np.ndarray
    """1.0 at nodes held at w = 0, (n_nodes,)"""
    normal: np.ndarray
    """fin normal n (3,)"""


@njit(cache=True)
def node_update(u, v, f5, y, N, i, coef):
    """Central-difference update of node i's 5 DOFs with its load f5 (5,) (frame B), K x in
    ``y``, constraint data ``N`` (:class:`NodeData`) and coef = (h, dt, α) [s, s, 1/s]:
    a = M⁻¹(f − y) − α v; v += h a; u += dt v; at w-fixed nodes the normal parts of v and u are
    removed (v ← v − (v·n) n, re-masked by M⁻¹ > 0), which is the constrained update
    a ← a − (a·n) n with the round-off of the projection kept from accumulating.
    Returns the node's work in the step, ½ dt f·(v_{n−½} + v_{n+½}) [J]: with the kinetic
    energy at the half step and the strain energy ½ u_{n+1}ᵀ K u_n, the central-difference
    scheme's exact discrete energy balance (:func:`advance_steps`)."""
    h, dt, alpha = coef
    minv, nrm = N.minv, N.normal
    b = NB * i
    w_old = 0.0
    for a in range(NB):
        w_old += f5[a] * v[b + a]
    for a in range(NB):
        acc = minv[b + a] * (f5[a] - y[b + a]) - alpha * v[b + a]
        v[b + a] += h * acc
    if N.wfix[i] != 0.0:  # remove the normal part of v (and re-mask): no drift of w by round-off
        vn = v[b] * nrm[0] + v[b + 1] * nrm[1] + v[b + 2] * nrm[2]
        for a in range(3):
            v[b + a] = (v[b + a] - vn * nrm[a]) * (minv[b + a] > 0.0)
    work = 0.5 * dt * w_old
    for a in range(NB):
        du = dt * v[b + a]
        u[b + a] += du
        work += 0.5 * f5[a] * du
    if N.wfix[i] != 0.0:
        un = u[b] * nrm[0] + u[b + 1] * nrm[1] + u[b + 2] * nrm[2]
        for a in range(3):
            u[b + a] -= un * nrm[a]
    return work


class StepData(NamedTuple):
    """What a kernel call needs that never changes during a run (all in the fin's local frame
    (u1, u2, w, θ1, θ2): loads and accelerations rotated once at set-up)."""

    K: SplitUpper
    minv: np.ndarray
    """1/m on free DOFs, 0 on fixed, (n,)"""
    mass: np.ndarray
    """lumped mass (n,) [kg | kg m²]"""
    mass_t: np.ndarray
    """translational lumped mass on free DOFs, 0 elsewhere (n,) [kg]"""
    times: np.ndarray
    """contact sample times (nt,) [s]"""
    colptr: np.ndarray
    """CSC column pointer of the nodal contact loads, (nt + 1,)"""
    rows: np.ndarray
    """CSC row (DOF) indices, (nnz,)"""
    vals: np.ndarray
    """CSC values [N], (nnz,)"""
    acc_times: np.ndarray
    """body acceleration sample times (na,) [s]"""
    acc: np.ndarray
    """body (frame) acceleration (na, 3) [m/s²]"""
    wfix: np.ndarray
    """1.0 at nodes held at w = 0, (n_nodes,)"""
    normal: np.ndarray
    """fin normal (3,)"""
    zones: object
    """the St-Venant zones of each contact sample's loads (:class:`flexnet_fe.shell.hotspot.Exclusion`)"""


class StepParams(NamedTuple):
    dt: float
    alpha: float
    beta: float
    growth_limit: float
    sample_every: int
    """history rows (energies, per-sample maxima) every that many steps"""
    peak_every: int = 0
    """stresses for the running peaks and the envelope every that many steps (a divisor of
    sample_every; 0: at the history rows only)"""


class RunState(NamedTuple):
    """Mutable state carried from call to call."""

    u: np.ndarray
    v: np.ndarray
    fext: np.ndarray
    """scratch, zero between steps (n,)"""
    y: np.ndarray
    """scratch, zero between steps (n,)"""
    scal: np.ndarray
    """float64 scalars: see the ``S_*`` indices"""
    u_peak: np.ndarray
    """u at the running von Mises peak (n,)"""
    x: np.ndarray
    """scratch u + β v (n,) (damped runs)"""


# indices into RunState.scal
S_STEP, S_WORK, S_WORK_INT, S_E0, S_PEAK_VM, S_PEAK_T, S_PEAK_NODE, S_PEAK_P1, S_PEAK_STEP, \
    S_PEAK_P1_T, S_NSAMP, S_WORK_NET, S_PEAK_RAW, S_STEP0 = range(14)
# S_WORK: Σ over sample intervals of |external work in the interval| [J], the instability
# guard's energy budget (an upper bound); S_WORK_NET: the signed external work [J] written to
# the history, so that kinetic + strain − work is the energy balance. S_PEAK_* are the
# structural peak (outside the St-Venant zones of the active loads); S_PEAK_RAW the largest nodal
# von Mises anywhere, the zones included [Pa]. S_STEP0: the step the run starts from (its state
# u0, v0 is at t = S_STEP0 dt; the first step is the half step), so that a run over a time
# window [t0, t1] keeps the absolute step numbers and times of a run from t = 0.
N_SCAL = 14


def new_state(n: int, u0: np.ndarray | None = None, v0: np.ndarray | None = None,
              start_step: int = 0) -> RunState:
    """State at step ``start_step`` (t = start_step dt): u0, v0 (n,) or zero."""
    scal = np.zeros(N_SCAL)
    scal[S_STEP] = start_step
    scal[S_STEP0] = start_step
    scal[S_PEAK_VM] = -1.0
    scal[S_PEAK_P1] = -np.inf
    scal[S_PEAK_NODE] = -1
    u = np.zeros(n) if u0 is None else np.array(u0, dtype=float)
    v = np.zeros(n) if v0 is None else np.array(v0, dtype=float)
    return RunState(u=u, v=v, fext=np.zeros(n), y=np.zeros(n), scal=scal, u_peak=np.zeros(n),
                    x=np.zeros(n))


class History(NamedTuple):
    """Per-sample output, preallocated (rows filled up to ``scal[S_NSAMP]``)."""

    t: np.ndarray
    vm: np.ndarray
    node: np.ndarray
    """int64 node of the sample's largest nodal von Mises"""
    p1: np.ndarray
    umax: np.ndarray
    ke: np.ndarray
    se: np.ndarray
    work: np.ndarray
    env: np.ndarray
    """per-node envelope (n_nodes, 2): max over samples of von Mises, max principal [Pa]"""
    nodal: np.ndarray
    """scratch (n_nodes, 4): the last sample's nodal vm_top, vm_bot, p1_top, p1_bot [Pa]"""
    mask: np.ndarray
    """scratch (n_nodes,) int8, zero between samples: 1 inside an active St-Venant zone"""


def new_history(capacity: int, n_nodes: int) -> History:
    z = lambda: np.zeros(capacity)  # noqa: E731
    return History(t=z(), vm=z(), node=np.zeros(capacity, np.int64), p1=z(), umax=z(), ke=z(),
                   se=z(), work=z(), env=np.zeros((n_nodes, 2)), nodal=np.zeros((n_nodes, 4)),
                   mask=np.zeros(n_nodes, np.int8))


@njit(cache=True)
def _bracket(times, t, k):
    """Index k (warm start) and fraction s with times[k] ≤ t ≤ times[k+1]; k = −1 outside."""
    n = len(times)
    if n == 0 or t < times[0] or t > times[n - 1]:
        return -1, 0.0
    if n == 1:
        return 0, 0.0
    if k < 0 or k > n - 2 or times[k] > t:
        k = 0
    while k < n - 2 and times[k + 1] <= t:
        k += 1
    return k, (t - times[k]) / (times[k + 1] - times[k])


@njit(cache=True)
def _scatter_loads(D, t, k, fext, sign):
    """fext += sign × (interpolated contact loads at t) on the loaded DOFs (sparse)."""
    k, s = _bracket(D.times, t, k)
    if k < 0:
        return k
    for col, w in ((k, 1.0 - s), (k + 1, s)):
        if w != 0.0 and col < len(D.times):
            for p in range(D.colptr[col], D.colptr[col + 1]):
                fext[D.rows[p]] += sign * w * D.vals[p]
    return k


@njit(cache=True)
def _frame_accel(D, t, k, out):
    k, s = _bracket(D.acc_times, t, k)
    if k < 0:
        out[:] = 0.0
        return k
    for c in range(3):
        out[c] = (1.0 - s) * D.acc[k, c] + (s * D.acc[k + 1, c] if s != 0.0 else 0.0)
    return k


_FAST = {"contract"}  # no 'nnan'/'ninf': blow-ups must stay visible

U1, U2, U3, U4, U5 = (np.uint64(k) for k in range(1, 6))
"""Unsigned offsets: the hot loops index with unsigned integers, for which numba emits no
negative-index (wrap-around) test; with signed ones the test on every gathered index cost
1.1–1.3× in the step and its stress sample (side by side, equal to the bit: benchmarks/shell_kernel_ab.py,
docs/performance.md, "The shell step with unsigned indices")."""


@njit(cache=True, fastmath=_FAST)
def _fused_step(D, P, St, x, h, acc3, want_se, want_ke):
    """One central-difference step (see module doc) on :class:`SplitUpper` storage, local frame.
    ``x`` is u itself when β = 0, else a copy of u + β v made before the step (rows j > i read
    x_j before node j is updated, so either is the pre-step value).
    Returns (½ u_{n+1}ᵀ K x of the states after and before the step (when ``want_se``; with
    x = u_n, β = 0, the strain energy of the scheme's energy balance), the work of the step
    ½ dt f·(v_{n−½} + v_{n+½}), ½ v_{n+½}ᵀ M v_{n+½} (when ``want_ke``)): see :func:`advance_steps`."""
    K = D.K
    ind, M, B, ptr = K.indices, K.mem, K.bend, K.indptr
    u, v, fe, y = St.u, St.v, St.fext, St.y
    minv, mass_t, mass, wfix = D.minv, D.mass_t, D.mass, D.wfix
    alpha, dt = P.alpha, P.dt
    g0, g1, g2 = acc3[0], acc3[1], acc3[2]
    se = 0.0
    work = 0.0
    ke = 0.0
    for i in range(np.uint64(len(ptr) - 1)):  # unsigned counters: ``U1``
        bi = U5 * i
        xi0, xi1, xi2, xi3, xi4 = x[bi], x[bi + U1], x[bi + U2], x[bi + U3], x[bi + U4]
        p0 = np.uint64(ptr[i])
        y0 = y[bi] + M[p0, 0] * xi0 + M[p0, 1] * xi1
        y1 = y[bi + U1] + M[p0, 2] * xi0 + M[p0, 3] * xi1
        y2 = y[bi + U2] + B[p0, 0] * xi2 + B[p0, 1] * xi3 + B[p0, 2] * xi4
        y3 = y[bi + U3] + B[p0, 3] * xi2 + B[p0, 4] * xi3 + B[p0, 5] * xi4
        y4 = y[bi + U4] + B[p0, 6] * xi2 + B[p0, 7] * xi3 + B[p0, 8] * xi4
        for p in range(np.uint64(ptr[i] + 1), np.uint64(ptr[i + U1])):
            bj = U5 * np.uint64(ind[p])
            x0, x1, x2, x3, x4 = x[bj], x[bj + U1], x[bj + U2], x[bj + U3], x[bj + U4]
            m0, m1, m2, m3 = M[p, 0], M[p, 1], M[p, 2], M[p, 3]
            b0, b1, b2, b3, b4, b5, b6, b7, b8 = (B[p, 0], B[p, 1], B[p, 2], B[p, 3], B[p, 4],
                                                  B[p, 5], B[p, 6], B[p, 7], B[p, 8])
            y0 += m0 * x0 + m1 * x1
            y1 += m2 * x0 + m3 * x1
            y2 += b0 * x2 + b1 * x3 + b2 * x4
            y3 += b3 * x2 + b4 * x3 + b5 * x4
            y4 += b6 * x2 + b7 * x3 + b8 * x4
            y[bj] += m0 * xi0 + m2 * xi1
            y[bj + U1] += m1 * xi0 + m3 * xi1
            y[bj + U2] += b0 * xi2 + b3 * xi3 + b6 * xi4
            y[bj + U3] += b1 * xi2 + b4 * xi3 + b7 * xi4
            y[bj + U4] += b2 * xi2 + b5 * xi3 + b8 * xi4
        # row i complete: y = (K x)_i. Node update (node_update, inlined by hand).
        mt = mass_t[bi]
        f0 = fe[bi] - mt * g0
        f1 = fe[bi + U1] - mt * g1
        f2 = fe[bi + U2] - mt * g2
        f3 = fe[bi + U3]
        f4 = fe[bi + U4]
        a0 = minv[bi] * (f0 - y0) - alpha * v[bi]
        a1 = minv[bi + U1] * (f1 - y1) - alpha * v[bi + U1]
        a2 = minv[bi + U2] * (f2 - y2) - alpha * v[bi + U2]
        a3 = minv[bi + U3] * (f3 - y3) - alpha * v[bi + U3]
        a4 = minv[bi + U4] * (f4 - y4) - alpha * v[bi + U4]
        if wfix[i] != 0.0:  # local frame: w = u[2] exactly
            a2 = 0.0
        work += 0.5 * dt * (f0 * v[bi] + f1 * v[bi + U1] + f2 * v[bi + U2] + f3 * v[bi + U3] + f4 * v[bi + U4])
        v0 = v[bi] + h * a0
        v1 = v[bi + U1] + h * a1
        v2 = v[bi + U2] + h * a2
        v3 = v[bi + U3] + h * a3
        v4 = v[bi + U4] + h * a4
        v[bi], v[bi + U1], v[bi + U2], v[bi + U3], v[bi + U4] = v0, v1, v2, v3, v4
        u[bi] += dt * v0
        u[bi + U1] += dt * v1
        u[bi + U2] += dt * v2
        u[bi + U3] += dt * v3
        u[bi + U4] += dt * v4
        work += 0.5 * dt * (f0 * v0 + f1 * v1 + f2 * v2 + f3 * v3 + f4 * v4)
        if want_se:
            se += 0.5 * (u[bi] * y0 + u[bi + U1] * y1 + u[bi + U2] * y2 + u[bi + U3] * y3
                         + u[bi + U4] * y4)
        if want_ke:  # only at sample steps: saves streaming m on the others
            ke += 0.5 * (mass[bi] * (v0 * v0 + v1 * v1 + v2 * v2)
                         + mass[bi + U3] * v3 * v3 + mass[bi + U4] * v4 * v4)
        y[bi] = 0.0
        y[bi + U1] = 0.0
        y[bi + U2] = 0.0
        y[bi + U3] = 0.0
        y[bi + U4] = 0.0
    return se, work, ke


@njit(cache=True, nogil=True)
def advance(D, P, R, St, H, n_steps):
    """:func:`advance_steps` with denormals flushed to zero (see ``_FTZ_DAZ``). Releases the
    GIL (``nogil``): independent fins advance concurrently in threads (the MXCSR is per thread,
    restored on return)."""
    old = _get_mxcsr()
    _set_mxcsr(old | _FTZ_DAZ)
    status = advance_steps(D, P, R, St, H, n_steps)
    _set_mxcsr(old)
    return status


@njit(cache=True)
def advance_steps(D, P, R, St, H, n_steps):
    """Advance ``n_steps`` central-difference steps from step ``St.scal[S_STEP]``, sampling
    stresses and energies into ``H`` at every multiple of ``P.sample_every`` and tracking the
    peaks and the envelope at every multiple of ``P.peak_every`` too.

    Scheme (Belytschko, Liu & Moran 2000, Box 6.1), velocities at half steps:
        a_n = M⁻¹ [f(t_n) − K (u_n + β v_{n−½})] − α v_{n−½};  v_{n+½} = v_{n−½} + dt a_n
        (first step: v_½ = v_0 + dt/2 a_0);  u_{n+1} = u_n + dt v_{n+½}.
    The first step is the one after ``St.scal[S_STEP0]``; the time of step n is n dt.
    Energy rows (β = 0): kinetic ½ v_{n−½}ᵀ M v_{n−½}, strain ½ u_nᵀ K u_{n−1}, work
    Σ_k ½ dt f_k·(v_{k−½} + v_{k+½}). Multiplying the step by (u_{k+1} − u_{k−1})/2 shows that
    kinetic + strain − work is then constant to round-off for the undamped scheme (a discrete
    energy identity of central differences; with ½ uᵀKu at the step the balance erred by
    O(dt) of the energy of the modes near dt_crit, 3.7 % of the work at 0.9 dt_crit). Two
    departures: the first (half) step books ½ dt f_0·(v_0 + v_½), exact when f_0 = 0 (a load
    window starts before the load); α, β > 0 dissipate energy that no column holds, and with
    β ≠ 0 the strain energy is ½ u_nᵀ K u_n.
    Returns 0, or the step number (> 0) at which the energy check failed (non-finite, or
    kinetic + strain > growth_limit × (E0 + Σ|work|)).
    """
    sc = St.scal
    kL, kA = 0, 0
    acc3 = np.zeros(3)
    fe = St.fext
    for _ in range(n_steps):
        step = int(sc[S_STEP]) + 1
        t = (step - 1) * P.dt
        kA = _frame_accel(D, t, kA, acc3)
        kL = _scatter_loads(D, t, kL, fe, 1.0)
        h = 0.5 * P.dt if step == int(sc[S_STEP0]) + 1 else P.dt
        sample = step % P.sample_every == 0
        if P.beta != 0.0:
            for r in range(len(St.u)):
                St.x[r] = St.u[r] + P.beta * St.v[r]
            se, work, ke = _fused_step(D, P, St, St.x, h, acc3, False, sample)
        else:
            se, work, ke = _fused_step(D, P, St, St.u, h, acc3, sample, sample)
        if kL >= 0:  # restore the scratch to zero on the loaded DOFs only
            for col in (kL, kL + 1):
                if col < len(D.times):
                    for p in range(D.colptr[col], D.colptr[col + 1]):
                        fe[D.rows[p]] = 0.0
        sc[S_WORK_INT] += work
        sc[S_STEP] = step
        if sample:
            row = int(sc[S_NSAMP])
            sc[S_WORK] += abs(sc[S_WORK_INT])
            sc[S_WORK_NET] += sc[S_WORK_INT]
            sc[S_WORK_INT] = 0.0
            H.t[row] = step * P.dt
            H.ke[row] = ke
            H.work[row] = sc[S_WORK_NET]
            _sample(D, R, St, H, row, step, step * P.dt)
            sc[S_NSAMP] = row + 1
            if P.beta != 0.0:
                split_product(D.K, St.u, St.y)
                se = 0.0
                for r in range(len(St.u)):
                    se += 0.5 * St.u[r] * St.y[r]
                    St.y[r] = 0.0
            if _close_sample(H, sc, row, se, P.growth_limit):
                return step
        elif P.peak_every > 0 and step % P.peak_every == 0:
            _track(D, R, St, H, step, step * P.dt)
    return 0


@njit(cache=True)
def _close_sample(H, sc, row, se, limit):
    H.se[row] = se
    total = H.ke[row] + se
    if row == 0:
        sc[S_E0] = total
    return not np.isfinite(total) or total > limit * (sc[S_E0] + sc[S_WORK])


@njit(cache=True)
def _mark_zones(D, t, mask, value):
    """mask[node] = value for the nodes in the St-Venant zones of the loads active at t (the
    two contact samples bracketing t, as :func:`_scatter_loads` interpolates)."""
    k, _ = _bracket(D.times, t, 0)
    if k < 0:
        return
    mark(D.zones, k, k + 2, mask, value)


@njit(cache=True)
def _track(D, R, St, H, step, t):
    """Nodal stresses of the current u (into ``H.nodal``); the envelope (all nodes) and the
    running peaks: the structural peak over the nodes outside the active St-Venant zones, and the
    raw one. Returns (structural max vm, its node, max p1, max |u|) of this instant."""
    sc = St.scal
    vm_raw, _, _, umax = sample_nodes(R, St.u, H.nodal)
    _mark_zones(D, t, H.mask, 1)
    vm_max, node, p1_max = 0.0, -1, -np.inf
    for i in range(H.nodal.shape[0]):
        vm = max(H.nodal[i, 0], H.nodal[i, 1])
        p1 = max(H.nodal[i, 2], H.nodal[i, 3])
        if vm > H.env[i, 0]:
            H.env[i, 0] = vm
        if p1 > H.env[i, 1]:
            H.env[i, 1] = p1
        if H.mask[i] == 0:
            if vm > vm_max:
                vm_max, node = vm, i
            p1_max = max(p1_max, p1)
    _mark_zones(D, t, H.mask, 0)
    sc[S_PEAK_RAW] = max(sc[S_PEAK_RAW], vm_raw)
    if vm_max > sc[S_PEAK_VM]:
        sc[S_PEAK_VM] = vm_max
        sc[S_PEAK_T] = t
        sc[S_PEAK_NODE] = node
        sc[S_PEAK_STEP] = step
        St.u_peak[:] = St.u
    if p1_max > sc[S_PEAK_P1]:
        sc[S_PEAK_P1] = p1_max
        sc[S_PEAK_P1_T] = t
    return vm_max, node, p1_max, umax


@njit(cache=True)
def _sample(D, R, St, H, row, step, t):
    """:func:`_track`, and the history row ``row`` of this instant's maxima."""
    vm_max, node, p1_max, umax = _track(D, R, St, H, step, t)
    H.vm[row] = vm_max
    H.node[row] = node
    H.p1[row] = p1_max
    H.umax[row] = umax
