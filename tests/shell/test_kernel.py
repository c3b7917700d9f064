"""The compiled step kernel against the PETSc step (same scheme, different code and storage)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import sparse

from flexnet_fe.shell import api
from flexnet_fe.shell.explicit import (Backend, LoadHistory, critical_step, max_eigenvalue,
                                       translational_mass)
from flexnet_fe.shell.forms import NDOF_NODE, ShellMaterial, Support
from flexnet_fe.shell.solve import recovery_for, run

from .conftest import A1, A2, ORIGIN

MAT = ShellMaterial(thickness=3e-3, youngs_modulus=70e9, poisson_ratio=0.3, density=2700.0)


def _loads(m):
    """A moving sparse load, a uniform pressure ramp and a body acceleration, all at once."""
    n = m.op.n_owned
    t = np.linspace(0.0, 4e-4, 9)
    P = np.zeros((n, len(t)))
    rng = np.random.default_rng(4)
    for k in range(len(t)):
        nodes = rng.choice(n // NDOF_NODE, 3, replace=False)
        for i in nodes:
            P[NDOF_NODE * i: NDOF_NODE * i + 3, k] = rng.normal(size=3) * 50.0
    P += api.pressure(m, t, 2e3 * t / t[-1]).nodal.toarray()
    acc = np.array([[0.0, 0.0, 0.0], [3e3, -1e3, 2e3], [0.0, 5e2, 0.0]])
    return LoadHistory(times=t, nodal=sparse.csc_matrix(P), accel_times=np.array([0, 2e-4, 4e-4]),
                       accel=acc, mass_c=translational_mass(m.op))


def test_compiled_step_equals_petsc_step_over_1000_steps():
    sup = {"root": Support.CLAMPED, "tip": Support.SIMPLY_SUPPORTED}
    m = api.plate(10, 6, 0.3, 0.15, MAT, supports=sup, origin=ORIGIN, a1=A1, a2=A2)
    loads = _loads(m)
    lam, _ = max_eigenvalue(m.op)
    dt = 0.9 * critical_step(lam, 50.0, 1e-7)
    R = recovery_for(m)
    out = {}
    for be in (Backend.COMPILED, Backend.PETSC):
        out[be] = run(m, loads, R, dt=dt, n_steps=1000, sample_every=10, frame_every=100,
                      alpha=50.0, beta=1e-7, backend=be)
    a, b = out[Backend.COMPILED], out[Backend.PETSC]
    # Reference: the PETSc backend (Mat.mult on the AIJ matrix in frame B, Python update). The
    # compiled kernel steps the block-upper, membrane/bending-split matrix in the fin frame.
    # Against an 80-bit extended-precision solution of each backend's own data
    # (benchmarks/bench_shell.py agreement) both are within 3.5–3.7e-13 after 1 000 steps; the
    # backends differ by 6e-12 because their data differ at round-off level (the frame-B K's
    # 4e-16 membrane–bending coupling, dropped in the fin frame; K's 5e-17 asymmetry), which
    # this problem amplifies ~1e4× in 1 000 steps — the exact solutions of the two data sets
    # are 6.0e-12 apart. Bounds, relative to their maxima: the state and the strain energy
    # 1e-11, the sampled stresses, kinetic energy and work 3e-12 (issue 10 asks 1e-12: not
    # reachable without a bit-identical operator; docs/validation.md).
    assert np.linalg.norm(a.u - b.u) <= 1e-11 * np.linalg.norm(b.u)
    np.testing.assert_allclose(a.se, b.se, rtol=0, atol=1e-11 * np.abs(b.se).max())
    for k in ("vm", "p1", "ke", "work", "umax"):
        x, y = getattr(a, k), getattr(b, k)
        np.testing.assert_allclose(x, y, rtol=0, atol=3e-12 * np.abs(y).max(), err_msg=k)
    scale = np.abs(b.u).max()
    assert a.peak_t == b.peak_t and a.peak_node == b.peak_node
    # w = u·n stays zero on the simply supported tip (a projection in frame B)
    tip = np.isclose((m.op.x_nodes - ORIGIN) @ A1, 0.3)
    w = a.u.reshape(-1, NDOF_NODE)[tip, :3] @ m.fin.plane.n
    assert np.abs(w).max() <= 1e-12 * scale


@pytest.mark.parametrize("shape", ["sine", "pulse"])
def test_history_closes_the_energy_balance_to_round_off_in_both_backends(shape):
    """Reference: the discrete energy identity of central differences. Undamped (α = β = 0),
    multiplying M(v_{n+½} − v_{n−½})/dt = f_n − K u_n by (u_{n+1} − u_{n−1})/2 gives
    E_{n+½} − E_{n−½} = ½ dt f_n·(v_{n−½} + v_{n+½}) exactly, E_{n+½} = ½ v_{n+½}ᵀ M v_{n+½}
    + ½ u_nᵀ K u_{n+1}: the history's kinetic + strain − work must stay at zero to round-off
    (≤ 1e-10 of the work scale; measured ≈ 1e-12), at any dt below the limit and in both
    backends. With ½ uᵀKu at the step and f_n·(u_{n+1} − u_n) (the history before) it erred by
    3.7 % / 1.9 % at 0.9 / 0.45 dt_crit, first order. "sine": a full period, so the plate
    moves against the load in part of the run and some sample intervals do negative work (a
    history of |interval work| would overstate W); "pulse": one 20 µs triangle of pressure,
    which excites the modes near dt_crit, where the old measure erred most."""
    sup = {"root": Support.CLAMPED}
    m = api.plate(10, 6, 0.3, 0.15, MAT, supports=sup, origin=ORIGIN, a1=A1, a2=A2)
    t = np.linspace(0.0, 2e-3, 201)
    p = 5e3 * np.sin(2 * np.pi * t / 1e-3) if shape == "sine" else np.where(np.arange(t.size) == 20, 5e4, 0.0)
    loads = api.pressure(m, t, p)
    lam, _ = max_eigenvalue(m.op)
    R = recovery_for(m)

    def gap(factor, be):
        dt = factor * critical_step(lam, 0.0, 0.0)
        n = int(2e-3 / dt)
        r = run(m, loads, R, dt=dt, n_steps=n, sample_every=10, frame_every=10 * (n // 10 + 1),
                backend=be)
        if shape == "sine":
            assert np.diff(r.work).min() < 0.0, "the test load must do negative work somewhere"
        assert np.abs(r.work).max() > 0.0
        return np.abs(r.ke + r.se - r.work).max() / np.abs(r.work).max()

    for be in (Backend.COMPILED, Backend.PETSC):
        for factor in (0.9, 0.45):
            assert gap(factor, be) < 1e-10, (be, factor)


@pytest.mark.parametrize("backend", [Backend.COMPILED, Backend.PETSC])
def test_peak_tracked_between_history_rows_equals_every_step_sampling(backend):
    """Reference: the same run sampled (history rows) at every step. With rows every 20 steps
    and the peak tracked every step (``peak_every`` = 1), the running peak — value, instant,
    node, state — and the envelope must be those of the every-step history, while the rows
    alone (no tracking) miss the peak of a load pulse shorter than the row interval (the reason
    for ``shell.peak_interval``: a rope load's stress peak is a few µs wide)."""
    sup = {"root": Support.CLAMPED}
    m = api.plate(10, 6, 0.3, 0.15, MAT, supports=sup, origin=ORIGIN, a1=A1, a2=A2)
    lam, _ = max_eigenvalue(m.op)
    dt = 0.9 * critical_step(lam, 0.0, 0.0)
    t = np.array([0.0, 30 * dt, 33 * dt, 36 * dt, 2e-3])  # a 6-step pulse
    loads = api.pressure(m, t, np.array([0.0, 0.0, 2e4, 0.0, 0.0]))
    R = recovery_for(m)
    n = 200
    kw = dict(dt=dt, n_steps=n, frame_every=n, backend=backend)
    every = run(m, loads, R, sample_every=1, **kw)
    tracked = run(m, loads, R, sample_every=20, peak_every=1, **kw)
    rows = run(m, loads, R, sample_every=20, **kw)
    assert tracked.peak_vm == every.peak_vm and tracked.peak_t == every.peak_t
    assert tracked.peak_node == every.peak_node
    np.testing.assert_array_equal(tracked.u_peak, every.u_peak)
    np.testing.assert_array_equal(tracked.env, every.env)
    assert len(tracked.t) == len(rows.t) == n // 20 + 1
    np.testing.assert_array_equal(tracked.vm, rows.vm)  # rows unchanged by the tracking
    assert rows.peak_vm < 0.99 * every.peak_vm


def test_frames_have_distinct_times_when_the_peak_stays_at_step_0():
    """No load: the running peak stays at the t = 0 sample; the compiled path must not write
    that instant as a second 'peak' frame (an XDMF file refuses two frames at one time)."""
    m = api.plate(4, 3, 0.3, 0.15, MAT, supports={"root": Support.CLAMPED})
    lam, _ = max_eigenvalue(m.op)
    dt = 0.9 * critical_step(lam, 0.0, 0.0)
    loads = api.pressure(m, np.array([0.0, 1.0]), np.zeros(2))
    times = []
    run(m, loads, recovery_for(m), dt=dt, n_steps=40, sample_every=4, frame_every=8,
        frame=lambda t, u: times.append(t), backend=Backend.COMPILED)
    assert len(times) == len(set(times)) == 6  # t = 0 and every 8 steps
